"""A feedback client: stream a joint CSV while the measured sway corrects the pivot (``lbr control damp``).

The rows are streamed as by :class:`~lbrcli.fri.players.TrajectoryPlayer` (the jerk-limited move to the start, the
wait for a calm ball, rejoining after lost messages); from the first row on, each command adds the
:class:`planners.feedback.damping.SwayDamper`'s horizontal offset (Δx, Δy) of the TCP, mapped onto the joints by
the row's precomputed Jacobian pseudo-inverse (:class:`planners.feedback.correction.CorrectionPlan`), inside the
joints' headroom left by the plan. After the last row the damper goes on for ``damp_s`` [s] (the settle), then a
jerk-limited move takes the arm from wherever the offset left it to the last row, and the session ends.

Angles come from a sensor (:mod:`lbrcli.control.sensors`): the controller's analog inputs (``io_names``, [rad], the
simulator's ball: ``ball_theta_x``, ``ball_theta_y``), the pendulum module's serial reader (one axis,
``module_axis``), or a camera tracked live; each reading is checked against the model, and the session completes
only when the fitted residual sway is within ``target``.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from typing import Sequence

import numpy as np

from planners.feedback.correction import CorrectionPlan
from planners.feedback.damping import DampingOptions, SwayDamper, sway_reference
from planners.feedback.health import HealthOptions, SensorHealth, swing_amplitude
from planners.pendulum import natural_period
from trajectories.limits import JointLimits

from lbrcli.fri import LBRState, OnlineMove, Phase, StopSession, TrajectoryPlayer
from lbrcli.fri.moves import extrapolated
from lbrcli.fri.outcome import cost_figures_us

from .sensors import IoSensor, ModuleSensor

REPLY_FIRST_MAX_PERIOD_S = 2e-3  # [s] up to this period the feedback runs after the reply (by default): there the
# cycle's work is a large share of the period; at longer periods one period more of delay would cost the damping more
LOG_COLUMNS = ("damp_x", "damp_y", "est_theta_x", "est_theta_y", "ref_theta_x", "ref_theta_y")  # [m] ×2, [rad] ×4


class DampingClient(TrajectoryPlayer):
    """Streams ``rows`` (n, 7) [rad] at ``period_s`` [s] with active sway damping for a string of ``length`` [m].

    ``sensor`` gives the readings (:mod:`lbrcli.control.sensors`; default: the analog inputs ``io_names``, or the
    pendulum module on ``module_axis`` when ``io_names`` is None). Every reading is checked against the model
    (:class:`planners.feedback.health.SensorHealth`): a sensor that is not telling the truth stops the correction —
    the rows finish as planned — and ends the session as failed. The residual sway is the amplitude of the swing
    fitted to the readings of the last ``tail_periods`` periods of the damping time; the session is completed only
    when it is at most ``target`` [rad]. ``reply_first`` (default: at periods up to ``REPLY_FIRST_MAX_PERIOD_S``):
    each message's readings are read and the damper stepped after its reply, and the next command is prepared then,
    so that the reply goes out as soon as the message is checked (one period more between a reading and its
    correction)."""

    def __init__(self, rows: np.ndarray, limits: JointLimits, period_s: float, length: float, plan: CorrectionPlan, *,
                 damp_s: float, sensor_delay_s: float, io_names: tuple[str, str] | None = ("ball_theta_x", "ball_theta_y"),
                 module_axis: int = 1, sensor_rate_hz: float | None = None, options: DampingOptions = DampingOptions(),
                 active: bool = True, actuation_delay: int = 1, sensor=None, target: float = math.radians(0.3),
                 tail_periods: float = 1.0, health: HealthOptions = HealthOptions(), reply_first: bool | None = None,
                 **player) -> None:  # fmt: skip
        player.setdefault("rejoin_share", plan.rejoin_share)  # a rejoin leaves the offsets the rest (rejoin_bounds)
        super().__init__(rows, limits, period_s=period_s, settle_s=damp_s, **player)
        if len(plan) != len(self.rows):
            raise ValueError("the correction plan must have one entry per row")
        self.length, self.plan, self.options = length, plan, options
        if sensor is None:
            sensor = IoSensor(io_names) if io_names is not None else ModuleSensor(module_axis, sensor_rate_hz or 200.0)
        self.sensor = sensor
        self._observe = getattr(sensor, "observe", None)  # a camera's pivot: the robot's pose of every message
        self._failure = getattr(sensor, "failure", None)  # a sensor that can tell it failed (a camera's stream)
        self.target = target
        n_total = len(self.rows) + int(round(damp_s / period_s)) + 2
        acc = np.zeros((n_total, 2))
        acc[: len(plan)] = plan.planned_accel
        self._ref, self._ref_rate = (a.tolist() for a in sway_reference(acc, length, period_s, actuation_delay))
        self._acc = acc.tolist()
        self._maps = [tuple(tuple(r) for r in m.T.tolist()) for m in plan.maps]  # per row: (x column, y column)
        self._bounds = [tuple(b) for b in plan.bounds.tolist()]
        self._rejoin_bounds = [tuple(b) for b in plan.rejoin_bounds.tolist()]
        self._bound = self._bounds[0]
        interval = sensor.interval_s or period_s
        opts = replace(options, travel=plan.travel)
        # reply first: each message's readings are read after its reply went out, for the next command — one
        # period more between a reading and the command it corrects
        self.reply_first = period_s <= REPLY_FIRST_MAX_PERIOD_S if reply_first is None else reply_first
        self._defer_s = period_s if self.reply_first else 0.0  # [s]
        sensor_delay_s += self._defer_s
        self.damper = SwayDamper(length, period_s, sensor_delay_s, interval, opts, actuation_delay=actuation_delay,
                                 bounds=lambda x, v, a: self._bound, max_delay=getattr(sensor, "max_age_s", None))  # fmt: skip
        self.damper.active = active
        self._lag = int(round(sensor_delay_s / period_s)) + actuation_delay
        self._actuation = actuation_delay
        # the plan's own swing may be large (an unshaped move): a runaway is well beyond it
        peak = float(np.max(np.abs(np.asarray(self._ref)))) if len(self._ref) else 0.0
        health = replace(health, diverged=max(health.diverged, 1.5 * peak + math.radians(10.0)))
        self.health = {axis: SensorHealth(sensor.describe(axis), health) for axis in sensor.axes}
        self.sensor_fault: str | None = None
        self._fault_at: float | None = None  # [s] after the first row
        self._k = -1  # damper cycles since the first row (index into the tables)
        self._pending: int | None = None  # reply first: the cycle (_k) the damper was stepped for after the last reply
        self._read_now = False  # this message's readings were read in its command() (the first row)
        self._applied = (0.0, 0.0)  # [m] the offsets (x, y) in this cycle's command
        self._return: OnlineMove | None = None
        self._finish: StopSession | None = None
        self._held = 0  # cycles held on the last row after the return move
        self._cmd: tuple[float, ...] | None = None
        self._cmd_prev: tuple[float, ...] | None = None
        # figures
        self.cost_ns: list[int] = []
        self.max_offset = 0.0  # [m]
        self.return_rows = 0
        self.readings = 0
        # the last tail_periods swing periods of the damping time: the readings the residual is fitted to
        self._period_T = natural_period(length)
        self._tail_from = len(self.rows) + max(0, int(round((damp_s - tail_periods * self._period_T) / period_s)))
        self._tail: dict[int, list[tuple[float, float]]] = {axis: [] for axis in sensor.axes}
        self.residual: float | None = None  # [rad] the fitted residual sway (None: not measured)
        self.peak_residual = 0.0  # [rad] the largest reading in the tail (noise included)

    @property
    def reader(self):
        """The pendulum module's reader (the runner sets it when the module is attached)."""
        return getattr(self.sensor, "reader", None)

    @reader.setter
    def reader(self, value) -> None:
        if hasattr(self.sensor, "reader"):
            self.sensor.reader = value

    # -- the per-cycle correction ----------------------------------------------------------------------------------
    def _read(self, state: LBRState) -> None:
        d = self.damper
        t = self._k * self._period
        last = len(self._ref) - 1
        for reading in self.sensor.poll(state):
            axis, value = reading[0], reading[1]
            age = reading[2] + self._defer_s if len(reading) > 2 else None  # [s] its own age, if the sensor knows it
            obs = d.observers[axis]
            if self.sensor_fault is None:
                lag = self._lag if age is None else obs.lag_of(age) + self._actuation
                seen = self._k - lag if self._k > lag else 0  # the row whose moment the reading shows
                drive = self._acc[min(self._k, len(self._acc) - 1)][axis] + d.carts[axis].a
                fault = self.health[axis].reading(t, value, obs.predicted_reading(age), self._ref[min(seen, last)][axis],
                                                  drive)  # fmt: skip
                if fault is not None:
                    self._stop_correcting(fault, t)
                else:  # the estimate follows the readings also open loop (it is logged)
                    d.correct(axis, value, age)
            self.readings += 1
            if self._k >= self._tail_from and math.isfinite(value):
                self._tail[axis].append((t, value))
                self.peak_residual = max(self.peak_residual, abs(value))
        if self._failure is not None and self.sensor_fault is None:
            why = self._failure()
            if why is not None:
                self._stop_correcting(why, t)

    def _stop_correcting(self, why: str, t: float) -> None:
        """The sensor is not to be trusted: no more correction (the offsets ride out); the session will fail."""
        self.sensor_fault, self._fault_at = why, t
        self.damper.active = False

    def _step_damper(self, k: int) -> None:
        """The damper's step for cycle ``k`` (its offsets for that command) and the estimate's health."""
        t0 = time.perf_counter_ns()
        n = len(self._bounds)
        row = k if k < n else n - 1
        # rejoining the rows after lost messages: the joints' motion is the rejoin's, the offsets get what it leaves
        self._bound = self._rejoin_bounds[row] if self._queue else self._bounds[row]
        m = len(self._ref) - 1
        kk = k if k < m else m
        self.damper.step(self._ref[kk], self._ref_rate[kk], self._acc[kk])
        if self.sensor_fault is None and self.damper.active:  # (open loop there is no feedback to run away)
            for axis, h in self.health.items():
                fault = h.estimate(self.damper.observers[axis].phi)
                if fault is not None:
                    self._stop_correcting(fault, k * self._period)
        self.cost_ns.append(time.perf_counter_ns() - t0)

    def _offset(self, q: Sequence[float], k: int) -> tuple[float, ...]:
        """The planned command ``q`` [rad] of cycle ``k`` plus the damper's offsets, mapped onto the joints."""
        n = len(self._maps)
        cx, cy = self.damper.carts
        dx, dy = cx.x, cy.x
        mx, my = self._maps[k if k < n else n - 1]
        return tuple([a + u * dx + w * dy for a, u, w in zip(q, mx, my)])  # (a list: no generator per cycle)

    def _corrected(self, q: Sequence[float], k: int) -> tuple[float, ...]:
        if self._pending is None:
            self._step_damper(k)
        else:  # stepped for cycle _pending after the last reply; periods the controller bridged since: coasted
            for _ in range(k - self._pending):
                self.damper.coast((0.0, 0.0))
            self._pending = None
        cx, cy = self.damper.carts
        self._applied = (cx.x, cy.x)
        off = abs(cx.x) if abs(cx.x) > abs(cy.x) else abs(cy.x)
        if off > self.max_offset:
            self.max_offset = off
        return self._offset(q, k)

    def after_reply(self) -> None:
        """Reply first: this message's readings and the damper's step for the next cycle, after the reply."""
        if (not self.reply_first or self._k < 0 or self._return is not None or self.braking or self._pending is not None
                or self.phase not in (Phase.TRAJECTORY, Phase.SETTLE)):  # fmt: skip
            self._read_now = False
            return
        if not self._read_now:
            self._read(self.robot_state)
        self._read_now = False
        self._step_damper(self._k + 1)
        self._pending = self._k + 1

    def prepare_command(self) -> Sequence[float] | None:
        """The next row plus the offsets the damper was stepped to after this reply (reply first), else None."""
        if self._pending is None or self._pending != self._k + 1 or self._return is not None:
            return None
        q = self._next_planned()
        return None if q is None else self._offset(q, self._pending)

    def monitor(self, state: LBRState) -> None:
        if self._observe is not None:
            self._observe(state)
        super().monitor(state)

    def wait_for_command(self, state: LBRState) -> None:
        if self._observe is not None:
            self._observe(state)
        super().wait_for_command(state)

    def command(self, state: LBRState) -> Sequence[float] | None:
        if self._observe is not None:
            self._observe(state)
        if self._return is not None:
            return self._returning()
        if self._k >= 0 and self.reply_due and self._pending is None:  # (reply first: read after the reply)
            for _ in range(self.skipped):  # the controller extrapolated our command: the offsets moved on as it did
                self.damper.coast((0.0, 0.0))  # (constant joint velocity: about no pivot acceleration)
            self._read(state)
            self._read_now = True
        try:
            q = super().command(state)
        except StopSession as stop:
            if not stop.completed or self._k < 0:
                raise
            return self._start_return(stop)
        if not self.reply_due or self.phase not in (Phase.TRAJECTORY, Phase.SETTLE):
            return q
        self._k += 1 + (self.skipped if self._k >= 0 else 0)
        if self._k == 0:
            self._read(state)
            self._read_now = True
        self._cmd_prev, self._cmd = self._cmd, self._corrected(q, self._k)
        self.exact_command = False  # a row plus the damper's offset: feedback, clamped into the envelope if need be
        return self._cmd

    def _start_return(self, stop: StopSession) -> Sequence[float]:
        """The damping time is over: a jerk-limited move from the last command (and its velocity) to the last row."""
        self._finish = stop
        # the offset (a millimetre or so) moved back fast would swing the ball by offset / length [rad]; a move that
        # takes one swing period accelerates and brakes over half a period each, which cancel at the string's period
        self._return = OnlineMove(self.limits, self._period, self.move_scale, self._period_T)
        self._replan_return()
        return self._returning(replanned=True)

    def _replan_return(self) -> None:
        """(Re)start the return from where the controller's extrapolation of our last two commands puts the arm."""
        prev = self._cmd_prev or self._cmd
        self._cmd, self._cmd_prev, vel = extrapolated(self._cmd, prev, self.skipped, self._period)
        self._return.start(self._cmd, self.rows[-1], vel)
        self._held = 0

    def _returning(self, replanned: bool = False) -> Sequence[float]:
        move = self._return
        if not self.reply_due:
            return self._cmd
        if self.skipped and not replanned:  # messages were lost during the return: it goes on in step with its plan
            prev = self._cmd_prev or self._cmd
            self._cmd, self._cmd_prev, _ = extrapolated(self._cmd, prev, self.skipped, self._period)
            move.skip(self.skipped)
        if move.done:
            if self._held < 2:  # at rest on the last row before the session's stop: it starts with zero velocity
                self._held += 1
                self._cmd_prev, self._cmd = self._cmd, move.target
                return self._cmd
            raise self._verdict()
        self._cmd_prev, self._cmd = self._cmd, move.next()
        self.phase = Phase.SETTLE
        self.return_rows += 1
        return self._cmd

    def _verdict(self) -> StopSession:
        """How the session ends: completed only when the sensor held up and the fitted residual is within the target."""
        amps = [swing_amplitude(np.array([p[0] for p in pts]), np.array([p[1] for p in pts]), self._period_T)
                for pts in self._tail.values() if len(pts) >= 4]  # fmt: skip
        self.residual = math.hypot(*amps) if amps else None
        if self.sensor_fault is not None:
            return StopSession(f"{self.sensor_fault} — the correction stopped {self._fault_at:.2f} s after the first row "
                               "and the rows finished as planned; the sway is not known", completed=False)  # fmt: skip
        if not self.damper.active:
            return self._finish  # open loop (asked for): the rows were streamed
        if self.residual is None:
            return StopSession("no reading arrived in the last period of the damping time: the sway is not known",
                               completed=False)  # fmt: skip
        if self.residual > self.target:
            return StopSession(f"residual sway {math.degrees(self.residual):.3f}° (fitted over the last "
                               f"{self._period_T:.2f} s) is above the target {math.degrees(self.target):.3f}°",
                               completed=False)  # fmt: skip
        return self._finish

    # -- log and figures ---------------------------------------------------------------------------------------
    def log_values(self, mon=None) -> tuple[float, ...]:
        if self._k < 0:
            return (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)  # before the first row (phase < TRAJECTORY): nothing estimated yet
        kk = min(self._k, len(self._ref) - 1)
        ox, oy = self.damper.observers
        return (*self._applied, ox.phi, oy.phi, self._ref[kk][0], self._ref[kk][1])

    def figures(self) -> dict:
        f = super().figures()
        f.update(
            damping_active=self.damper.active,
            max_offset_m=self.max_offset,
            offset_trimmed_cycles=sum(c.trimmed for c in self.damper.carts),
            return_rows=self.return_rows,
            sway_readings=self.readings,
            measured_residual_deg=math.degrees(self.residual) if self.residual is not None else None,
            peak_residual_reading_deg=math.degrees(self.peak_residual) if self._k >= self._tail_from else None,
            target_deg=math.degrees(self.target),
            sensor_fault=self.sensor_fault,
            **cost_figures_us(self.cost_ns),
        )
        sensor_figures = getattr(self.sensor, "figures", None)
        if sensor_figures is not None:
            f.update(sensor_figures())
        return f
