"""The compiled pendulum integration (tracking._rk4) against model_look's pure-Python one: the same values to the
last bit, forwards and backwards in time, and the fallback taken when the extension is not built."""

from __future__ import annotations

import numpy as np
import pytest

from tracking import model_look

compiled = pytest.mark.skipif(model_look._rk4 is None, reason="tracking._rk4 not built (no C compiler at install)")


def _cases(n: int):
    rng = np.random.default_rng(7)
    for _ in range(n):  # large swings, damping of either sign, 30-240 fps either way, numpy scalars as arguments
        p = (rng.uniform(-3.1, 3.1), rng.uniform(-12, 12), rng.uniform(1.0, 400.0), rng.uniform(-0.5, 2.0))
        dt = float(rng.choice([1 / 30, 1 / 60, -1 / 120, 1 / 240, -1 / 30]))
        yield np.float64(p[0]), p[1], p[2], p[3], dt, np.int64(rng.integers(0, 300))


@compiled
def test_compiled_integration_equals_python_to_the_last_bit() -> None:
    for theta, rate, w2, c, dt, steps in _cases(200):
        a = model_look.integrate(theta, rate, w2, c, dt, steps)
        b = model_look.integrate_py(float(theta), rate, w2, c, dt, int(steps))
        assert a.shape == (steps + 1,) and np.array_equal(a, b)
        j = model_look.trajectory(theta, rate, w2, c, dt, steps)
        k = model_look.trajectory_py(float(theta), rate, w2, c, dt, int(steps))
        assert j.shape == (steps + 1, 5) and np.array_equal(j, k)
    out = model_look.integrate(0.3, 0.0, 39.0, 0.1, 1 / 60, 5)
    out[1:] = 0.0  # a writable array, as the pure-Python one (callers fill runs of frames from it)
    assert out[0] == 0.3


@compiled
def test_compiled_integration_refuses_bad_arguments() -> None:
    with pytest.raises(TypeError):
        model_look._rk4.integrate(0.1, 0.0, 39.0, 0.1, 1 / 60)
    with pytest.raises(ValueError):
        model_look._rk4.trajectory(0.1, 0.0, 39.0, 0.1, 1 / 60, -1)
    with pytest.raises(TypeError):
        model_look._rk4.integrate("0.1", 0.0, 39.0, 0.1, 1 / 60, 3)


def test_fallback_without_the_extension(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(model_look, "_rk4", None)
    th = model_look.integrate(1e-3, 0.0, 40.0, 0.0, 1 / 60, 120)  # small swing: θ₀ cos(√w2 t)
    t = np.arange(121) / 60
    assert np.max(np.abs(th - 1e-3 * np.cos(np.sqrt(40.0) * t))) < 5e-8  # RK4 at 60 fps
    j = model_look.trajectory(1e-3, 0.0, 40.0, 0.0, 1 / 60, 120)
    assert j.shape == (121, 5) and np.array_equal(j[:, 0], th)
