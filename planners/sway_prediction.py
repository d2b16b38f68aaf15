"""Predicted swing of the ball under a sampled pivot path: piecewise integration of the sampled acceleration.

A position-controlled robot realises the pivot acceleration of a path sampled every h as the second differences
of the samples (the path held at rest before the first and after the last sample). Here that acceleration is
the sum of hat functions acc_k·Λ((t − t_k)/h) — linear between samples, ramping in over the interval before the
first sample and out after the last one — so its integral is exactly the net velocity change of the samples
(zero: the pivot ends at rest). Within each interval the input is a known linear function of time, so the driven
spherical pendulum is integrated interval by interval with classical RK4 sub-steps that sample the input exactly
at their nodes: no adaptive step can step over an input feature. Error below 10⁻⁵ ° for the anti-sway plans.
"""

from __future__ import annotations

import math

import numpy as np

from .pendulum import HANGING, PendulumRun, SampledAcceleration, natural_period, rk4_step_floats, tension_per_mass


def simulate_sampled(
    t: np.ndarray, positions: np.ndarray, length: float, end_time: float, substep: float = 0.001
) -> PendulumRun:
    """Spherical pendulum hanging at rest at t[0], driven by the pivot samples (n, 3) [m] every h [s] until
    ``end_time`` [s] (the pivot rests after the last sample), RK4 sub-steps ≤ ``substep`` [s]; reported at the
    sample step."""
    h = float(t[1] - t[0])
    acc = SampledAcceleration(t, positions).samples()
    n_out = int(math.floor((end_time - float(t[0])) / h + 1e-9)) + 1
    a = np.zeros((n_out + 1, 3))  # a[j] at t_{j−1}: a[0] = 0 one step before the first sample
    m = min(len(acc), n_out)
    a[1 : m + 1] = acc[:m]
    a_list = a.tolist()
    s, v = tuple(HANGING.tolist()), (0.0, 0.0, 0.0)
    S = np.empty((n_out, 3))
    Vd = np.empty((n_out, 3))
    substeps = max(1, int(math.ceil(h / substep - 1e-9)))
    hs = h / substeps
    for k in range(n_out):
        a0, a1 = a_list[k], a_list[k + 1]
        for j in range(substeps):
            w0, w1 = j / substeps, (j + 1) / substeps
            b0 = (a0[0] + w0 * (a1[0] - a0[0]), a0[1] + w0 * (a1[1] - a0[1]), a0[2] + w0 * (a1[2] - a0[2]))
            b1 = (a0[0] + w1 * (a1[0] - a0[0]), a0[1] + w1 * (a1[1] - a0[1]), a0[2] + w1 * (a1[2] - a0[2]))
            s, v = rk4_step_floats(s, v, b0, b1, hs, length)
        S[k], Vd[k] = s, v
    times = float(t[0]) + np.arange(n_out) * h
    return PendulumRun(t=times, s=S, sdot=Vd, tension=tension_per_mass(S, Vd, a[1:], length), length=length)


def hat_acceleration(t: np.ndarray, positions: np.ndarray):
    """The same input as a function of time [s] → (3,) [m/s²] (for adaptive integrators and tests)."""
    h = float(t[1] - t[0])
    acc = SampledAcceleration(t, positions).samples()
    te = np.concatenate([[t[0] - h], t, [t[-1] + h]])
    ae = np.vstack([np.zeros(3), acc, np.zeros(3)])

    def fn(x: float) -> np.ndarray:
        return np.array([np.interp(x, te, ae[:, i], left=0.0, right=0.0) for i in range(3)])

    return fn


def predict(
    t: np.ndarray, positions: np.ndarray, length: float, stop_time: float, settle_periods: float = 3.0
) -> PendulumRun:
    """``simulate_sampled`` until ``settle_periods`` small-angle periods past ``stop_time`` [s]."""
    end = max(float(t[-1]), stop_time + settle_periods * natural_period(length))
    return simulate_sampled(t, positions, length, end)


__all__ = ["simulate_sampled", "predict", "hat_acceleration"]
