"""State-feedback gains (continuous LQR, scipy) for a pendulum on a jerk-driven cart.

State z = (x, v, a, θ, θ̇): cart position [m], velocity [m/s], acceleration [m/s²], the pendulum's angle from the
equilibrium [rad] and its rate [rad/s]; input the cart jerk [m/s³]. Linearised about hanging (θ̈ = −(g·θ + a)/l) or
upright (θ̈ = (g·θ + a)/l), l the equivalent length [m]. The law is jerk = −K·z.
"""

from __future__ import annotations

import numpy as np

from ..pendulum import G


def cart_pendulum(length: float, upright: bool) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) of the linearised pendulum on a jerk-driven cart with equivalent ``length`` [m]."""
    s = 1.0 if upright else -1.0
    A = np.zeros((5, 5))
    A[0, 1] = A[1, 2] = A[3, 4] = 1.0
    A[4, 2] = s / length
    A[4, 3] = s * G / length
    B = np.array([[0.0], [0.0], [1.0], [0.0], [0.0]])
    return A, B


def lqr_gain(length: float, upright: bool, weights: tuple[float, float, float, float, float],
             jerk_weight: float) -> np.ndarray:  # fmt: skip
    """K (5,) minimising ∫ zᵀ·diag(weights)·z + jerk_weight·jerk² dt."""
    from scipy.linalg import solve_continuous_are

    A, B = cart_pendulum(length, upright)
    Q = np.diag(weights)
    R = np.array([[jerk_weight]])
    P = solve_continuous_are(A, B, Q, R)
    return (np.linalg.solve(R, B.T @ P)).ravel()
