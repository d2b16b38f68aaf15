"""Session logic of the simulated FRI controller: connection quality from the client's timing and the state machine.

Pure logic, no sockets: the simulator feeds one verdict per cycle (was the cycle covered by a timely reply?)
and the command consistency; this module answers the connection quality and the session state.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..constants import ConnectionQuality, SessionState


@dataclass(frozen=True)
class QualityThresholds:
    """Quality from the share of timely cycles in a sliding window of ``window`` cycles (ratios 0..1)."""

    window: int = 50  # [cycles]
    fair: float = 0.5  # share of timely cycles for FAIR
    good: float = 0.9  # ... for GOOD (commanding allowed)
    excellent: float = 0.98  # ... for EXCELLENT


class QualityMonitor:
    """Sliding window of per-cycle timeliness verdicts (starts empty = all late, so quality starts POOR)."""

    def __init__(self, thresholds: QualityThresholds = QualityThresholds()) -> None:
        self.t = thresholds
        self._ring = bytearray(max(1, thresholds.window))
        self._i = 0
        self._sum = 0

    def push(self, timely: bool) -> ConnectionQuality:
        """Record one cycle and return the quality over the window."""
        v = 1 if timely else 0
        self._sum += v - self._ring[self._i]
        self._ring[self._i] = v
        self._i = (self._i + 1) % len(self._ring)
        return self.quality

    @property
    def ratio(self) -> float:
        return self._sum / len(self._ring)

    @property
    def quality(self) -> ConnectionQuality:
        r = self.ratio
        if r >= self.t.excellent:
            return ConnectionQuality.EXCELLENT
        if r >= self.t.good:
            return ConnectionQuality.GOOD
        if r >= self.t.fair:
            return ConnectionQuality.FAIR
        return ConnectionQuality.POOR


class EndReason:
    """Why the robot application ended the session (strings for the stats)."""

    NONE = ""
    DURATION = "duration"  # session_duration_s of COMMANDING_ACTIVE elapsed
    QUALITY = "quality"  # quality dropped below GOOD while commanding
    SAFETY = "safety_stop"  # command outside the position limits
    COMMAND_MISSING = "command_missing"  # a reply in COMMANDING_ACTIVE without the 7 joint positions (or pose)
    CARTESIAN_REFUSED = "cartesian_refused"  # a Cartesian pose the controller cannot execute (unreachable, a jump)


@dataclass(frozen=True)
class SessionTiming:
    """When the simulated robot application moves between states [s] and how many cycles it waits."""

    commanding_after_s: float = 0.2  # from the first MONITORING_READY until the overlay starts (needs quality GOOD)
    wait_cycles: int = 10  # consistent (mirroring) commands in COMMANDING_WAIT before ACTIVE
    session_duration_s: float | None = None  # COMMANDING_ACTIVE length (None: until the client stops); without
    # the overlay: the application's run time from the first MONITORING_READY (quality changes do not restart it)
    end_delay_s: float = 0.1  # monitoring after the overlay ended, before IDLE
    idle_messages: int = 3  # IDLE messages sent before the simulator stops (also when it is stopped: ``close``)
    overlay: bool = True  # False: the application only monitors (no COMMANDING states)

    @classmethod
    def of(cls, cfg) -> "SessionTiming":
        """The timing fields of a :class:`~lbrcli.fri.sim.SimConfig` (same names)."""
        return cls(**{f: getattr(cfg, f) for f in cls.__dataclass_fields__})


class SessionMachine:
    """The controller's FRI session state, advanced once per cycle at time ``now`` [s].

    The robot application's time line starts when the session first reaches MONITORING_READY (KUKA's
    ``FRISession.await()`` returns): the overlay start and, without an overlay, the session's end count from there,
    not from the latest MONITORING_WAIT → MONITORING_READY change (the quality flips under load). With an overlay
    the duration is COMMANDING_ACTIVE time, which happens once: leaving it ends the session.
    """

    def __init__(self, timing: SessionTiming = SessionTiming()) -> None:
        self.timing = timing
        self.state = SessionState.MONITORING_WAIT
        self.end_reason = EndReason.NONE
        self._opened: float | None = None  # first MONITORING_READY [s]
        self._since = 0.0  # COMMANDING_ACTIVE started [s]
        self._consistent = 0
        self._ending_since: float | None = None
        self._idle_sent = 0

    @property
    def finished(self) -> bool:
        """True once all IDLE messages have been sent."""
        return self.state is SessionState.IDLE and self._idle_sent >= self.timing.idle_messages

    def note_idle_sent(self) -> None:
        self._idle_sent += 1

    def close(self) -> None:
        """The robot application ends now (stopped, timed out): IDLE from the next cycle on, ``finished`` after the
        ``idle_messages`` of a normal ending. Keeps ``end_reason`` (the caller knows why)."""
        self.state = SessionState.IDLE
        self._ending_since = None

    def _end(self, now: float, reason: str, state: SessionState) -> None:
        self.end_reason = reason
        self._ending_since = now
        self.state = state

    def advance(self, now: float, quality: ConnectionQuality, mirror_ok: bool | None, safety_stop: bool,
                command_missing: bool = False, command_refused: bool = False) -> SessionState:  # fmt: skip
        """New state after a cycle. ``mirror_ok``: this cycle's command mirrored ipo (None: no command);
        ``command_missing``: a reply to a COMMANDING_ACTIVE message carried no joint positions (an error: the overlay
        ends, the robot stops); ``command_refused``: a Cartesian pose could not be executed (the same)."""
        s = self.state
        good = quality >= ConnectionQuality.GOOD
        if s is SessionState.IDLE:
            return s
        if self._ending_since is not None:  # the robot application is closing the session
            self.state = SessionState.MONITORING_READY if good else SessionState.MONITORING_WAIT
            if now - self._ending_since >= self.timing.end_delay_s:
                self.state = SessionState.IDLE
            return self.state
        if s is SessionState.MONITORING_WAIT or s is SessionState.MONITORING_READY:
            if good and self._opened is None:
                self._opened = now
            self.state = SessionState.MONITORING_READY if good else SessionState.MONITORING_WAIT
            run = -1.0 if self._opened is None else now - self._opened  # the application's run time [s]
            if not self.timing.overlay:
                if self.timing.session_duration_s is not None and run >= self.timing.session_duration_s:
                    self._end(now, EndReason.DURATION, self.state)
            elif s is SessionState.MONITORING_READY and good and run >= self.timing.commanding_after_s:
                self.state, self._consistent = SessionState.COMMANDING_WAIT, 0
        elif s is SessionState.COMMANDING_WAIT:
            if not good:
                self._end(now, EndReason.QUALITY, SessionState.MONITORING_WAIT)
            elif mirror_ok is not None:
                self._consistent = self._consistent + 1 if mirror_ok else 0
                if self._consistent >= self.timing.wait_cycles:
                    self.state, self._since = SessionState.COMMANDING_ACTIVE, now
        elif s is SessionState.COMMANDING_ACTIVE:
            if safety_stop:
                self._end(
                    now, EndReason.SAFETY, SessionState.MONITORING_READY if good else SessionState.MONITORING_WAIT
                )
            elif command_missing or command_refused:
                self._end(
                    now,
                    EndReason.COMMAND_MISSING if command_missing else EndReason.CARTESIAN_REFUSED,
                    SessionState.MONITORING_READY if good else SessionState.MONITORING_WAIT,
                )
            elif not good:
                self._end(now, EndReason.QUALITY, SessionState.MONITORING_WAIT)
            elif self.timing.session_duration_s is not None and now - self._since >= self.timing.session_duration_s:
                self._end(now, EndReason.DURATION, SessionState.MONITORING_READY)
        return self.state
