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


def band_sweep(
    t: np.ndarray, positions: np.ndarray, lengths: np.ndarray, stop_time: float, end_time: float, substep: float = 0.001
) -> tuple[np.ndarray, np.ndarray]:
    """The same driven spherical pendulum for many string lengths (k,) [m] at once (numpy, RK4 sub-steps ≤ ``substep``
    [s]): the largest tilt after ``stop_time`` (the residual) and over the whole run (the peak), both (k,) [rad].

    For judging a plan across a dense band of lengths — the residual varies between the lengths a few point checks
    see."""
    lengths = np.asarray(lengths, dtype=float)[:, None]
    h = float(t[1] - t[0])
    acc = SampledAcceleration(t, positions).samples()
    n_out = int(math.floor((end_time - float(t[0])) / h + 1e-9)) + 1
    a = np.zeros((n_out + 1, 3))
    m = min(len(acc), n_out)
    a[1 : m + 1] = acc[:m]
    g = np.array([0.0, 0.0, -9.81])
    s = np.tile(HANGING, (len(lengths), 1))
    v = np.zeros_like(s)
    substeps = max(1, int(math.ceil(h / substep - 1e-9)))
    hs = h / substeps

    def rhs(s_, v_, acc_):
        f = (g - acc_)[None, :] / lengths
        lam = np.einsum("ij,ij->i", s_, f) + np.einsum("ij,ij->i", v_, v_)
        return f - lam[:, None] * s_

    residual = np.zeros(len(lengths))
    peak = np.zeros(len(lengths))
    for k in range(n_out):
        a0, a1 = a[k], a[k + 1]
        for j in range(substeps):
            b0 = a0 + (j / substeps) * (a1 - a0)
            b1 = a0 + ((j + 1) / substeps) * (a1 - a0)
            bm = 0.5 * (b0 + b1)
            k1 = rhs(s, v, b0)
            s2, v2 = s + 0.5 * hs * v, v + 0.5 * hs * k1
            k2 = rhs(s2, v2, bm)
            s3, v3 = s + 0.5 * hs * v2, v + 0.5 * hs * k2
            k3 = rhs(s3, v3, bm)
            s4, v4 = s + hs * v3, v + hs * k3
            k4 = rhs(s4, v4, b1)
            s = s + hs / 6.0 * (v + 2 * v2 + 2 * v3 + v4)
            v = v + hs / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
            s /= np.linalg.norm(s, axis=1, keepdims=True)
            v -= np.einsum("ij,ij->i", v, s)[:, None] * s
        tilt = np.arccos(np.clip(-s[:, 2], -1.0, 1.0))
        np.maximum(peak, tilt, out=peak)
        if float(t[0]) + k * h >= stop_time - 1e-12:
            np.maximum(residual, tilt, out=residual)
    return residual, peak


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


__all__ = ["simulate_sampled", "predict", "hat_acceleration", "band_sweep"]
