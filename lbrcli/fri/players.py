"""Clients that move the robot along joint positions: the CSV player and the point-to-point move.

:class:`TrajectoryPlayer` streams rows [rad] at the command period, one per sent command: first a jerk-limited
move (ruckig, online, ≤ ``move_scale`` of the limits) from where the controller holds the robot to the first row —
always, so that the stream never starts with a jump; farther than ``start_tolerance`` only with
``move_to_start`` — then the rows, then the last row for ``settle_cycles``. Rows follow the controller's clock:
after lost messages (it bridged those periods by extrapolation) a short jerk-limited segment rejoins the rows in
step (``rejoin``). With a ``move_shaper`` (impulses for the swing period of a ball on the flange) the move is
input-shaped so that it leaves the ball at rest; with a :class:`~lbrcli.fri.sway.SwayWatch` the sway the rows start
with is reported, and with ``move_to_start`` the first row is held until the measured sway has stayed below its
threshold for a window (at most its ``max_wait_s``). It checks the start at the first message (before anything is sent) and again at
activation, and ends with :class:`StopSession` (the application then brakes to rest and ends).
"""

from __future__ import annotations

import math
from typing import Any, Callable, Sequence

import numpy as np

from trajectories.limits import JointLimits

from .client import LBRClient
from .constants import Phase
from .errors import StopSession
from .moves import OnlineMove, ShapedMove, extrapolated, rejoin
from .state import LBRState
from .sway import SwayWatch

PHASE_NONE, PHASE_MOVE, PHASE_TRAJECTORY, PHASE_SETTLE = Phase.NONE, Phase.MOVE, Phase.TRAJECTORY, Phase.SETTLE
PHASE_WAIT = Phase.WAIT


MAX_SEND_PERIOD_MS = 100  # [ms] the longest send period a controller's FRI configuration takes (1..100)


def whole_send_period_ms(step_s: float, receive_multiplier: int = 1) -> int | None:
    """The send period [ms], a whole 1..100, at which rows ``step_s`` [s] apart are one per command (send period ×
    ``receive_multiplier``); None when there is none."""
    send_ms = step_s * 1e3 / receive_multiplier
    whole = round(send_ms)
    return whole if abs(send_ms - whole) <= 1e-6 and 1 <= whole <= MAX_SEND_PERIOD_MS else None


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
        move_shaper: Any = None,
        move_robot: Any = None,
        sway: SwayWatch | None = None,
        rejoin_share: float = 1.0,
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
        self.move_shaper = move_shaper  # .amplitudes, .times [s] (planners.shapers.Shaper): the move is shaped
        self.move_robot = move_robot  # trajectories.robot.Robot: ... for the TCP's path (the ball hangs there)
        self.sway = sway
        self.rejoin_share = rejoin_share  # of the limits a rejoin after lost messages may use (a client adding its own
        # corrections to the rows keeps the rest for them)
        self._started = False  # the first row was commanded
        self._waited = 0  # commands holding the first row for the sway
        self._max_wait = 0  # commands (from the period at activation)
        self._rest_mark = 0  # move commands when the sway was last judged from rest
        self._move: OnlineMove | None = None
        self._ahead: tuple[tuple[float, ...], bool] | None = None  # the move's next step and whether it ends it
        self._checked = False
        self._i = 0  # next row
        self._settled = 0
        self._last: tuple[float, ...] | None = None
        self._last2: tuple[float, ...] | None = None  # the command before _last
        self._queue: list[tuple[float, ...]] = []  # commands of a rejoin after lost messages
        self._deferred = 0  # rows passed while a rejoin waits to be planned after the reply (0: none waits)
        self._period = 0.0  # [s] command period (known at activation)
        # figures
        self.move_rows = self.trajectory_rows = self.settle_rows = 0
        self.start_sway: float | None = None  # [rad] largest |sway| over the window before the first row
        self.started_above_threshold = False  # the rows started above the sway threshold (no wait, or it ran out)
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
        got = self.command_period_s or 0.0  # [s] (0: the controller sends no period)
        if abs(got - self.period_s) > 1e-9 and self.resample is not None:
            rows = np.asarray(self.resample(got), dtype=float)  # may raise StopSession (e.g. the check fails)
            self.rows = [tuple(r) for r in rows.tolist()]
            self.period_s = got
            return
        if abs(got - self.period_s) > 1e-9:
            raise StopSession(
                f"the controller's command period is {got * 1e3:g} ms (send period {state.sample_time * 1e3:g} ms × "
                f"receive multiplier {state.receive_multiplier}), the rows' step is {self.period_s * 1e3:g} ms; "
                "re-plan at that step or resample the rows (TrajectoryPlayer.resample)",
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
                f"(measured {q[j]:.6f}, file {self.rows[0][j]:.6f}), more than the start tolerance "
                f"(TrajectoryPlayer.start_tolerance) {self.start_tolerance:g} rad; move the robot there first or "
                "move to the start (TrajectoryPlayer.move_to_start)",
                completed=False,
            )

    def monitor(self, state: LBRState) -> None:
        if self.sway is not None:
            self.sway.update(state)
        if not self._checked:
            self._check_start(state, "at the first message")
        self.phase = PHASE_NONE

    def wait_for_command(self, state: LBRState) -> None:
        if self.sway is not None:
            self.sway.update(state)
        if not self._checked:
            self._check_start(state, "at the first message")
        self.hold_ipo(state)
        self.phase = PHASE_NONE

    # -- streaming -------------------------------------------------------------------------------------------
    def command(self, state: LBRState) -> Sequence[float] | None:
        if self.sway is not None and not self._started:  # (only the start is judged by the sway)
            self.sway.update(state)
        if self._last is None:  # activation: the robot must still be where the start was checked
            self._check_start(state, "at activation")
            q0 = state.ipo_joint_position
            self._last = q0
            period = self.period_s or self.command_period_s
            self._period = period
            if self.settle_s is not None:
                self.settle_cycles = int(round(self.settle_s / period))
            shaper = self.move_shaper
            self._move = (
                OnlineMove(self.limits, period, self.move_scale, self.move_minimum_duration) if shaper is None
                else ShapedMove(self.limits, period, self.move_scale, shaper.amplitudes, shaper.times,
                                self.move_minimum_duration, self.move_robot)
            )  # fmt: skip
            if self.sway is not None and self.move_to_start:  # without it the sway is only reported
                self._max_wait = int(round(self.sway.max_wait_s / period))
            if max(abs(a - b) for a, b in zip(q0, self.rows[0])) > 0.0 or self.move_minimum_duration:
                self._move.start(q0, self.rows[0])
        if not self.reply_due:  # with receive multiplier k only every k-th command is sent: advance then
            return self._last
        if self.skipped and self._last2 is not None:
            if self._defers():  # the rejoin is planned after the reply: this command goes on at constant velocity
                return self._go_on(self.skipped)
            self._bridged(self.skipped)
        elif self._deferred:  # (the reply went out without after_reply: planned now)
            self._plan_deferred()
        self._last2 = self._last
        if self._advance():
            return self._last
        raise StopSession(self.finish_text)

    def after_reply(self) -> None:
        """The rejoin after lost messages, planned behind the reply (ruckig, up to a few tenths of a ms): the cycle
        that found the loss answered at once with the controller's own constant-velocity continuation."""
        if self._deferred:
            self._plan_deferred()

    def _defers(self) -> bool:
        """Whether a loss found now is answered by going on at constant velocity, its rejoin planned after the reply:
        streaming the rows (not moving to the start), and a client whose command and after_reply are these."""
        move = self._move
        cls = type(self)
        return (
            cls.command is TrajectoryPlayer.command
            and cls.after_reply is TrajectoryPlayer.after_reply
            and self._started
            and (move is None or move.done)
            and self._ahead is None
            and (bool(self._queue) or self._i < len(self.rows))
        )

    def _go_on(self, n: int) -> tuple[float, ...]:
        """After ``n`` lost periods: where the controller's extrapolation is one period on — the command that agrees
        with every bridging model; the rows it passed (``n`` + 1) are rejoined from there (:meth:`_plan_deferred`)."""
        q, self._last2, _ = extrapolated(self._last, self._last2, n + 1, self._period)  # type: ignore[arg-type]
        self._last = q
        self._deferred += n + 1
        self.skipped_rows += n
        self.trajectory_rows += 1  # (as a rejoin's commands: in place of the row due now)
        self.phase, self.row = PHASE_TRAJECTORY, min(self._i + self._deferred - len(self._queue), len(self.rows)) - 1
        self.exact_command = False
        return q

    def _plan_deferred(self) -> None:
        """The rejoin from the last command [rad] and its velocity onto the rows, ``_deferred`` rows on."""
        k, self._deferred = self._deferred, 0
        dt = self._period
        vel = [(a - b) / dt for a, b in zip(self._last, self._last2)]  # type: ignore[arg-type]
        first = self._i + k - len(self._queue)
        self._queue, self._i = rejoin(
            self.limits, dt, self._last, vel, self.rows, min(first, len(self.rows)), share=self.rejoin_share
        )
        self._queue.reverse()  # popped from the end

    def prepare_command(self) -> Sequence[float] | None:
        """The next move, row, rejoin or settle command [rad] (None at activation, on arrival at the first row, during a
        wait for the sway, after lost messages and at the end: those are decided per message). A subclass
        that overrides ``command`` (corrections from the measured state) prepares nothing unless it overrides this."""
        if type(self).command is not TrajectoryPlayer.command:
            return None
        return self._next_planned()

    def _next_planned(self) -> tuple[float, ...] | None:
        """What :meth:`prepare_command` prepares, for a subclass that adds to the planned command [rad]."""
        if self._last is None or self._deferred:
            return None
        if self._queue:
            return self._queue[-1]
        move = self._move
        if move is not None and (not move.done or self._ahead is not None):
            if self._ahead is None:  # the move's next step, computed now and taken by the next _advance
                q = move.next()
                self._ahead = (q, move.done)
            q, done = self._ahead
            return q if not done or q != self.rows[0] else None  # arrived: the sway and the rows decide
        if not self._started:
            return None
        if self._i < len(self.rows):
            return self.rows[self._i]
        if self._settled < self.settle_cycles:
            return self._last
        return None

    def _bridged(self, n: int) -> None:
        """The controller extrapolated our last command for ``n`` periods (its messages were lost): continue from
        there — the move goes on in step with its plan (it arrives on time; the motion-safety core absorbs the
        extrapolation's difference), the rows rejoined in step (never rows behind), the settle unchanged."""
        move = self._move
        if self._ahead is not None:  # a move's step computed ahead was never sent
            self._ahead = None
            if move is not None:
                move.unstep()
        dt = self._period
        q, self._last2, vel = extrapolated(self._last, self._last2, n, dt)
        self._last = q
        self.skipped_rows += n
        if move is not None and (not move.done or not self._started):  # moving to, or waiting at, the start
            move.skip(n)
        elif self._queue or self._i < len(self.rows):
            first = self._i + n - len(self._queue)  # the row due now (a rejoin in progress: its rows)
            self._queue, self._i = rejoin(
                self.limits, dt, q, vel, self.rows, min(first, len(self.rows)), share=self.rejoin_share
            )
            self._queue.reverse()  # popped from the end

    def _advance(self) -> bool:
        """Step to the next command (``_last``, ``phase``, ``row``); False when the hold at the end is over."""
        self.exact_command = True  # the file's rows go out exactly, or the session ends braking …
        if self._queue:
            self._last = self._queue.pop()
            self.phase, self.row = PHASE_TRAJECTORY, self._i - len(self._queue) - 1
            self.trajectory_rows += 1
            self.exact_command = False  # … our own moves and rejoins may be clamped into the envelope
            return True
        move = self._move
        ahead = self._ahead
        if ahead is not None or (move is not None and not move.done):
            if ahead is not None:  # computed by prepare_command
                self._ahead = None
                q, done = ahead
            else:
                q = move.next()  # type: ignore[union-attr]
                done = move.done  # type: ignore[union-attr]
            if not done or q != self.rows[0]:
                self.phase, self.row = PHASE_MOVE, -1
                self.move_rows += 1
                self._last = q
                self.exact_command = False
                return True
        if not self._started and self._wait_for_sway():
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

    def _wait_for_sway(self) -> bool:
        """Hold the first row while the sway is above the threshold (at most ``max_wait_s``); True while holding.
        On the way out the sway the rows start with is recorded."""
        sway = self.sway
        if sway is not None and self._max_wait and self._rest_mark != self.move_rows:
            self._rest_mark = self.move_rows  # the robot has just arrived: judge its free swing from here
            sway.restart()
        if sway is not None and sway.readings and not sway.calm and self._waited < self._max_wait:
            self._waited += 1
            self.phase, self.row = PHASE_WAIT, -1
            self._last = self.rows[0]
            return True
        self._started = True
        if sway is not None and sway.readings:
            self.start_sway = sway.amplitude
            self.started_above_threshold = not sway.calm
        return False

    def figures(self) -> dict[str, float | int]:
        start = self.start_sway
        return {
            "move_rows": self.move_rows,
            "trajectory_rows": self.trajectory_rows,
            "settle_rows": self.settle_rows,
            "skipped_rows": self.skipped_rows,
            "start_distance_rad": self.start_distance,
            "operation_mode": self.operation_mode,
            "sway_wait_rows": self._waited,
            "sway_wait_s": self._waited * self._period,
            "start_sway_rad": start,
            "start_sway_deg": None if start is None else math.degrees(start),
            "start_sway_above_threshold": self.started_above_threshold if start is not None else None,
            "sway_threshold_deg": math.degrees(self.sway.threshold) if self.sway is not None else None,
        }
