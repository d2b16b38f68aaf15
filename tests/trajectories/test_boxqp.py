import pytest
import numpy as np
from scipy.optimize import lsq_linear

from trajectories.boxqp import solve_box_qp


@pytest.mark.heavy
def test_matches_scipy_bounded_least_squares():
    rng = np.random.default_rng(3)
    for _ in range(200):
        A = rng.normal(size=(6, 7))
        b = rng.normal(size=6) * rng.uniform(0.1, 5)
        lo, hi = -rng.uniform(0, 1, 7), rng.uniform(0, 1, 7)
        lam = 1e-3
        sol = solve_box_qp(A.T @ A + lam**2 * np.eye(7), A.T @ b, lo, hi)
        ref = lsq_linear(
            np.vstack([A, lam * np.eye(7)]), np.r_[b, np.zeros(7)], bounds=(lo, hi), method="bvls", tol=1e-14
        )
        assert np.abs(sol.x - ref.x).max() < 1e-9
        assert np.all(sol.x >= lo - 1e-15) and np.all(sol.x <= hi + 1e-15)
        assert np.array_equal(sol.active == -1, np.isclose(sol.x, lo, atol=0, rtol=0) & (sol.active != 0))


def test_unconstrained_minimum_inside_the_box_is_returned():
    H = np.diag([1.0, 2.0, 3.0])
    g = np.array([0.1, 0.2, -0.3])
    sol = solve_box_qp(H, g, -np.ones(3), np.ones(3))
    assert np.allclose(sol.x, [0.1, 0.1, -0.1]) and not sol.active.any()


def test_degenerate_box_fixes_the_variable():
    H = np.eye(2)
    sol = solve_box_qp(H, np.array([5.0, 5.0]), np.array([0.2, -1.0]), np.array([0.2, 1.0]))
    assert np.allclose(sol.x, [0.2, 1.0]) and sol.active[1] == 1
