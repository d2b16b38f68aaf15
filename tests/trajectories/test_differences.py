import numpy as np

from trajectories.differences import central_difference, derivatives


def test_central_differences_on_analytic_sines():
    h = 1e-3
    w = 2 * np.pi * 1.5
    t = np.arange(0, 2, h)
    x = np.sin(w * t)
    v, a, j = derivatives(x, h, 3)
    inner = slice(5, -5)
    # central differences are second-order accurate: error ~ (w h)^2 / 6 relative per application
    assert np.abs(v[inner] - w * np.cos(w * t[inner])).max() < 1e-4 * w
    assert np.abs(a[inner] + w**2 * np.sin(w * t[inner])).max() < 3e-4 * w**2
    assert np.abs(j[inner] + w**3 * np.cos(w * t[inner])).max() < 5e-4 * w**3


def test_central_difference_is_thesis_eq_5_7():
    h = 0.005
    q = np.array([0.0, 1.0, 4.0, 9.0, 16.0])
    d = central_difference(q, h)
    assert d[2] == (9.0 - 1.0) / (2 * h)
    assert d[0] == (1.0 - 0.0) / h  # one-sided at the ends


def test_columns_are_independent():
    h = 0.01
    t = np.arange(0, 1, h)
    x = np.column_stack([t**2, 3 * t])
    v = central_difference(x, h)
    assert np.allclose(v[1:-1, 0], 2 * t[1:-1])
    assert np.allclose(v[:, 1], 3.0)
