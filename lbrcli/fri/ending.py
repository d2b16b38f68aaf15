"""How a session ends, a collaborator of :class:`~lbrcli.fri.application.ClientApplication`: the session states the
robot reports and the ends on its side, the stops the client side asks for (the first counts; a braking stop when
the robot was being commanded), the client's callbacks, whose ``StopSession`` or exception becomes such a stop, the
observers (one that fails is dropped and stops the session) and the final
:class:`~lbrcli.fri.outcome.SessionResult` handed to them."""

from __future__ import annotations

import time
from typing import Any

from .clock import SessionClock
from .constants import SessionState
from .cycle import Observer
from .errors import FriTimeout, StopSession
from .motion import ExecutedMotion
from .outcome import EndReason, Outcome, SessionResult, session_result
from .supervision import End, robot_side_end
from .transport import no_message_text

from .constants import STATE_COMMANDING_ACTIVE as CMD_ACTIVE, STATE_COMMANDING_WAIT as CMD_WAIT, STATE_IDLE as IDLE


class SessionEnding:
    """The ends of one session for ``client`` (``commanding_timeout_s`` [s]: the longest wait in COMMANDING_WAIT,
    None: no limit) and its ``observers``. ``motion`` is the executed motion once the period is known: what a stop
    brakes. The methods that end the session take the application (``app``): the observers are told of it and the
    result holds its counters."""

    def __init__(self, client: Any, observers: list[Observer], commanding_timeout_s: float | None = None) -> None:
        self.client = client
        self.observers = observers  # the application's list (an observer that fails is dropped from it)
        self.commanding_timeout_s = commanding_timeout_s
        self.motion: ExecutedMotion | None = None
        self.stop: End | None = None  # the stop the client side asked for (the first counts)
        self.error: BaseException | None = None  # a client callback's or observer's exception, if one ended it
        self.ended = False
        self.result: SessionResult | None = None
        self.cpu0: float | None = None  # [s] the thread's CPU time at the first message (the result's CPU figure)
        self.states_seen: list[int] = []
        self.last_state = IDLE  # the session state of the last accepted message
        self.seen_session = False  # a message outside IDLE was seen
        self.commanding = False  # ... in a commanding state
        self.was_active = False  # ... in COMMANDING_ACTIVE

    def moving(self) -> bool:
        """Commands were sent in COMMANDING_ACTIVE and the robot was last seen there: a stop must brake."""
        return self.last_state == CMD_ACTIVE and self.motion is not None and self.motion.moving

    # -- stops the client side asks for ---------------------------------------------------------------------------
    def stop_braking(self, outcome: Outcome, reason: EndReason, text: str) -> None:
        """Remember the first stop of the session; brake when commanding (else it ends before the next answer)."""
        if self.stop is not None:
            return
        self.stop = (outcome, reason, text)
        if self.moving():
            self.motion.begin_braking()  # type: ignore[union-attr]

    def interrupted(self, app: Any, reason: EndReason) -> bool:
        """An interrupt (Ctrl-C: SIGINT, SIGTERM) as the stop in force; True if that ended the session at once."""
        text = "interrupted (Ctrl-C)" if reason is EndReason.SIGINT else "terminated (SIGTERM)"
        return self.request_stop(app, Outcome.INTERRUPTED, reason, text)

    def check_send_period(self, send_period_ms: int, asked_s: float | None) -> None:
        """A controller at another send period than ``asked_s`` [s] ends the session before it commands (BAD_INPUT)."""
        if asked_s is not None and abs(send_period_ms * 1e-3 - asked_s) > 1e-9:
            self.stop_braking(Outcome.REFUSED, EndReason.BAD_INPUT,
                              f"the controller's send period is {send_period_ms} ms, not the {asked_s * 1e3:g} ms "
                              "asked; set it in the robot's FRI configuration or ask for that period")  # fmt: skip

    def call(self, method: str, *args: Any, on: Any = None) -> Any:
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
            self.stop_braking(outcome, reason, s.reason)  # the first stop of the session counts
        except Exception as exc:  # noqa: BLE001 - a client bug ends the session, reported
            if self.stop is None:
                self.error = exc
                self.stop_braking(Outcome.FAILED, EndReason.CLIENT_ERROR,
                                  f"the client's {method} raised {type(exc).__name__}: {exc}")  # fmt: skip
        return None

    def ask_client(self, state: int, motion: ExecutedMotion | None, cmd: Any, tc: Any, cyc: Any) -> End | None:
        """The client's callback for ``state`` into the cleared command ``cmd`` (none while ``motion`` brakes), then
        the transformation client ``tc``'s ``provide`` (if any); the stop that ends the session here (nothing to
        answer: a stop asked for outside COMMANDING_ACTIVE or before anything moved), or None."""
        cmd.reset()
        client = self.client
        braking = motion is not None and motion.braking
        client.braking = braking
        if self.stop is not None and (not braking or state != CMD_ACTIVE):
            return self.stop
        if not braking:
            if state == CMD_ACTIVE:
                q = self.call("command", client.robot_state)
                if q is not None:
                    cmd.set_joint_position(q)
            else:
                self.call("wait_for_command" if state == CMD_WAIT else "monitor", client.robot_state)
            if self.stop is not None and not (motion is not None and motion.braking):
                return self.stop
        if tc is not None:  # its provide() for this message (values kept for the reply)
            tc.robot_state = client.robot_state
            tc.values.clear()
            self.call("provide", on=tc)
        cyc.phase = client.phase
        cyc.row = client.row
        return None

    # -- the robot side ----------------------------------------------------------------------------------------
    def robot_side(self, mon: Any, state: int, period_key: tuple[int, int] | None, waited_s: float) -> End | None:
        """The session ``state`` of an accepted message (a change is told to the client): the robot side's end
        with it (``waited_s`` [s] since the first message), or None."""
        seen = self.states_seen
        if not seen or state != seen[-1]:
            seen.append(state)
        if state != self.last_state:
            old, self.last_state = self.last_state, state
            self.call("on_state_change", SessionState(old), SessionState(state))
        end = robot_side_end(mon, state, seen_session=self.seen_session, commanding=self.commanding,
                             was_active=self.was_active, period_key=period_key, waited_s=waited_s,
                             commanding_timeout_s=self.commanding_timeout_s)  # fmt: skip
        if end is None and state != IDLE:
            self.seen_session = True
            if state >= CMD_WAIT:
                self.commanding = True
            if state == CMD_ACTIVE:
                self.was_active = True
        return end

    def check_clocks(self, app: Any, clock: SessionClock, now: float) -> bool:
        """``app``'s time-outs and monitoring duration on its ``clock`` at ``now`` [s]; False once the session ended
        (:class:`~lbrcli.fri.errors.FriTimeout` when no message came at all)."""
        if self.ended:
            return False
        expired = clock.expired(now, self.stop is not None)
        if expired is None:
            return True
        what, seconds = expired
        if what == "first":
            self.ended = True
            version = f"FRI {app.version.value}" if app.version else "any FRI version"
            raise FriTimeout(no_message_text(app.transport, seconds, app.malformed, version))
        if what == "silent":
            self.finish(app, Outcome.STOPPED, EndReason.SILENT, f"the controller was silent for {seconds:.2f} s")
            return False
        return not self.request_stop(app, Outcome.COMPLETED, EndReason.DURATION, f"monitored for {seconds:g} s")

    # -- observers and the end -------------------------------------------------------------------------------
    def call_observer(self, app: Any, o: Observer, method: str, *args: Any) -> None:
        """``o``'s ``method`` (if it has one); a failure drops it and stops the session (:meth:`_observer_failed`)."""
        fn = getattr(o, method, None)
        if fn is not None:
            try:
                fn(*args)
            except Exception as exc:  # noqa: BLE001 - e.g. the log's disk is full: stop safely, say why
                self._observer_failed(app, o, exc, ending=method == "on_end")

    def observe(self, app: Any) -> None:
        """Every observer's ``on_cycle(app)``, after the reply went out."""
        for o in self.observers:
            fn = getattr(o, "on_cycle", None)
            if fn is not None:
                try:
                    fn(app)
                except Exception as exc:  # noqa: BLE001
                    self._observer_failed(app, o, exc)
                    break

    def _observer_failed(self, app: Any, o: Observer, exc: BaseException, ending: bool = False) -> None:
        """Drop the observer; unless the session is ending anyway, stop (braking when commanding) and say why."""
        if o in self.observers:
            self.observers.remove(o)
        if ending or self.stop is not None or self.ended:
            return
        self.error = exc
        self.request_stop(app, Outcome.FAILED, EndReason.OBSERVER_FAILED,
                          f"{getattr(o, 'name', type(o).__name__)} failed: {exc}")  # fmt: skip

    def request_stop(self, app: Any, outcome: Outcome, reason: EndReason, text: str) -> bool:
        """Make this the stop in force: brake when commanding, else end ``app``'s session at once (True)."""
        self.stop = (outcome, reason, text)
        if self.moving():
            self.motion.begin_braking()  # type: ignore[union-attr]
            return False
        self.finish(app, outcome, reason, text)
        return True

    def finish(self, app: Any, outcome: Outcome, reason: EndReason, text: str, observe: bool = False) -> None:
        """End ``app``'s session; with ``observe`` the observers see this cycle first (its log row, its figures)."""
        if self.ended:
            return
        self.ended = True
        if observe:
            self.observe(app)
        figures: dict[str, Any] = {}
        for o in list(self.observers):
            fn = getattr(o, "figures", None)
            if fn is not None:
                try:
                    figures.update(fn())
                except Exception:  # noqa: BLE001 - a figure less, the session's end is what matters
                    pass
        cpu = time.thread_time() - self.cpu0 if self.cpu0 is not None else 0.0
        self.result = session_result(app, outcome, reason, text, figures, cpu_s=cpu, cpu_cycles=max(app.cycles - 1, 0))
        for o in list(self.observers):
            self.call_observer(app, o, "on_end", app, self.result)
