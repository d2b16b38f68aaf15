import numpy as np

from trajectories.linsolve import solve_spd


def test_matches_numpy_on_positive_definite_systems():
    rng = np.random.default_rng(0)
    for n in (6, 7):
        A = rng.normal(size=(n, n))
        a = A @ A.T + 1e-9 * np.eye(n)
        b = rng.normal(size=n)
        B = rng.normal(size=(n, 7))
        assert np.allclose(solve_spd(a, b), np.linalg.solve(a, b), rtol=1e-8, atol=1e-10)
        assert np.allclose(solve_spd(a, B), np.linalg.solve(a, B), rtol=1e-8, atol=1e-10)


def test_indefinite_matrix_falls_back_to_a_general_solve():
    a = np.array([[1.0, 2.0], [2.0, 1.0]])  # eigenvalues 3 and −1: Cholesky fails
    b = np.array([1.0, 0.0])
    x = solve_spd(a, b)
    assert np.allclose(a @ x, b)
