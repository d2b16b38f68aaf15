"""Command sources for an FRI session: the rows streamed in COMMANDING_ACTIVE, one per answered cycle.

A :class:`Plan` is computed before the first command (when the first monitoring message tells where the robot
stands and at which period the controller runs): an optional jerk-limited move to the start (ruckig), the file's
rows, and the last row held for the settle time. Everything is sampled at the controller's command period.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trajectories.errors import CheckFailed, PlanningError
from trajectories.limits import JointLimits
from trajectories.trajectory import JointTrajectory

from .log import PHASE_MOVE, PHASE_SETTLE, PHASE_TRAJECTORY

MOVE_SCALE = 0.2  # moves to the start run at ≤ 20 % of the velocity, acceleration and jerk limits


@dataclass(frozen=True)
class Plan:
    """Joint positions [rad] to command, one per answered COMMANDING_ACTIVE cycle, in order.

    rows (n, 7) = n_move rows of the move to the start, n_traj rows of the trajectory, n_settle copies of the last.
    """

    rows: np.ndarray
    n_move: int
    n_traj: int
    n_settle: int
    period_s: float  # [s] between two commands

    def __post_init__(self) -> None:
        if self.rows.shape != (self.n_move + self.n_traj + self.n_settle, 7):
            raise ValueError("plan rows do not match the phase counts")

    def __len__(self) -> int:
        return int(self.rows.shape[0])

    def phase(self, i: int) -> tuple[int, int]:
        """(phase code, index of the trajectory row or −1) of row ``i``."""
        if i < self.n_move:
            return PHASE_MOVE, -1
        if i < self.n_move + self.n_traj:
            return PHASE_TRAJECTORY, i - self.n_move
        return PHASE_SETTLE, -1


def jerk_limited_move(
    q_from: np.ndarray,
    q_to: np.ndarray,
    limits: JointLimits,
    period_s: float,
    scale: float = MOVE_SCALE,
    minimum_duration: float | None = None,
) -> np.ndarray:
    """Positions (n, 7) [rad] of a rest-to-rest ruckig move sampled every ``period_s``, from one period after the
    start to the target (last row = ``q_to`` exactly); limits scaled by ``scale``; ``minimum_duration`` [s]."""
    from ruckig import InputParameter, OutputParameter, Result, Ruckig

    otg = Ruckig(7, period_s)
    inp = InputParameter(7)
    out = OutputParameter(7)
    lim = limits.scaled(scale)
    inp.current_position = [float(v) for v in q_from]
    inp.current_velocity = [0.0] * 7
    inp.current_acceleration = [0.0] * 7
    inp.target_position = [float(v) for v in q_to]
    inp.target_velocity = [0.0] * 7
    inp.target_acceleration = [0.0] * 7
    inp.max_velocity = lim.velocity.tolist()
    inp.max_acceleration = lim.acceleration.tolist()
    inp.max_jerk = lim.jerk.tolist()
    if minimum_duration is not None:
        inp.minimum_duration = float(minimum_duration)
    rows: list[list[float]] = []
    while True:
        res = otg.update(inp, out)
        if res not in (Result.Working, Result.Finished):
            raise PlanningError(f"ruckig could not plan the move ({res.name})")
        rows.append(list(out.new_position))
        out.pass_to_input(inp)
        if res == Result.Finished:
            break
    q = np.array(rows)
    q[-1] = np.asarray(q_to, dtype=float)
    return q


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


def start_distance(q_first: np.ndarray, q_measured: np.ndarray) -> tuple[float, int]:
    """Largest |q_first − q_measured| [rad] and its joint index."""
    d = np.abs(np.asarray(q_first) - np.asarray(q_measured))
    j = int(np.argmax(d))
    return float(d[j]), j


def build_plan(
    q_traj: np.ndarray,
    q_measured: np.ndarray,
    period_s: float,
    limits: JointLimits,
    *,
    start_tolerance: float,
    move_to_start: bool,
    settle_s: float,
) -> Plan:
    """Plan for streaming ``q_traj`` (n, 7) [rad] at ``period_s`` from a robot standing at ``q_measured``.

    Raises CheckFailed when the first row is farther than ``start_tolerance`` [rad] from the measured position and
    no move to the start was asked for.
    """
    q_traj = np.asarray(q_traj, dtype=float)
    dist, j = start_distance(q_traj[0], q_measured)
    move = np.empty((0, 7))
    if dist > start_tolerance:
        if not move_to_start:
            raise CheckFailed(
                f"the first row is {dist:.6f} rad from the measured position on A{j + 1} "
                f"(measured {q_measured[j]:.6f}, file {q_traj[0, j]:.6f}), more than --start-tolerance "
                f"{start_tolerance:g} rad; move the robot there first or use --move-to-start"
            )
        move = jerk_limited_move(q_measured, q_traj[0], limits, period_s)
    n_settle = max(0, int(round(settle_s / period_s)))
    rows = np.vstack([move, q_traj, np.repeat(q_traj[-1:], n_settle, axis=0)])
    return Plan(rows=rows, n_move=len(move), n_traj=len(q_traj), n_settle=n_settle, period_s=period_s)
