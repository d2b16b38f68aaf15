"""An independent check of predicted sway, written apart from ``sway_prediction`` (for tests and benchmarks).

The pivot path is the clamped C² cubic spline through the sampled pivot positions (e.g. FK of a joint CSV), held
at rest after the last sample; the spherical pendulum s̈ = (I − s sᵀ)(g − p̈)/l − |ṡ|²·s hanging at rest at t = 0
is integrated by scipy's DOP853 (rtol 1e-10, atol 1e-12, max step = the sample step).
"""

from __future__ import annotations

import math

import numpy as np

GRAVITY = np.array([0.0, 0.0, -9.81])  # [m/s²]


def judge_sway(pos: np.ndarray, dt: float, length: float, stop_time: float, settle_periods: float = 3.0):
    """(largest tilt after ``stop_time``, largest tilt overall) [deg] for pivot samples pos (n, 3) [m] every dt [s]."""
    from scipy.integrate import solve_ivp
    from scipy.interpolate import CubicSpline

    t = np.arange(len(pos)) * dt
    acc = CubicSpline(t, pos, bc_type="clamped").derivative(2)

    def f(tt: float, y: np.ndarray) -> np.ndarray:
        s, v = y[:3], y[3:]
        a = acc(tt) if tt <= t[-1] else np.zeros(3)
        force = (GRAVITY - a) / length
        return np.concatenate([v, force - (s @ force) * s - (v @ v) * s])

    end = max(t[-1], stop_time) + settle_periods * 2 * math.pi * math.sqrt(length / 9.81)
    sol = solve_ivp(
        f, (0.0, end), [0, 0, -1, 0, 0, 0], method="DOP853", rtol=1e-10, atol=1e-12, max_step=dt, dense_output=True
    )
    tt = np.arange(0.0, end, dt / 2)
    s = sol.sol(tt)[:3]
    theta = np.degrees(np.arccos(np.clip(-s[2] / np.linalg.norm(s, axis=0), -1.0, 1.0)))
    return float(theta[tt >= stop_time].max()), float(theta.max())


__all__ = ["judge_sway"]
