"""The link to the controller as the application sees it, a collaborator of
:class:`~lbrcli.fri.application.ClientApplication`: the session's clock, the controller's messages lost on the way
(bridged by its extrapolation), our replies it reports not received (its reflected counter), and — once the first
message outside IDLE tells the period — the executed motion (:class:`~lbrcli.fri.motion.ExecutedMotion`) and the
supervision of the trends (:class:`~lbrcli.fri.supervision.Supervisor`).

A controller whose replies arrive a steady few periods late executes our commands in order, late: each message
reflects the reply after the one the previous message reflected, and reports that reply's position. Our commands
are then not bridged but queued: the history stays ours (re-basing it on the old position the message reports would
make each next command a jump from the ones still in flight — 100× the acceleration limit at 1–5 periods late)."""

from __future__ import annotations

from collections import deque
from typing import Any

from trajectories.limits import JointLimits

from .clock import SessionClock
from .motion import MATCH_TOL, ExecutedMotion
from .rejoin import far
from .supervision import Supervisor

from .constants import STATE_COMMANDING_ACTIVE as CMD_ACTIVE, STATE_IDLE as IDLE

_COMMANDED = "commandedJointPosition"
Supervised = tuple[bool, bool, Any, int]  # (commanding, moving, command in force [rad], our last sequence counter)


def _reported(mon: Any) -> tuple[Any, bool]:
    """The position the controller commanded (FRI 1.15) [rad] and False, else the measured one and True."""
    md = mon.monitorData
    cmd = md.commandedJointPosition.value if _COMMANDED in md.DESCRIPTOR.fields_by_name else ()
    return (cmd, False) if len(cmd) == 7 else (md.measuredJointPosition.value, True)


class Link:
    """One session's link: ``clock`` and, once the period is known, ``motion`` and ``sup`` (built from ``limits``,
    the wrench bounds ``max_force`` [N] and ``max_moment`` [Nm], ``hold_cycles`` and the supervision's bounds, as
    :class:`~lbrcli.fri.application.ClientApplication` takes them)."""

    def __init__(self, clock: SessionClock, limits: JointLimits, max_force: float, max_moment: float,
                 hold_cycles: int, max_tracking_error: float | None, reply_gap_s: float | None,
                 tracking_lag_s: float | None) -> None:  # fmt: skip
        self.clock = clock
        self.limits = limits
        self._wrench = (max_force, max_moment)
        self.hold_cycles = hold_cycles
        self._bounds = (max_tracking_error, reply_gap_s, tracking_lag_s)
        self.motion: ExecutedMotion | None = None
        self.sup: Supervisor | None = None
        self.missed = 0  # the controller's messages that never arrived
        self.lost_replies = 0  # commands the controller reported not received (reflected counter) while moving
        self.reply_seq_prev: int | None = None  # our reply to the previous message, if it carried a position
        self.late_in_order = 0  # messages that reflected our commands executed in order, late (not bridged)
        self._sent: deque[tuple[int, tuple[float, ...]]] = deque(maxlen=64)  # (client seq, position) sent moving
        self._reflected: int | None = None  # the reflected counter of the previous message

    @property
    def braking_cycles(self) -> int:
        """Cycles of the client side's braking stop (0: none)."""
        return self.motion.braking_cycles if self.motion is not None else 0

    @property
    def extrapolated_cycles(self) -> int:
        """Command periods the controller bridged because its messages were lost."""
        return self.motion.extrapolated_cycles if self.motion is not None else 0

    def reply_lost(self, mon: Any, d: int) -> bool:
        """Our reply to the previous message never reached the controller (the message, ``d`` = 1 sequence step
        later, reflects an older one): it bridged that period by extrapolation instead of executing our command."""
        expected, self.reply_seq_prev = self.reply_seq_prev, None
        return (expected is not None and d == 1 and self.sup is not None and self.sup.reflecting
                and mon.header.reflectedSequenceCounter != expected)  # fmt: skip

    def received(self, mon: Any, d: int, lost_reply: bool, moving: bool, now: float) -> int:
        """An accepted message ``d`` sequence steps after the last (0: the first) at ``now`` [s]; ``moving``: the
        robot was being commanded. The command periods the client missed (the motion bridged them), or −1 if more
        messages were lost in a row than any controller bridges."""
        clock = self.clock
        clock.received(now, d, mon.connectionInfo.sendPeriod)
        skipped = 0
        if d > 1:
            self.missed += d - 1
            if moving:
                if self.sup is not None and d - 1 > self.sup.max_reply_gap:
                    return -1
                skipped = self.motion.extrapolate((d - 1) // (clock.period_key[1] if clock.period_key else 1))  # type: ignore[union-attr]
                if skipped:  # where the controller really is after the gap (it may have held, not extrapolated)
                    pos, measured = _reported(mon)
                    self.motion.gap_seen(pos, skipped, measured)  # type: ignore[union-attr]
        reflected, self._reflected = self._reflected, mon.header.reflectedSequenceCounter
        if lost_reply and moving:
            pos, measured = _reported(mon)
            if self._in_order(reflected, pos, measured):
                self.late_in_order += 1
            else:
                self.motion.reply_lost(pos, measured)  # type: ignore[union-attr]
            self.lost_replies += 1  # (late replies: the controller had not received it when it sent this message)
        elif d == 1 and self.motion is not None and self.motion.lagging:
            self.motion.confirmed()  # (reflected: our last reply was in time)
        return skipped

    def _in_order(self, reflected: int | None, pos: Any, measured: bool) -> bool:
        """The message reflects the reply after the one the previous message reflected (``reflected``) and — its
        commanded position exact (FRI 1.15) — reports that reply's position, as sent or carried forward a whole number
        of periods at our commands' velocity (as our simulator does with a late reply): the controller executes our
        commands in order, late. A measured position (FRI 2.x) carries noise and the servo's lag: the counter decides."""
        r = self._reflected
        if reflected is None or r != (reflected + 1) & 0xFFFFFFFF or len(pos) != 7:
            return False
        q = q1 = None
        for c, x in reversed(self._sent):
            if c == r:
                q = x
            elif c == r - 1 and q is not None:
                q1 = x
                break
        if q is None:
            return False
        return measured or far(pos, q) <= MATCH_TOL or (q1 is not None and _carried(pos, q, q1, MATCH_TOL))

    def learn_period(self, mon: Any) -> bool:
        """The first message outside IDLE tells the command period: the executed motion and its supervision are
        built (True, once)."""
        ci = mon.connectionInfo
        if self.clock.period_key is not None or ci.sessionState == IDLE or not self.clock.learn_period(ci):
            return False
        clock = self.clock
        self.motion = ExecutedMotion(self.limits, clock.period_s, *self._wrench, self.hold_cycles,  # type: ignore[arg-type]
                                     mon.monitorData.measuredJointPosition.value)  # fmt: skip
        self.sup = Supervisor.from_limits(self.limits.velocity, ci.sendPeriod * 1e-3, clock.period_key[1],  # type: ignore[index]
                                          *self._bounds)  # fmt: skip
        return True

    def replied(self, cyc: Any, client_seq: int, seq: int) -> None:
        """Our reply ``client_seq`` to the message ``seq`` went out with ``cyc``'s command."""
        if self.sup is not None:
            self.sup.sent(client_seq, seq)
        if cyc.sent_position and cyc.state == CMD_ACTIVE:
            self.reply_seq_prev = client_seq
            if self.motion is not None:
                self._sent.append((client_seq, self.motion.prev))

    def supervise(
        self, mon: Any, seq: int, supervised: Supervised, position_mode: bool, stamp_ns: int | None
    ) -> str | None:
        """The supervision's judgement of the message ``seq`` against the command in force when it was sent
        (``supervised``): a problem (the motion then brakes at the period the robot really runs at), or None."""
        sup = self.sup
        if sup is None:
            return None
        commanding, moving, command, last_sent = supervised
        problem = sup.check(mon, seq, commanding, moving, position_mode, command, last_sent, stamp_ns)
        if problem is not None and sup.measured_period_s is not None and self.motion is not None:
            self.motion.retime(sup.measured_period_s)
        return problem


def _carried(pos: Any, q: tuple[float, ...], q1: tuple[float, ...], tol: float) -> bool:
    """``pos`` [rad] is our command ``q`` carried forward 1–63 periods at the velocity from ``q1`` (the one before)."""
    d = [a - b for a, b in zip(q, q1)]
    dd = sum(x * x for x in d)
    if dd <= 0.0:
        return False
    n = round(sum((p - a) * x for p, a, x in zip(pos, q, d)) / dd)
    return 0 < n < 64 and far(pos, [a + n * x for a, x in zip(q, d)]) <= tol
