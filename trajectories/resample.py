"""Resampling a joint trajectory at another step (e.g. the controller's FRI period), and picking samples at a
spacing."""

from __future__ import annotations

import numpy as np

from .trajectory import JointTrajectory


def resample(traj: JointTrajectory, period_s: float) -> JointTrajectory:
    """The trajectory resampled at ``period_s`` [s] by a cubic spline through its samples (ends at its last row)."""
    from scipy.interpolate import CubicSpline

    if len(traj) < 2:
        return JointTrajectory.from_samples(traj.q, period_s)
    n = int(np.ceil(traj.duration / period_s - 1e-9)) + 1
    t = np.minimum(np.arange(n) * period_s, traj.duration)
    q = CubicSpline(traj.t, traj.q, axis=0)(t)
    q[-1] = traj.q[-1]
    return JointTrajectory.from_samples(q, period_s)


def spaced_indices(times: np.ndarray, spacing: float) -> np.ndarray:
    """Indices of samples about ``spacing`` [s] apart (a stride of the median step), first and last included."""
    n = len(times)
    dt = float(np.median(np.diff(times))) if n > 1 else spacing
    stride = max(1, int(round(spacing / dt))) if dt > 0 else 1
    idx = np.arange(0, n, stride)
    if idx[-1] != n - 1:
        idx = np.append(idx, n - 1)
    return idx
