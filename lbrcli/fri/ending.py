"""How a session ends, mixed into :class:`~lbrcli.fri.application.ClientApplication`: client-side stops (a braking
stop when the robot was being commanded), the client's own end or error, time-outs, failing observers, and the
final :class:`~lbrcli.fri.outcome.SessionResult` handed to the observers."""

from __future__ import annotations

import time
from typing import Any

from .clock import SessionClock
from .cycle import Observer
from .constants import SessionState
from .errors import FriError, FriTimeout, StopSession
from .motion import ExecutedMotion
from .outcome import EndReason, Outcome, SessionResult, session_result
from .supervision import robot_side_end
from .transport import no_message_text

from .constants import STATE_COMMANDING_ACTIVE as CMD_ACTIVE, STATE_COMMANDING_WAIT as CMD_WAIT, STATE_IDLE as IDLE


class SessionEnding:
    """The stop and end paths of the application (state it reads is set by the application)."""

    client: Any
    observers: list[Observer]
    result: SessionResult | None
    error: BaseException | None
    transport: Any
    version: Any
    malformed: int
    cycles: int
    _clock: SessionClock
    _motion: ExecutedMotion | None
    _stop: tuple[Outcome, EndReason, str] | None
    _ended: bool
    _cpu0: float
    _cycles0: int
    _answered_any: bool
    _unanswered_at_start: int
    send_period_s: float | None
    _last_state: int
    _interrupt: EndReason | None
    watchdog: Any
    states_seen: list[int]
    cycle: Any

    def _moving(self) -> bool:
        """Commands were sent in COMMANDING_ACTIVE and the robot was last seen there: a stop must brake."""
        return self._last_state == CMD_ACTIVE and self._motion is not None and self._motion.moving

    # -- stops -----------------------------------------------------------------------------------------------
    def _stop_braking(self, outcome: Outcome, reason: EndReason, text: str) -> None:
        """Remember the first stop of the session; brake when commanding (else it ends before the next answer)."""
        if self._stop is not None:
            return
        self._stop = (outcome, reason, text)
        if self._moving():
            self._motion.begin_braking()  # type: ignore[union-attr]

    def _check_send_period(self, send_period_ms: int) -> None:
        """A controller at another send period than ``send_period_s`` ends the session before it commands (BAD_INPUT)."""
        if self.send_period_s is not None and abs(send_period_ms * 1e-3 - self.send_period_s) > 1e-9:
            self._stop_braking(Outcome.REFUSED, EndReason.BAD_INPUT,
                               f"the controller's send period is {send_period_ms} ms, not the {self.send_period_s * 1e3:g} ms "
                               "asked; set it in the robot's FRI configuration or ask for that period")  # fmt: skip

    def _request_stop(self, outcome: Outcome, reason: EndReason, text: str) -> bool:
        """Remember a client-side stop; brake when commanding. True if the session ended at once."""
        self._stop = (outcome, reason, text)
        if self._moving():
            self._motion.begin_braking()  # type: ignore[union-attr]
            return False
        self._finish(outcome, reason, text)
        return True

    def _call_client(self, method: str, *args: Any, on: Any = None) -> Any:
        """The client's (or ``on``'s: the transformation client's) ``method``; its StopSession or exception becomes
        the session's (braking) stop."""
        try:
            return getattr(self.client if on is None else on, method)(*args)
        except StopSession as s:
            outcome = Outcome.COMPLETED if s.completed else Outcome.REFUSED
            reason = (
                EndReason.FINISHED
                if s.completed
                else (EndReason.BAD_INPUT if s.bad_input else EndReason.CLIENT_REFUSED)
            )
            self._stop_braking(outcome, reason, s.reason)  # the first stop of the session counts
        except Exception as exc:  # noqa: BLE001 - a client bug ends the session, reported
            if self._stop is None:
                self.error = exc
                self._stop_braking(Outcome.FAILED, EndReason.CLIENT_ERROR,
                                   f"the client's {method} raised {type(exc).__name__}: {exc}")  # fmt: skip
        return None

    def _check_clocks(self, now: float) -> bool:
        """Time-outs and the monitoring duration; False once the session ended."""
        if self._ended:
            return False
        expired = self._clock.expired(now, self._stop is not None)
        if expired is None:
            return True
        what, seconds = expired
        if what == "first":
            self._ended = True
            version = f"FRI {self.version.value}" if self.version else "any FRI version"
            raise FriTimeout(no_message_text(self.transport, seconds, self.malformed, version))  # type: ignore[arg-type]
        if what == "silent":
            self._finish(Outcome.STOPPED, EndReason.SILENT, f"the controller was silent for {seconds:.2f} s")
            return False
        return not self._request_stop(Outcome.COMPLETED, EndReason.DURATION, f"monitored for {seconds:g} s")

    # -- observers and the end -------------------------------------------------------------------------------
    def _call_observer(self, o: Observer, method: str, *args: Any) -> None:
        fn = getattr(o, method, None)
        if fn is not None:
            try:
                fn(*args)
            except Exception as exc:  # noqa: BLE001 - e.g. the log's disk is full: stop safely, say why
                self._observer_failed(o, exc, ending=method == "on_end")

    def _observe(self) -> None:
        for o in self.observers:
            fn = getattr(o, "on_cycle", None)
            if fn is not None:
                try:
                    fn(self)
                except Exception as exc:  # noqa: BLE001
                    self._observer_failed(o, exc)
                    break

    def _observer_failed(self, o: Observer, exc: BaseException, ending: bool = False) -> None:
        """Drop the observer; unless the session is ending anyway, stop (braking when commanding) and say why."""
        if o in self.observers:
            self.observers.remove(o)
        if ending or self._stop is not None or self._ended:
            return
        self.error = exc
        self._request_stop(
            Outcome.FAILED, EndReason.OBSERVER_FAILED, f"{getattr(o, 'name', type(o).__name__)} failed: {exc}"
        )

    def _finish(self, outcome: Outcome, reason: EndReason, text: str, observe: bool = False) -> None:
        """End the session; with ``observe`` the observers see this cycle first (its log row, its figures)."""
        if self._ended:
            return
        self._ended = True
        if observe:
            self._observe()
        figures: dict[str, Any] = {}
        for o in list(self.observers):
            fn = getattr(o, "figures", None)
            if fn is not None:
                try:
                    figures.update(fn())
                except Exception:  # noqa: BLE001 - a figure less, the session's end is what matters
                    pass
        cpu = time.thread_time() - self._cpu0 if self._clock.t_first is not None else 0.0
        self.result = session_result(
            self, outcome, reason, text, figures, cpu_s=cpu, cpu_cycles=self.cycles - self._cycles0,
            unanswered_at_start=self._unanswered_at_start if self._answered_any else 0,
        )  # fmt: skip
        for o in list(self.observers):
            self._call_observer(o, "on_end", self, self.result)

    def _stop_on_interrupt(self) -> bool:
        """Turn a pending interrupt (Ctrl-C, SIGTERM) into a stop; True if that ended the session at once."""
        text = "interrupted (Ctrl-C)" if self._interrupt is EndReason.SIGINT else "terminated (SIGTERM)"
        return self._request_stop(Outcome.INTERRUPTED, self._interrupt, text)  # type: ignore[arg-type]

    def _on_silence(self, t_wait: float, now: float) -> bool:
        """A receive timeout: the controller is quiet since ``t_wait`` [s]; the watchdog may end the session."""
        if self._clock.quiet_from is None:
            self._clock.quiet_from = t_wait
        self._prepared = None
        if self.watchdog is not None:
            problem = self.watchdog()
            if problem:
                self._ended = True
                raise FriError(problem)
        return self._check_clocks(now)

    def _robot_side(self, mon: Any, state: int, now: float) -> bool | None:
        """The session state as the robot reports it: state changes (told to the client), the robot side's ends,
        IDLE (observed, not answered). The step's result when the cycle ends here, else None."""
        if not self.states_seen or state != self.states_seen[-1]:
            self.states_seen.append(state)
        if state != self._last_state:
            old, self._last_state = self._last_state, state
            self._call_client("on_state_change", SessionState(old), SessionState(state))
        clock = self._clock
        end = robot_side_end(mon, state, seen_session=self._seen_session, commanding=self._commanding,
                             was_active=self._was_active, period_key=clock.period_key, waited_s=now - clock.t_first,  # type: ignore[operator]
                             commanding_timeout_s=self.commanding_timeout_s)  # fmt: skip
        if end is not None:
            self._finish(*end, observe=True)
            return False
        if state == IDLE:
            if not self._seen_session:
                self.cycle.command = tuple(mon.monitorData.measuredJointPosition.value)
            self._observe()
            return self._check_clocks(now)
        self._seen_session = True
        if state >= CMD_WAIT:
            self._commanding = True
        if state == CMD_ACTIVE:
            self._was_active = True
            self.active_cycles += 1
        return None
