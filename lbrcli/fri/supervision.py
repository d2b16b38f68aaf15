"""What the application checks in every monitoring message: is it one a real controller could send, has the robot
side ended the session (safety stop, drives off, POOR quality, leaving COMMANDING_ACTIVE, a period change), and does
the session still hold (``Supervisor``: the controller's clock, our replies reaching it, the robot following)."""

from __future__ import annotations

import math
from operator import le as _le
from operator import sub as _sub
from typing import Any, Sequence

from .constants import ConnectionQuality, DriveState, SafetyState, SessionState

try:  # the per-joint checks compiled (setup.py; without a C compiler the Python below)
    from trajectories import _quick
except ImportError:  # pragma: no cover - a build without a C compiler
    _quick = None
from .outcome import EndReason, Outcome

from .constants import STATE_COMMANDING_ACTIVE as CMD_ACTIVE
from .constants import STATE_COMMANDING_WAIT as CMD_WAIT
from .constants import STATE_IDLE as IDLE

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


if _quick is not None:  # the same, compiled (a fifth of the cost: this runs twice before every reply)
    within = _quick.within  # noqa: F811


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


def robot_side_end(
    mon: Any,
    state: int,
    *,
    seen_session: bool,
    commanding: bool,
    was_active: bool,
    period_key: tuple[int, int] | None,
    waited_s: float,
    commanding_timeout_s: float | None,
) -> End | None:
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
FAST_WINDOW = 10  # messages: a controller whose timestamps run faster than its period is judged over this many …
FAST_RATIO = 0.75  # … as timestamps advancing less than this × steps × period (plus FAST_ALLOWANCE_S) …
FAST_ALLOWANCE_S = 1e-3  # … and below every older on-time message (a late burst catching up is not faster)
RX_WINDOW = 20  # messages: by our clock (the kernel's receive times) it must be more than twice as fast:
RX_RATIO = 0.5  # test controllers that answer in lock-step run somewhat faster than their period
SLOW_WINDOW = 100  # messages: a controller slower than its period (a period change it did not announce) …
SLOW_RATIO = 1.6  # … advances more than this (plus SLOW_ALLOWANCE_S) on its own clock and on ours
SLOW_ALLOWANCE_S = 5e-3
FROZEN_MESSAGES = 10  # a clock with sub-second resolution unchanged over this many messages is frozen
JUMP_S = 0.1  # [s] a timestamp further ahead than the messages explain jumped
_RING = 256
_EPS = 1e-9  # [s] the inline pre-test of a fast clock errs by this toward the full test (rounding aside)


class Supervisor:
    """Per-message checks of a session once its period is known (hot path: a few float operations each).

    - ``clock``: each message's timestamp step against the sequence step × ``send_period_s`` and, with the kernel's
      receive time of the datagram, against our own clock: timestamps that go back, freeze or jump, and a controller
      that sends faster (or much slower) than its period says, are found within ``FAST_WINDOW`` messages (a slower
      one within ``SLOW_WINDOW``) — windows, not sums since the first message, so a change mid-session counts as
      soon as it happens;
    - ``replies``: the reflected sequence counter tells which reply of ours the controller last received; more than
      ``max_reply_gap`` of its messages since then means our commands are not reaching it;
    - ``tracking``: |measured − commanded| per joint within ``max_tracking_error`` [rad] (position mode).
    """

    __slots__ = ("send_period_s", "max_tracking_error", "max_reply_gap", "_ts0", "_seq0", "_ts_last", "_answered",
                 "_reflecting", "largest_tracking_error", "largest_reply_gap", "_seq_last", "_frozen", "_coarse",
                 "_ring_seq", "_ring_ts", "_ring_rx", "_n", "measured_period_s")  # fmt: skip

    def __init__(self, max_tracking_error: Sequence[float], max_reply_gap: int, send_period_s: float) -> None:
        self.send_period_s = send_period_s
        self.max_tracking_error = tuple(max_tracking_error)  # [rad] per joint
        self.max_reply_gap = max_reply_gap  # controller messages
        self._ts0 = -1  # [ns] timestamp of the first message with one
        self._seq0 = 0
        self._ts_last = -1
        self._seq_last = -1
        self._frozen = 0  # messages since the timestamp last changed
        self._coarse = True  # every timestamp so far on a whole second (a coarse clock ticks once a second)
        self._ring_seq = [0] * _RING  # per message: sequence counter, timestamp [ns], kernel receive time [ns]
        self._ring_ts = [0] * _RING
        self._ring_rx = [0] * _RING
        self._n = 0  # messages in the rings
        self._answered = [-1] * _RING  # monitoring sequence counter answered by each of our replies (ring)
        self._reflecting = False  # the controller has been seen reflecting our counter
        self.largest_tracking_error = 0.0  # [rad]
        self.largest_reply_gap = 0  # controller messages
        self.measured_period_s: float | None = None  # [s] set with a "faster than its period" problem

    @classmethod
    def from_limits(cls, velocity_limit: Sequence[float], send_period_s: float, receive_multiplier: int = 1,
                    max_tracking_error: float | None = None, reply_gap_s: float | None = None,
                    tracking_lag_s: float | None = None) -> "Supervisor":  # fmt: skip
        """Defaults: tracking bound = velocity limit × max(``tracking_lag_s`` (20 ms), 8 command periods) per joint;
        reply gap = max(50 ms, 2 command periods + 1 message) in messages."""
        k = max(1, receive_multiplier)
        period = send_period_s * k
        if max_tracking_error is None:
            lag = max(TRACKING_LAG_S if tracking_lag_s is None else tracking_lag_s, 8 * period)
            bound = tuple(v * lag for v in velocity_limit)
        else:
            bound = (max_tracking_error,) * 7
        gap_s = REPLY_GAP_S if reply_gap_s is None else reply_gap_s
        gap = max(2 * k + 1, int(math.ceil(gap_s / send_period_s - 1e-9)))
        return cls(bound, gap, send_period_s)

    def clock(self, seq: int, sec: int, nanosec: int, received_ns: int | None = None) -> str | None:
        """None while the controller's timestamp (``sec``, ``nanosec``) and the kernel's receive time of the message
        (``received_ns`` [ns], or None) agree with the send period."""
        ts = sec * 1_000_000_000 + nanosec
        period = self.send_period_s
        problem = None
        if ts != 0 or self._ts0 >= 0:
            if self._ts0 < 0:
                self._ts0, self._seq0 = ts, seq
            elif self._seq_last >= 0:
                steps = (seq - self._seq_last) & 0xFFFFFFFF
                if nanosec:
                    self._coarse = False
                if ts < self._ts_last:
                    problem = (f"the controller's timestamp went back {(self._ts_last - ts) * 1e-6:.1f} ms: its clock "
                               "is not one a controller has")  # fmt: skip
                elif ts == self._ts_last:
                    self._frozen += steps
                    limit = FROZEN_MESSAGES if not self._coarse else int(1.0 / period) + FROZEN_MESSAGES
                    if self._frozen >= limit:
                        problem = (
                            f"the controller's timestamp stood still over {self._frozen} messages: its clock froze"
                        )
                else:
                    self._frozen = 0
                    ahead = (ts - self._ts_last) * 1e-9 - steps * period
                    if ahead > JUMP_S and not self._coarse:
                        problem = (f"the controller's timestamp jumped {ahead * 1e3:.0f} ms ahead of its "
                                   f"{steps} message(s)")  # fmt: skip
            self._ts_last = ts
        self._seq_last = seq
        k = self._n % _RING
        self._ring_seq[k] = seq
        self._ring_ts[k] = ts
        self._ring_rx[k] = received_ns if received_ns is not None else -1
        self._n += 1
        if problem is None:
            problem = self._rate(seq, ts, received_ns, period)
        return problem

    def _rate(self, seq: int, ts: int, rx: int | None, period: float) -> str | None:
        """The windows: faster than the period on either clock, or much slower on both."""
        n = self._n
        if n > 4:  # from the 5th message on
            # (inline, a test that errs toward the full one in :meth:`_fast`: it is rarely due, and this runs for
            # every message) a timestamp standing still is judged as frozen, not as a fast clock
            ring_seq = self._ring_seq
            if not (self._coarse or self._ts0 < 0 or self._frozen):
                k = (n - 1 - min(n - 1, FAST_WINDOW)) % _RING
                then = self._ring_ts[k]
                if then > 0 and (ts - then) * 1e-9 < ((seq - ring_seq[k]) & 0xFFFFFFFF) * period * FAST_RATIO + _EPS:
                    problem = self._fast("timestamps", seq, ts, self._ring_ts, FAST_WINDOW, FAST_RATIO, period)
                    if problem is not None:
                        return problem
            if rx is not None:
                k = (n - 1 - min(n - 1, RX_WINDOW)) % _RING
                then = self._ring_rx[k]
                if then > 0 and (rx - then) * 1e-9 < ((seq - ring_seq[k]) & 0xFFFFFFFF) * period * RX_RATIO + _EPS:
                    problem = self._fast("messages", seq, rx, self._ring_rx, RX_WINDOW, RX_RATIO, period)
                    if problem is not None:
                        return problem
        if n > SLOW_WINDOW and rx is not None and not self._coarse:
            k = (n - 1 - SLOW_WINDOW) % _RING
            then_ts, then_rx = self._ring_ts[k], self._ring_rx[k]
            if then_rx > 0 and then_ts > 0:
                steps = (seq - self._ring_seq[k]) & 0xFFFFFFFF
                bound = steps * period * SLOW_RATIO + SLOW_ALLOWANCE_S
                if (ts - then_ts) * 1e-9 > bound and (rx - then_rx) * 1e-9 > bound:
                    return (f"the controller sends every {(rx - then_rx) * 1e-6 / steps:.2f} ms over the last "
                            f"{steps} messages, not every {period * 1e3:g} ms as its period says")  # fmt: skip
        return None

    def _fast(self, what: str, seq: int, now: int, ring: list[int], window: int, ratio: float,
              period: float) -> str | None:  # fmt: skip
        """The clock ``ring`` (``what``) advanced faster than the period over the last ``window`` messages."""
        n = self._n
        w = min(n - 1, window)
        k = (n - 1 - w) % _RING
        then = ring[k]
        if then <= 0:
            return None
        steps = (seq - self._ring_seq[k]) & 0xFFFFFFFF
        elapsed = (now - then) * 1e-9
        slack = steps * period * (1.0 - ratio) + FAST_ALLOWANCE_S
        if elapsed < steps * period - slack and self._ahead_of_all(now, seq, ring, w, period, slack):
            self.measured_period_s = max(elapsed / steps, 1e-5)
            return (f"the controller's {what} advanced {elapsed * 1e3:.1f} ms over {steps} messages: it "
                    f"sends every {elapsed / steps * 1e3:.2f} ms, not every {period * 1e3:g} ms as its "
                    "period says")  # fmt: skip
        return None

    def _ahead_of_all(self, now: int, seq: int, ring: list[int], w: int, period: float, slack: float) -> bool:
        """The message at ``now`` [ns] is earlier (relative to the sequence × period grid) than every older message in
        the ring beyond the window ``w`` by more than ``slack`` [s]: the clock really runs fast — a message that was
        late (a stall, then a burst catching up) leaves later ones on the grid, not ahead of it."""
        n = self._n
        mine = now * 1e-9 - ((seq - self._ring_seq[(n - 1) % _RING]) & 0xFFFFFFFF) * period  # = now
        ref_seq = self._ring_seq[(n - 1) % _RING]
        for i in range(w, min(n, _RING)):
            k = (n - 1 - i) % _RING
            t = ring[k]
            if t <= 0:
                continue
            back = (ref_seq - self._ring_seq[k]) & 0xFFFFFFFF  # messages before this one
            if mine - (t * 1e-9 + back * period) >= -slack:  # that older one was as early (or earlier) on the grid
                return False
        return True

    @property
    def reflecting(self) -> bool:
        """The controller has been seen reflecting our sequence counter."""
        return self._reflecting

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
        if _quick is not None:  # compiled: the largest error when every joint is within its bound
            worst = _quick.worst(measured, command, self.max_tracking_error)
            if worst >= 0.0:
                if worst > self.largest_tracking_error:
                    self.largest_tracking_error = worst
                return None
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
              command: Sequence[float], last_sent: int, received_ns: int | None = None) -> str | None:  # fmt: skip
        """All checks due for this message (``received_ns``: the kernel's receive time [ns], or None): the clock always; with ``commanding`` (COMMANDING_ACTIVE, not braking)
        the replies, and with ``moving`` in position mode the tracking of ``command`` [rad]. The first problem."""
        ts = mon.monitorData.timestamp
        problem = self.clock(seq, ts.sec, ts.nanosec, received_ns)
        if problem is None and commanding:
            problem = self.replies(seq, mon.header.reflectedSequenceCounter, last_sent)
            if problem is None and moving and position_mode:
                problem = self.tracking(mon.monitorData.measuredJointPosition.value, command)
        return problem
