"""Time-optimal re-timing of an ordinary joint path within velocity and acceleration limits (toppra).

Never for anti-sway or swing-up plans: their timing is what makes them work.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from .errors import PlanningError
from .limits import JointLimits
from .trajectory import JointTrajectory

MAX_SAMPLES = 2_000_000  # longest re-timed output (≈ 33 min at 1 ms): ≈ 110 MB of samples


@dataclass(frozen=True)
class RetimeResult:
    trajectory: JointTrajectory
    duration_in: float  # [s]
    duration_out: float  # [s]
    scale: float = 1.0  # fraction of the velocity and acceleration limits given to toppra
    attempts: int = 1


def _path_parameter(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cumulative joint-space distance as the path parameter, dropping repeated samples (stops)."""
    step = np.linalg.norm(np.diff(q, axis=0), axis=1)
    keep = np.concatenate([[True], step > 1e-12])
    q = q[keep]
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(q, axis=0), axis=1))])
    return s, q


def retime(traj: JointTrajectory, limits: JointLimits, dt: float, *, scale: float = 0.98) -> RetimeResult:
    """Fastest timing of the joint path of ``traj`` within ``scale`` × the velocity and acceleration limits.

    Uses toppra with the constant-acceleration parametrizer (no overshoot of the acceleration limits) and
    resamples at ``dt`` [s]. The small default headroom absorbs the finite-difference check's sampling.
    """
    import toppra
    import toppra.algorithm as algo
    import toppra.constraint as constraint

    logging.getLogger("toppra").setLevel(logging.ERROR)
    s, q = _path_parameter(traj.q)
    if len(s) < 2:
        raise PlanningError("the path does not move: nothing to re-time")
    # Hermite-like fit through the samples; 'clamped' keeps zero path velocity at both ends.
    path = toppra.SplineInterpolator(s, q, bc_type="clamped")
    vlim = np.column_stack([-limits.velocity, limits.velocity]) * scale
    alim = np.column_stack([-limits.acceleration, limits.acceleration]) * scale
    gridpoints = np.linspace(0.0, s[-1], min(max(200, len(s)), 2000))
    instance = algo.TOPPRA(
        [constraint.JointVelocityConstraint(vlim), constraint.JointAccelerationConstraint(alim)],
        path,
        gridpoints=gridpoints,
        parametrizer="ParametrizeConstAccel",
    )
    result = instance.compute_trajectory(0.0, 0.0)
    if result is None:
        raise PlanningError("toppra found no feasible timing for this path within the limits")
    duration = float(result.duration)
    if not np.isfinite(duration) or duration / dt > MAX_SAMPLES:
        raise PlanningError(
            f"the fastest timing within the limits lasts {duration:.4g} s: more than {MAX_SAMPLES:,} samples at "
            f"{dt:g} s (are the velocity or acceleration limits, or 1 − margin, tiny?)"
        )
    n = int(np.ceil(duration / dt - 1e-9)) + 1
    t = np.arange(n) * dt
    qs = result(np.minimum(t, duration))
    qs[-1] = q[-1]
    return RetimeResult(JointTrajectory(t=t, q=np.asarray(qs)), traj.duration, float(t[-1]), scale)


def sampled_ratios(traj: JointTrajectory, limits: JointLimits) -> dict[str, float]:
    """Peak / limit of the sampled trajectory: position, and velocity and acceleration by central (the thesis check)
    and forward differences (what the controller executes step by step), whichever is larger."""
    from .check import check_trajectory

    r = check_trajectory(traj, limits).ratios()  # central and step (forward) differences in one pass
    return {
        "position": float(r["position"].max()),
        "velocity": max(float(r["velocity"].max()), float(r["step velocity"].max())),
        "acceleration": max(float(r["acceleration"].max()), float(r["step acceleration"].max())),
        "jerk": float(r["jerk"].max()),
    }


def retime_within(
    traj: JointTrajectory, limits: JointLimits, dt: float, *, scale: float = 0.98, attempts: int = 5
) -> tuple[RetimeResult, dict[str, float]]:
    """:func:`retime`, then verify the samples; while a velocity or acceleration ratio exceeds 1 (toppra bounds the
    continuous spline, the samples of a sharp path can overshoot by a few %), retime again with the scale lowered
    by the excess. Returns the result and its :func:`sampled_ratios`; raises CheckFailed when the samples stay
    outside the limits (or the path itself leaves the position limits). Jerk is reported, not bounded."""
    from .errors import CheckFailed

    if np.any(np.abs(traj.q) > limits.position):
        k, j = np.argwhere(np.abs(traj.q) > limits.position)[0]
        raise CheckFailed(
            f"the path leaves the position limit of A{j + 1} at row {k + 2} ({traj.q[k, j]:.4f} rad, limit "
            f"±{limits.position[j]:.4f} rad): no timing can fix that"
        )
    for attempt in range(1, attempts + 1):
        result = retime(traj, limits, dt, scale=scale)
        ratios = sampled_ratios(result.trajectory, limits)
        worst = max(ratios["velocity"], ratios["acceleration"])
        if worst <= 1.0 and ratios["position"] <= 1.0:
            return RetimeResult(result.trajectory, result.duration_in, result.duration_out, scale, attempt), ratios
        scale *= 0.99 / worst
    raise CheckFailed(
        f"the re-timed samples stay outside the limits after {attempts} attempts (velocity "
        f"{100 * ratios['velocity']:.0f} %, acceleration {100 * ratios['acceleration']:.0f} % of the limits)"
    )
