"""A feedback client: stream a joint CSV while the measured sway corrects the pivot (``lbr control damp``).

The rows are streamed as by :class:`~lbrcli.fri.players.TrajectoryPlayer` (the jerk-limited move to the start, the
wait for a calm ball, rejoining after lost messages); from the first row on, each command adds the
:class:`planners.feedback.damping.SwayDamper`'s horizontal offset (Δx, Δy) of the TCP, mapped onto the joints by
the row's precomputed Jacobian pseudo-inverse (:class:`planners.feedback.correction.CorrectionPlan`), inside the
joints' headroom left by the plan. After the last row the damper goes on for ``damp_s`` [s] (the settle), then a
jerk-limited move takes the arm from wherever the offset left it to the last row, and the session ends.

Angles come from the controller's analog inputs (``io_names``, [rad], the simulator's ball: ``ball_theta_x``,
``ball_theta_y``) or from the pendulum module's serial reader (one axis, ``module_axis``).
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from typing import Sequence

import numpy as np

from planners.feedback.correction import CorrectionPlan
from planners.feedback.damping import DampingOptions, SwayDamper, sway_reference
from planners.pendulum import natural_period
from trajectories.limits import JointLimits

from lbrcli.fri import LBRState, OnlineMove, Phase, StopSession, TrajectoryPlayer
from lbrcli.fri.moves import extrapolated
from lbrcli.fri.outcome import cost_figures_us

LOG_COLUMNS = ("damp_x", "damp_y", "est_theta_x", "est_theta_y", "ref_theta_x", "ref_theta_y")  # [m] ×2, [rad] ×4


class DampingClient(TrajectoryPlayer):
    """Streams ``rows`` (n, 7) [rad] at ``period_s`` [s] with active sway damping for a string of ``length`` [m]."""

    def __init__(self, rows: np.ndarray, limits: JointLimits, period_s: float, length: float, plan: CorrectionPlan, *,
                 damp_s: float, sensor_delay_s: float, io_names: tuple[str, str] | None = ("ball_theta_x", "ball_theta_y"),
                 module_axis: int = 1, sensor_rate_hz: float | None = None, options: DampingOptions = DampingOptions(),
                 active: bool = True, actuation_delay: int = 1, **player) -> None:  # fmt: skip
        player.setdefault("rejoin_share", plan.rejoin_share)  # a rejoin leaves the offsets the rest (rejoin_bounds)
        super().__init__(rows, limits, period_s=period_s, settle_s=damp_s, **player)
        if len(plan) != len(self.rows):
            raise ValueError("the correction plan must have one entry per row")
        self.length, self.plan, self.options = length, plan, options
        self.io_names, self.module_axis = io_names, module_axis
        self.reader = None  # PendulumReader (set by the runner when the module is attached; used without io_names)
        n_total = len(self.rows) + int(round(damp_s / period_s)) + 2
        acc = np.zeros((n_total, 2))
        acc[: len(plan)] = plan.planned_accel
        self._ref, self._ref_rate = (a.tolist() for a in sway_reference(acc, length, period_s, actuation_delay))
        self._acc = acc.tolist()
        self._maps = [tuple(tuple(r) for r in m.T.tolist()) for m in plan.maps]  # per row: (x column, y column)
        self._bounds = [tuple(b) for b in plan.bounds.tolist()]
        self._rejoin_bounds = [tuple(b) for b in plan.rejoin_bounds.tolist()]
        self._bound = self._bounds[0]
        interval = period_s if io_names is not None else 1.0 / (sensor_rate_hz or 200.0)
        opts = replace(options, travel=plan.travel)
        self.damper = SwayDamper(length, period_s, sensor_delay_s, interval, opts, actuation_delay=actuation_delay,
                                 bounds=lambda x, v, a: self._bound)  # fmt: skip
        self.damper.active = active
        self._k = -1  # damper cycles since the first row (index into the tables)
        self._reading = None
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
        # the last swing period of the damping time
        self._tail_from = len(self.rows) + max(0, int(round((damp_s - natural_period(length)) / period_s)))
        self.residual = 0.0  # [rad] largest measured sway in that period

    # -- the per-cycle correction ----------------------------------------------------------------------------------
    def _read(self, state: LBRState) -> None:
        d = self.damper
        if self.io_names is not None:
            tx, ty = state.analog_io(self.io_names[0]), state.analog_io(self.io_names[1])
            d.correct(0, tx)
            d.correct(1, ty)
            self.readings += 1
            if self._k >= self._tail_from:
                self.residual = max(self.residual, math.hypot(tx, ty))
            return
        r = self.reader.latest if self.reader is not None else None
        if r is not None and r is not self._reading:
            self._reading = r
            d.correct(self.module_axis, r.theta)
            self.readings += 1
            if self._k >= self._tail_from:
                self.residual = max(self.residual, abs(r.theta))

    def _corrected(self, q: Sequence[float], k: int) -> tuple[float, ...]:
        t0 = time.perf_counter_ns()
        n = len(self._bounds)
        row = k if k < n else n - 1
        # rejoining the rows after lost messages: the joints' motion is the rejoin's, the offsets get what it leaves
        self._bound = self._rejoin_bounds[row] if self._queue else self._bounds[row]
        m = len(self._ref) - 1
        kk = k if k < m else m
        self.damper.step(self._ref[kk], self._ref_rate[kk], self._acc[kk])
        cx, cy = self.damper.carts
        dx, dy = cx.x, cy.x
        mx, my = self._maps[row]
        out = tuple(a + u * dx + w * dy for a, u, w in zip(q, mx, my))
        off = abs(dx) if abs(dx) > abs(dy) else abs(dy)
        if off > self.max_offset:
            self.max_offset = off
        self.cost_ns.append(time.perf_counter_ns() - t0)
        return out

    def command(self, state: LBRState) -> Sequence[float] | None:
        if self._return is not None:
            return self._returning()
        if self._k >= 0 and self.reply_due:
            for _ in range(self.skipped):  # the controller extrapolated our command: the offsets moved on as it did
                self.damper.coast((0.0, 0.0))  # (constant joint velocity: about no pivot acceleration)
            self._read(state)
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
        self._cmd_prev, self._cmd = self._cmd, self._corrected(q, self._k)
        return self._cmd

    def _start_return(self, stop: StopSession) -> Sequence[float]:
        """The damping time is over: a jerk-limited move from the last command (and its velocity) to the last row."""
        self._finish = stop
        self._return = OnlineMove(self.limits, self._period, self.move_scale)
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
            raise self._finish
        self._cmd_prev, self._cmd = self._cmd, move.next()
        self.phase = Phase.SETTLE
        self.return_rows += 1
        return self._cmd

    # -- log and figures ---------------------------------------------------------------------------------------
    def log_values(self, mon=None) -> tuple[float, ...]:
        if self._k < 0:
            return (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)  # before the first row (phase < TRAJECTORY): nothing estimated yet
        d = self.damper
        kk = min(self._k, len(self._ref) - 1)
        ox, oy = d.observers
        return (d.carts[0].x, d.carts[1].x, ox.phi, oy.phi, self._ref[kk][0], self._ref[kk][1])

    def figures(self) -> dict:
        f = super().figures()
        f.update(
            damping_active=self.damper.active,
            max_offset_m=self.max_offset,
            offset_trimmed_cycles=sum(c.trimmed for c in self.damper.carts),
            return_rows=self.return_rows,
            sway_readings=self.readings,
            measured_residual_deg=math.degrees(self.residual) if self._k >= self._tail_from else None,
            **cost_figures_us(self.cost_ns),
        )
        return f
