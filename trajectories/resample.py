"""Resampling a joint trajectory at another step (e.g. the controller's FRI period)."""

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
