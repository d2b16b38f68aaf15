"""A swing-up plan of the pivot along one horizontal axis, and the jerk-limited stop every plan ends with.

Both swing-up methods (energy shaping, fast pumping) produce a ``PivotPlan``: the pivot displacement x(t)
from its start [m] sampled every dt along the swing axis (base y), the planned acceleration u = ẍ, and the
ball angle the planner claims for it (planar model, ``planners.cartpole``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from trajectories.errors import PlanningError


@dataclass(frozen=True)
class TaskBounds:
    """Limits of the pivot motion along the swing axis: speed [m/s], acceleration [m/s²], jerk [m/s³]."""

    v_max: float
    a_max: float
    j_max: float

    def scaled(self, factor: float) -> "TaskBounds":
        """Bounds with speed, acceleration and jerk multiplied by ``factor``."""
        return TaskBounds(self.v_max * factor, self.a_max * factor, self.j_max * factor)


@dataclass(frozen=True)
class PivotPlan:
    """Sampled pivot path and the planner's own claim of the ball's swing.

    t (n,) [s] uniform step; x, v, u (n,) pivot displacement [m], velocity [m/s], acceleration [m/s²] along
    the swing axis; theta, theta_dot (n,) claimed ball angle [rad] (toward +x positive) and rate [rad/s];
    tension (n,) claimed tension per ball mass [m/s²]; t_reach [s] first time |θ| ≥ the reach angle (None
    if never); t_rest [s] when the pivot is at rest for good.
    """

    method: str
    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    u: np.ndarray
    theta: np.ndarray
    theta_dot: np.ndarray
    tension: np.ndarray
    theta_d: float  # [rad] requested apex
    reach_angle: float  # [rad] |θ| at which θ_d counts as reached (θ_d − tolerance)
    t_reach: float | None
    t_rest: float
    info: dict = field(default_factory=dict, hash=False, compare=False)

    @property
    def dt(self) -> float:
        return float(self.t[1] - self.t[0])

    @property
    def max_theta(self) -> float:
        """Largest claimed |θ| [rad]."""
        return float(np.max(np.abs(self.theta)))

    @property
    def reached(self) -> bool:
        return self.t_reach is not None


class StopProfile:
    """Time-optimal jerk-limited stop of the pivot from (v0, a0) to rest (ruckig, velocity interface).

    ``at(tau)`` returns (displacement from the start of the stop [m], velocity [m/s], acceleration [m/s²])
    at times tau [s] after the stop began; after ``duration`` the pivot rests.
    """

    def __init__(self, v0: float, a0: float, bounds: TaskBounds) -> None:
        from ruckig import ControlInterface, InputParameter, Result, Ruckig, Trajectory

        inp = InputParameter(1)
        inp.control_interface = ControlInterface.Velocity
        inp.current_position = [0.0]
        inp.current_velocity = [float(v0)]
        inp.current_acceleration = [float(np.clip(a0, -bounds.a_max, bounds.a_max))]
        inp.target_velocity = [0.0]
        inp.target_acceleration = [0.0]
        inp.max_velocity = [max(bounds.v_max, abs(v0))]
        inp.max_acceleration = [bounds.a_max]
        inp.max_jerk = [bounds.j_max]
        self._traj = Trajectory(1)
        result = Ruckig(1).calculate(inp, self._traj)
        if result not in (Result.Working, Result.Finished):
            raise PlanningError(f"ruckig could not stop the pivot from v = {v0:.3g} m/s, a = {a0:.3g} m/s²: {result}")
        self.duration = float(self._traj.duration)  # [s]
        self.distance = float(self._traj.at_time(self.duration)[0][0])  # [m]

    def at(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        tau = np.atleast_1d(np.asarray(tau, dtype=float))
        out = np.empty((3, tau.size))
        for k, s in enumerate(tau):
            p, v, a = self._traj.at_time(min(max(float(s), 0.0), self.duration))
            out[:, k] = (p[0], v[0], a[0])
        rest = tau > self.duration
        out[1, rest] = 0.0
        out[2, rest] = 0.0
        return out[0], out[1], out[2]


def time_grid(duration: float, dt: float) -> np.ndarray:
    """Uniform times 0, dt, ... covering ``duration`` [s] (the last sample at or after it)."""
    n = int(math.ceil(duration / dt - 1e-9)) + 1
    return np.arange(n) * dt


def first_reach(t: np.ndarray, theta: np.ndarray, angle: float) -> float | None:
    """First time [s] the sampled |θ| reaches ``angle`` [rad] (linear interpolation), None if never."""
    a = np.abs(theta)
    idx = np.flatnonzero(a >= angle)
    if not idx.size:
        return None
    k = int(idx[0])
    if k == 0:
        return float(t[0])
    w = (angle - a[k - 1]) / (a[k] - a[k - 1])
    return float(t[k - 1] + w * (t[k] - t[k - 1]))


def reach_side(plan: PivotPlan) -> int:
    """+1 if θ_d is first reached toward +x (positive θ), −1 toward −x, 0 if never reached."""
    if plan.t_reach is None:
        return 0
    k = int(np.searchsorted(plan.t, plan.t_reach))
    return 1 if plan.theta[min(k, len(plan.t) - 1)] > 0 else -1


def mirrored(plan: PivotPlan) -> PivotPlan:
    """The same swing-up mirrored about the start (x → −x, θ → −θ): the ball reaches θ_d on the other side."""
    from dataclasses import replace

    return replace(plan, x=-plan.x, v=-plan.v, u=-plan.u, theta=-plan.theta, theta_dot=-plan.theta_dot)
