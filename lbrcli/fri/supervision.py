"""What the application checks in every monitoring message: is it one a real controller could send, has the robot
side ended the session (safety stop, drives off, POOR quality, leaving COMMANDING_ACTIVE, a period change), and does
the session still hold (``Supervisor``: the controller's clock, our replies reaching it, the robot following)."""

from __future__ import annotations

import math
from operator import le as _le
from operator import sub as _sub
from typing import Any, Sequence

from .constants import ConnectionQuality, DriveState, SafetyState, SessionState
from .outcome import EndReason, Outcome

IDLE, CMD_WAIT, CMD_ACTIVE = 0, 3, 4
_DRIVE_ACTIVE = int(DriveState.ACTIVE)
_POOR = int(ConnectionQuality.POOR)
POSITION_SLACK = 0.05  # [rad] a reported position beyond the limits by more than this is not a real robot's

End = tuple[Outcome, EndReason, str]


def joint_bound(position_limit: Sequence[float]) -> tuple[float, ...]:
    """The largest |joint value| [rad] a real robot reports: the position limits plus a small slack."""
    return tuple(float(p) + POSITION_SLACK for p in position_limit)


def within(values: Sequence[float], bound: Sequence[float]) -> bool:
    """7 joint values with |value| ≤ ``bound`` [rad] (:func:`joint_bound`); NaN and inf compare False."""
    # hot path, before every reply: C-level loops straight over the message's values
    return len(values) == 7 and all(map(_le, map(abs, values), bound))


def joints_ok(values: Sequence[float], position_limit: Sequence[float]) -> bool:
    """7 finite joint values [rad] within the position limits (plus a small slack)."""
    return within(values, joint_bound(position_limit))


def consistent(mon: Any, bound: Sequence[float]) -> bool:
    """A message a real controller could have sent: connection info, 7 finite joint values where the state needs
    them, |positions| ≤ ``bound`` (:func:`joint_bound`)."""
    if not mon.HasField("connectionInfo"):
        return False
    state = mon.connectionInfo.sessionState
    if state == IDLE:
        return True
    if not within(mon.monitorData.measuredJointPosition.value, bound):
        return False
    return state < CMD_WAIT or within(mon.ipoData.jointPosition.value, bound)


def robot_side_end(mon: Any, state: int, *, seen_session: bool, commanding: bool, was_active: bool,
                   period_key: tuple[int, int] | None, waited_s: float, commanding_timeout_s: float | None) -> End | None:
    """Why the robot side ended the session with this message (None: it did not). ``waited_s`` [s] since the
    first message, for ``commanding_timeout_s``."""
    if state == IDLE:
        if seen_session:
            return Outcome.STOPPED, EndReason.IDLE, "the robot application closed the FRI session (IDLE)"
        return None
    if commanding or state >= CMD_WAIT:
        return commanding_end(mon, state, was_active, period_key)
    if commanding_timeout_s is not None and waited_s > commanding_timeout_s:
        return (Outcome.STOPPED, EndReason.NO_COMMANDING, f"the robot application did not start commanding within "
                f"{commanding_timeout_s:g} s (session state {SessionState(state).name})")  # fmt: skip
    return None


def commanding_end(mon: Any, state: int, was_active: bool, period_key: tuple[int, int] | None) -> End | None:
    """Why the robot side ended a commanding session with this message (state not IDLE), or None."""
    ci = mon.connectionInfo
    ri = mon.robotInfo
    if (ci.sendPeriod, ci.receiveMultiplier or 1) != period_key:
        pk = period_key or (0, 1)
        return (Outcome.STOPPED, EndReason.PERIOD_CHANGED, f"the controller changed its period from {pk[0]} ms × "
                f"{pk[1]} to {ci.sendPeriod} ms × {ci.receiveMultiplier or 1}")  # fmt: skip
    if ri.safetyState != 0:
        return Outcome.STOPPED, EndReason.SAFETY_STOP, f"safety stop ({SafetyState(ri.safetyState).name})"
    drives = ri.driveState
    if drives and min(drives) != _DRIVE_ACTIVE:
        return Outcome.STOPPED, EndReason.DRIVES_OFF, "drives not active"
    if ci.quality == _POOR:
        return Outcome.STOPPED, EndReason.QUALITY_POOR, "connection quality POOR"
    if was_active and state != CMD_ACTIVE:
        return (Outcome.STOPPED, EndReason.LEFT_COMMANDING,
                f"the session left COMMANDING_ACTIVE ({SessionState(state).name})")  # fmt: skip
    return None


# -- supervision of a commanding session --------------------------------------------------------------------------
TRACKING_LAG_S = 0.02  # [s] the lag the default tracking bound allows at full speed (at least 8 command periods)
REPLY_GAP_S = 0.05  # [s] the default: longest time the controller may go without receiving a reply of ours
CLOCK_SLACK = 0.1  # relative: timestamps may run this much slower than sequence × send period before we object
_RING = 256


class Supervisor:
    """Per-message checks of a session once its period is known (hot path: a few float operations each).

    - ``clock``: the controller's timestamps must advance by at least ``send_period_s`` per sequence step (less
      means the controller really runs faster than it says, and every step would be executed faster);
    - ``replies``: the reflected sequence counter tells which reply of ours the controller last received; more than
      ``max_reply_gap`` of its messages since then means our commands are not reaching it;
    - ``tracking``: |measured − commanded| per joint within ``max_tracking_error`` [rad] (position mode).
    """

    __slots__ = ("send_period_s", "max_tracking_error", "max_reply_gap", "_ts0", "_seq0", "_ts_last", "_answered",
                 "_reflecting", "largest_tracking_error", "largest_reply_gap")  # fmt: skip

    def __init__(self, max_tracking_error: Sequence[float], max_reply_gap: int, send_period_s: float) -> None:
        self.send_period_s = send_period_s
        self.max_tracking_error = tuple(max_tracking_error)  # [rad] per joint
        self.max_reply_gap = max_reply_gap  # controller messages
        self._ts0 = -1  # [ns] timestamp of the first message
        self._seq0 = 0
        self._ts_last = -1
        self._answered = [-1] * _RING  # monitoring sequence counter answered by each of our replies (ring)
        self._reflecting = False  # the controller has been seen reflecting our counter
        self.largest_tracking_error = 0.0  # [rad]
        self.largest_reply_gap = 0  # controller messages

    @classmethod
    def from_limits(cls, velocity_limit: Sequence[float], send_period_s: float, receive_multiplier: int = 1,
                    max_tracking_error: float | None = None, reply_gap_s: float | None = None) -> "Supervisor":
        """Defaults: tracking bound = velocity limit × max(20 ms, 8 command periods) per joint; reply gap =
        max(50 ms, 2 command periods + 1 message) in messages."""
        k = max(1, receive_multiplier)
        period = send_period_s * k
        if max_tracking_error is None:
            lag = max(TRACKING_LAG_S, 8 * period)
            bound = tuple(v * lag for v in velocity_limit)
        else:
            bound = (max_tracking_error,) * 7
        gap_s = REPLY_GAP_S if reply_gap_s is None else reply_gap_s
        gap = max(2 * k + 1, int(math.ceil(gap_s / send_period_s - 1e-9)))
        return cls(bound, gap, send_period_s)

    def clock(self, seq: int, sec: int, nanosec: int) -> str | None:
        """None while the timestamps agree with the send period (evaluated when the timestamp changes)."""
        ts = sec * 1_000_000_000 + nanosec
        if ts == self._ts_last:
            return None  # no timestamps, or a coarse clock between ticks: nothing to judge
        self._ts_last = ts
        if self._ts0 < 0 or ts == 0:
            self._ts0, self._seq0 = ts, seq
            return None
        # cumulative from the first message: a late first message or a controller catching up cannot trip it
        steps = (seq - self._seq0) & 0xFFFFFFFF
        expected = steps * self.send_period_s  # [s]
        elapsed = (ts - self._ts0) * 1e-9
        slack = max(3 * self.send_period_s, 0.02)
        if elapsed < expected * (1.0 - CLOCK_SLACK) - slack:
            return (f"the controller's timestamps advanced {elapsed * 1e3:.1f} ms over {steps} messages: it sends every "
                    f"{elapsed / steps * 1e3:.2f} ms, not every {self.send_period_s * 1e3:g} ms as its period says")  # fmt: skip
        return None

    def sent(self, client_seq: int, answered_seq: int) -> None:
        """Our reply ``client_seq`` answered the monitoring message ``answered_seq``."""
        self._answered[client_seq % _RING] = answered_seq

    def replies(self, seq: int, reflected: int, last_sent: int) -> str | None:
        """None while the controller keeps receiving our replies (``reflected``: its echo of our counter)."""
        if not self._reflecting:
            if reflected == 0 or last_sent < 0:
                return None  # 0 is also "nothing reflected yet": judge once the controller has echoed a later one
            self._reflecting = True
        behind = (last_sent - reflected) & 0xFFFFFFFF
        if behind >= _RING:
            return (f"the controller reflects our reply {reflected}, {behind} replies behind the last one sent: "
                    "our commands are not reaching it")  # fmt: skip
        answered = self._answered[reflected % _RING]
        if answered < 0:
            return None
        gap = ((seq - answered) & 0xFFFFFFFF) - 1  # its messages since the one our received reply answered
        if gap > self.largest_reply_gap:
            self.largest_reply_gap = gap
        if gap > self.max_reply_gap:
            return (f"replies lost: the controller received none of our last {behind} replies over {gap} of its "
                    f"messages ({gap * self.send_period_s * 1e3:.0f} ms)")  # fmt: skip
        return None

    def tracking(self, measured: Sequence[float], command: Sequence[float]) -> str | None:
        """None while every joint's measured position [rad] is within the bound of the command in force."""
        errors = tuple(map(abs, map(_sub, measured, command)))  # C-level: the hot path of every message
        worst = max(errors)
        if not all(map(_le, errors, self.max_tracking_error)):  # NaN too
            for j, (e, bound) in enumerate(zip(errors, self.max_tracking_error)):
                if not e <= bound:
                    self.largest_tracking_error = max(self.largest_tracking_error, e)
                    return (f"A{j + 1} measured {measured[j]:.4f} rad is {e:.4f} rad from the command {command[j]:.4f} "
                            f"rad (bound {bound:.4f} rad): the robot does not follow, or was pushed")  # fmt: skip
        if worst > self.largest_tracking_error:
            self.largest_tracking_error = worst
        return None

    def check(self, mon: Any, seq: int, commanding: bool, moving: bool, position_mode: bool,
              command: Sequence[float], last_sent: int) -> str | None:  # fmt: skip
        """All checks due for this message: the clock always; with ``commanding`` (COMMANDING_ACTIVE, not braking)
        the replies, and with ``moving`` in position mode the tracking of ``command`` [rad]. The first problem."""
        ts = mon.monitorData.timestamp
        problem = self.clock(seq, ts.sec, ts.nanosec)
        if problem is None and commanding:
            problem = self.replies(seq, mon.header.reflectedSequenceCounter, last_sent)
            if problem is None and moving and position_mode:
                problem = self.tracking(mon.monitorData.measuredJointPosition.value, command)
        return problem
