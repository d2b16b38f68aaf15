"""Clients that move the robot along joint positions: the CSV player and the point-to-point move.

:class:`TrajectoryPlayer` streams rows [rad] at the command period, one per sent command: first a jerk-limited
move (ruckig, online, ≤ ``move_scale`` of the limits) from where the controller holds the robot to the first row —
always, so that the stream never starts with a jump; farther than ``start_tolerance`` only with
``move_to_start`` — then the rows, then the last row for ``settle_cycles``. Rows follow the controller's clock:
after lost messages (it bridged those periods by extrapolation) a short jerk-limited segment rejoins the rows in
step (``rejoin``). It checks the start at the first message (before anything is sent) and again at activation, and ends with :class:`StopSession` (the application
then brakes to rest and ends).
"""

from __future__ import annotations

import math
from typing import Callable, Sequence

import numpy as np
from ruckig import InputParameter, OutputParameter, Result, Ruckig, Trajectory

from trajectories.limits import JointLimits

from .client import LBRClient
from .constants import Phase
from .errors import StopSession
from .state import LBRState

PHASE_NONE, PHASE_MOVE, PHASE_TRAJECTORY, PHASE_SETTLE = Phase.NONE, Phase.MOVE, Phase.TRAJECTORY, Phase.SETTLE


class OnlineMove:
    """A rest-to-rest ruckig move computed one cycle at a time (position interface)."""

    def __init__(self, limits: JointLimits, period_s: float, scale: float, minimum_duration: float | None = None) -> None:
        self._otg = Ruckig(7, period_s)
        self._inp = InputParameter(7)
        self._out = OutputParameter(7)
        lim = limits.scaled(scale)
        self._inp.max_velocity = lim.velocity.tolist()
        self._inp.max_acceleration = lim.acceleration.tolist()
        self._inp.max_jerk = lim.jerk.tolist()
        if minimum_duration is not None:
            self._inp.minimum_duration = float(minimum_duration)
        self.target: tuple[float, ...] = ()
        self.done = True
        self.duration_s = 0.0

    def start(self, q_from: Sequence[float], q_to: Sequence[float], v_from: Sequence[float] | None = None) -> float:
        """Plan from ``q_from`` [rad] (at rest, or moving at ``v_from`` [rad/s]) to rest at ``q_to``; the duration
        [s]."""
        inp = self._inp
        inp.current_position = list(q_from)
        inp.current_velocity = list(v_from) if v_from is not None else [0.0] * 7
        inp.current_acceleration = [0.0] * 7
        inp.target_position = list(q_to)
        inp.target_velocity = [0.0] * 7
        inp.target_acceleration = [0.0] * 7
        traj = Trajectory(7)
        res = self._otg.calculate(inp, traj)
        if res not in (Result.Working, Result.Finished):
            raise StopSession(f"ruckig could not plan the move ({res.name})", completed=False)
        self.target = tuple(q_to)
        self.duration_s = traj.duration
        self.done = False
        return traj.duration

    def next(self) -> tuple[float, ...]:
        if self.done:
            return self.target
        res = self._otg.update(self._inp, self._out)
        if res == Result.Finished:
            self.done = True
            return self.target
        if res != Result.Working:
            raise StopSession(f"ruckig failed during the move ({res.name})", completed=False)
        self._out.pass_to_input(self._inp)
        return tuple(self._out.new_position)


def rejoin(limits: JointLimits, period_s: float, q: Sequence[float], v: Sequence[float], rows: Sequence[Sequence[float]],
           first: int, max_tries: int = 20) -> tuple[list[tuple[float, ...]], int]:
    """The commands that bring the robot from ``q`` [rad] moving at ``v`` [rad/s] (where the controller's
    extrapolation left it) back onto ``rows`` in step: jerk-limited (ruckig, at the limits), ``m`` commands for rows
    ``first`` … ``first + m − 1``, the last one exactly that row (with its velocity and acceleration). Returns (the
    commands, the next row). Towards the end of the rows: to the last row at rest, taking the time it needs."""
    otg = Ruckig(7, period_s)
    inp = InputParameter(7)
    inp.max_velocity = limits.velocity.tolist()
    inp.max_acceleration = limits.acceleration.tolist()
    inp.max_jerk = limits.jerk.tolist()
    inp.current_position = list(q)
    inp.current_velocity = list(v)
    inp.current_acceleration = [0.0] * 7  # the controller extrapolates at constant velocity
    n = len(rows)
    dt = period_s
    m = 8
    for _ in range(max_tries):
        r = first + m - 1
        traj = Trajectory(7)
        if r + 1 >= n:  # the end of the rows is near: stop on the last row
            inp.target_position = list(rows[-1])
            inp.target_velocity = [0.0] * 7
            inp.target_acceleration = [0.0] * 7
            inp.minimum_duration = None
            if otg.calculate(inp, traj) not in (Result.Working, Result.Finished):
                break
            k = max(1, int(math.ceil(traj.duration / dt - 1e-9)))
            out = [tuple(traj.at_time(min(i * dt, traj.duration))[0]) for i in range(1, k)]
            return out + [tuple(rows[-1])], n
        a, b, c = rows[r - 1], rows[r], rows[r + 1]
        inp.target_position = list(b)
        inp.target_velocity = [(z - x) / (2.0 * dt) for x, z in zip(a, c)]
        inp.target_acceleration = [(x - 2.0 * y + z) / (dt * dt) for x, y, z in zip(a, b, c)]
        inp.minimum_duration = m * dt
        res = otg.calculate(inp, traj)
        if res in (Result.Working, Result.Finished) and traj.duration <= m * dt * (1 + 1e-12):
            return [tuple(traj.at_time(i * dt)[0]) for i in range(1, m)] + [tuple(b)], r + 1
        m = int(math.ceil(m * 1.25))  # (the time-optimal rejoin is not monotonic in m: no jump to its duration)
    raise StopSession(f"messages were lost at row {first}: the rows cannot be rejoined within the limits", completed=False)


class TrajectoryPlayer(LBRClient):
    """Streams ``rows`` (n, 7) [rad], one per sent command, at the controller's command period."""

    def __init__(
        self,
        rows: np.ndarray,
        limits: JointLimits,
        *,
        period_s: float | None = None,
        start_tolerance: float = 1e-3,
        move_to_start: bool = False,
        move_scale: float = 0.2,
        settle_cycles: int = 0,
        settle_s: float | None = None,
        move_minimum_duration: float | None = None,
        finish_text: str = "trajectory streamed and settled",
        resample: Callable[[float], np.ndarray] | None = None,
    ) -> None:
        rows = np.asarray(rows, dtype=float)
        if rows.ndim != 2 or rows.shape[1] != 7 or len(rows) == 0:
            raise ValueError("rows must be (n, 7) joint positions")
        self.rows = [tuple(r) for r in rows.tolist()]
        self.limits = limits
        self.period_s = period_s
        self.start_tolerance = start_tolerance
        self.move_to_start = move_to_start
        self.move_scale = move_scale
        self.settle_cycles = settle_cycles
        self.settle_s = settle_s  # [s] if given, the hold at the end in time (cycles from the period at activation)
        self.move_minimum_duration = move_minimum_duration
        self.finish_text = finish_text
        self.resample = resample  # (command period [s]) -> rows at that period, for a controller at another one
        self._move: OnlineMove | None = None
        self._checked = False
        self._i = 0  # next row
        self._settled = 0
        self._last: tuple[float, ...] | None = None
        self._last2: tuple[float, ...] | None = None  # the command before _last
        self._queue: list[tuple[float, ...]] = []  # commands of a rejoin after lost messages
        self._period = 0.0  # [s] command period (known at activation)
        # figures
        self.move_rows = self.trajectory_rows = self.settle_rows = 0
        self.skipped_rows = 0  # commands the controller bridged by extrapolation (its messages were lost)
        self.start_distance = 0.0  # [rad] largest |first row − measured| at the first message
        self.operation_mode: str | None = None  # T1, T2 or AUT as reported at the first message

    # -- checks ----------------------------------------------------------------------------------------------
    def _distance(self, q: Sequence[float]) -> tuple[float, int]:
        first = self.rows[0]
        d = [abs(a - b) for a, b in zip(first, q)]
        j = max(range(7), key=d.__getitem__)
        return d[j], j

    def _check_period(self, state: LBRState) -> None:
        """The rows are sampled at ``period_s``: refuse a controller that runs at another command period."""
        self.operation_mode = state.operation_mode.name
        if self.period_s is None:
            return
        got = state.sample_time * state.receive_multiplier
        if abs(got - self.period_s) > 1e-9 and self.resample is not None:
            rows = np.asarray(self.resample(got), dtype=float)  # may raise StopSession (e.g. the check fails)
            self.rows = [tuple(r) for r in rows.tolist()]
            self.period_s = got
            return
        if abs(got - self.period_s) > 1e-9:
            raise StopSession(
                f"the controller's command period is {got * 1e3:g} ms (send period {state.sample_time * 1e3:g} ms × "
                f"receive multiplier {state.receive_multiplier}), the rows' step is {self.period_s * 1e3:g} ms; "
                "re-plan at that step or use --resample",
                completed=False,
                bad_input=True,
            )

    def _check_start(self, state: LBRState, where: str) -> None:
        if not self._checked:
            self._check_period(state)
        q = state.measured_joint_position
        dist, j = self._distance(q)
        if not self._checked:
            self.start_distance = dist
            self._checked = True
        if dist > self.start_tolerance and not self.move_to_start:
            raise StopSession(
                f"the first row is {dist:.6f} rad from the measured position on A{j + 1} {where} "
                f"(measured {q[j]:.6f}, file {self.rows[0][j]:.6f}), more than --start-tolerance "
                f"{self.start_tolerance:g} rad; move the robot there first or use --move-to-start",
                completed=False,
            )

    def monitor(self, state: LBRState) -> None:
        if not self._checked:
            self._check_start(state, "at the first message")
        self.phase = PHASE_NONE

    def wait_for_command(self, state: LBRState) -> None:
        if not self._checked:
            self._check_start(state, "at the first message")
        self.hold_ipo(state)
        self.phase = PHASE_NONE

    # -- streaming -------------------------------------------------------------------------------------------
    def command(self, state: LBRState) -> Sequence[float] | None:
        if self._last is None:  # activation: the robot must still be where the start was checked
            self._check_start(state, "at activation")
            q0 = state.ipo_joint_position
            self._last = q0
            period = self.period_s or state.sample_time * state.receive_multiplier
            self._period = period
            if self.settle_s is not None:
                self.settle_cycles = int(round(self.settle_s / period))
            self._move = OnlineMove(self.limits, period, self.move_scale, self.move_minimum_duration)
            if max(abs(a - b) for a, b in zip(q0, self.rows[0])) > 0.0 or self.move_minimum_duration:
                self._move.start(q0, self.rows[0])
        if not self.reply_due:  # with receive multiplier k only every k-th command is sent: advance then
            return self._last
        if self.skipped and self._last2 is not None:
            self._bridged(self.skipped)
        self._last2 = self._last
        if self._advance():
            return self._last
        raise StopSession(self.finish_text)

    def _bridged(self, n: int) -> None:
        """The controller extrapolated our last command for ``n`` periods (its messages were lost): continue from
        there — the move re-planned, the rows rejoined in step (never rows behind), the settle unchanged."""
        dt = self._period
        vel = [(a - b) / dt for a, b in zip(self._last, self._last2)]  # [rad/s]
        q = tuple(a + n * v * dt for a, v in zip(self._last, vel))
        self._last, self._last2 = q, tuple(a - v * dt for a, v in zip(q, vel))
        self.skipped_rows += n
        move = self._move
        if move is not None and not move.done:
            move.start(q, self.rows[0], vel)
        elif self._queue or self._i < len(self.rows):
            first = self._i + n - len(self._queue)  # the row due now (a rejoin in progress: its rows)
            self._queue, self._i = rejoin(self.limits, dt, q, vel, self.rows, min(first, len(self.rows)))
            self._queue.reverse()  # popped from the end

    def _advance(self) -> bool:
        """Step to the next command (``_last``, ``phase``, ``row``); False when the hold at the end is over."""
        if self._queue:
            self._last = self._queue.pop()
            self.phase, self.row = PHASE_TRAJECTORY, self._i - len(self._queue) - 1
            self.trajectory_rows += 1
            return True
        move = self._move
        if move is not None and not move.done:
            q = move.next()
            if not move.done or q != self.rows[0]:
                self.phase, self.row = PHASE_MOVE, -1
                self.move_rows += 1
                self._last = q
                return True
        if self._i < len(self.rows):
            self.phase, self.row = PHASE_TRAJECTORY, self._i
            self._last = self.rows[self._i]
            self._i += 1
            self.trajectory_rows += 1
            return True
        if self._settled < self.settle_cycles:
            self._settled += 1
            self.settle_rows += 1
            self.phase, self.row = PHASE_SETTLE, -1
            return True
        return False

    def figures(self) -> dict[str, float | int]:
        return {
            "move_rows": self.move_rows,
            "trajectory_rows": self.trajectory_rows,
            "settle_rows": self.settle_rows,
            "skipped_rows": self.skipped_rows,
            "start_distance_rad": self.start_distance,
            "operation_mode": self.operation_mode,
        }
