"""The client application (KUKA's ``ClientApplication``): the one loop that talks to the controller.

``ClientApplication(client, robot=IP, port=30200)`` binds the port (``connect()``), then every ``step()`` receives
one monitoring message, checks it, calls the client's callback for the session state, passes the command through
the guard, sends it (every k-th message with receive multiplier k) and then calls the observers (log, figures,
telemetry) — after the reply is out. ``run()`` steps until the session ends and returns a
:class:`~lbrcli.fri.outcome.SessionResult`.

Safety lives here, once, for every client: a message that is not self-consistent is never answered; every command
passes the guard; every stop the client side initiates (interrupt, a guard refusal, the client's end or error, a
failed observer) is a jerk-limited braking stop (``BrakingStop``) when the robot was being commanded; events on the
robot side (safety stop, drives off, POOR quality, the session leaving COMMANDING_ACTIVE, IDLE, a period change, a
silent controller) end the session at once (the controller stops the robot itself). Supervision (``Supervisor``) ends
the stream with a braking stop when the controller's timestamps disagree with its period, when our replies stop
reaching it (its reflected counter) or when the measured position leaves the command (position mode); it judges each
message after its reply, so its stop brakes from the next command. A client that prepares its next command
(``LBRClient.prepare_command``) is answered from a reply guarded and encoded after the previous cycle as soon as the
expected message is decoded and checked (:mod:`~lbrcli.fri.replying`). Lost monitoring messages were bridged by the
controller's extrapolation: the guard's reference and the braking stop continue from there, and the client is told
how many command periods it missed (``LBRClient.skipped``). The loop is this class; what one session knows lives in
its collaborators (:mod:`.inbound`, :mod:`.link`, :mod:`.replying`, :mod:`.ending`), each owning its state.
"""

from __future__ import annotations

import time
from operator import attrgetter
from typing import Any, Callable, Sequence

from trajectories.limits import JointLimits, default_limits

from .client import LBRClient
from .clock import SessionClock
from .constants import DEFAULT_PORT
from .cycle import Cycle, Observer
from .ending import SessionEnding
from .errors import FriError
from .guard import DEFAULT_MAX_FORCE, DEFAULT_MAX_MOMENT
from .inbound import Inbound
from .interpreter import loop_settings
from .link import Link, Supervised
from .messages import FriVersion
from .outcome import EndReason, Outcome, SessionResult
from .replying import Prepared, Replier
from .state import LBRState
from .supervision import commanding_end
from .transformation import TransformationClient
from .transport import UdpTransport

from .constants import STATE_COMMANDING_ACTIVE as CMD_ACTIVE, STATE_COMMANDING_WAIT as CMD_WAIT, STATE_IDLE as IDLE
from .replying import _CARTESIAN, _POSITION


class ClientApplication:
    """Runs one FRI session for ``client`` against the controller at ``robot`` (IPv4 address or name).

    The loop is this class. Each session's state lives in the collaborators ``start`` makes, each owning its part
    and taking the rest as arguments: the monitoring side (:class:`~lbrcli.fri.inbound.Inbound`: decoding, checks),
    the link (:class:`~lbrcli.fri.link.Link`: clock, lost messages and replies, the executed motion, supervision),
    the reply side (:class:`~lbrcli.fri.replying.Replier`: guarded and prepared replies, their counts) and the ends
    (:class:`~lbrcli.fri.ending.SessionEnding`: the robot side's, the stops asked for, client calls, observers)."""

    def __init__(
        self,
        client: LBRClient,
        robot: str = "127.0.0.1",
        port: int = DEFAULT_PORT,
        *,
        bind_host: str = "",
        version: FriVersion | str | None = None,
        limits: JointLimits | None = None,
        observers: Sequence[Observer] = (),
        first_message_timeout_s: float = 60.0,
        silence_timeout_s: float = 1.0,
        commanding_timeout_s: float | None = None,
        max_force: float = DEFAULT_MAX_FORCE,
        max_moment: float = DEFAULT_MAX_MOMENT,
        hold_cycles: int = 5,
        max_tracking_error: float | None = None,
        reply_gap_s: float | None = None,
        tracking_lag_s: float | None = None,
        busy_wait_s: float = 0.0,
        catch_up: bool = True,
        send_period_s: float | None = None,
        prepare: bool = True,
        transformation_client: TransformationClient | None = None,
        tcp_robot: Any = None,
        paced_by_replies: bool = False,
    ) -> None:
        self.client = client
        self.transformation_client, self.tcp_robot = transformation_client, tcp_robot
        self.prepares = prepare and type(client).prepare_command is not LBRClient.prepare_command
        self.robot, self.port_requested, self.bind_host = robot, port, bind_host
        self.version: FriVersion | None = FriVersion(version) if version is not None else None
        self.limits = limits if limits is not None else default_limits()
        self.observers: list[Observer] = list(observers)
        self.first_message_timeout_s = first_message_timeout_s
        self.silence_timeout_s = silence_timeout_s
        self.commanding_timeout_s = commanding_timeout_s
        self.max_force, self.max_moment = max_force, max_moment  # [N], [Nm] the guard's bounds on a wrench command
        self.hold_cycles = max(1, hold_cycles)
        self.max_tracking_error = max_tracking_error  # [rad] None: velocity limit × max(20 ms, 8 periods) per joint
        self.reply_gap_s = reply_gap_s  # [s] None: 50 ms
        self.tracking_lag_s = tracking_lag_s  # [s] the default tracking bound's lag at full speed (None: 20 ms)
        self.busy_wait_s = busy_wait_s  # [s] the receive polls this long before each message is due (transport)
        self.catch_up = catch_up  # a client behind answers the newest message waiting, the older ones are missed
        self.send_period_s = send_period_s  # [s] the send period the controller must have (None: whatever it sends)
        self.paced_by_replies = paced_by_replies  # a lock-step simulator: its messages' arrival times are not judged
        self.transport: UdpTransport | None = None
        self.cycle = Cycle()
        self.state: LBRState | None = None  # view of the last accepted message
        self.watchdog: Callable[[], str | None] | None = None  # asked on receive time-outs; a text ends the session
        self._interrupt: EndReason | None = None
        self._reset()

    # -- connection ------------------------------------------------------------------------------------------
    def connect(self) -> "ClientApplication":
        """Bind the local port (``port`` tells which; 0 binds a free one)."""
        if self.transport is None:
            self.transport = UdpTransport(self.robot, self.port_requested, self.bind_host, busy_wait_s=self.busy_wait_s,
                                          catch_up=self.catch_up)  # fmt: skip
        return self

    @property
    def port(self) -> int:
        return self.connect().transport.port  # type: ignore[union-attr]

    def disconnect(self) -> None:
        if self.transport is not None:
            self.transport.close()
            self.transport = None

    close = disconnect

    def __enter__(self) -> "ClientApplication":
        return self.connect()

    def __exit__(self, *exc: object) -> None:
        self.disconnect()

    def interrupt(self, reason: EndReason = EndReason.SIGINT) -> None:
        """Ask the session to end (signal-safe): brake if commanding, then stop."""
        if self._interrupt is None:
            self._interrupt = reason

    # -- state -----------------------------------------------------------------------------------------------
    def _reset(self, duration_s: float | None = None) -> None:
        """A new session: its collaborators, clock and counters."""
        self._in = Inbound(self.version, self.limits.position)
        self._out = Replier(self.limits, self.transformation_client, self.tcp_robot)
        self._end = SessionEnding(self.client, self.observers, self.commanding_timeout_s)
        self._link = Link(SessionClock(self.first_message_timeout_s, self.silence_timeout_s, duration_s), self.limits,
                          self.max_force, self.max_moment, self.hold_cycles, self.max_tracking_error, self.reply_gap_s,
                          self.tracking_lag_s)  # fmt: skip
        self._started = False
        self._send_counter = 0  # messages since the last reply (receive multiplier)
        self.cycles = self.active_cycles = 0

    # the session's figures, kept by the collaborators that count them (read-only)
    result = property(attrgetter("_end.result"), doc="The session's result (None while it runs).")
    error = property(attrgetter("_end.error"), doc="A client callback's or observer's exception, if one ended it.")
    states_seen = property(attrgetter("_end.states_seen"), doc="The session states in the order seen.")
    malformed = property(attrgetter("_in.malformed"), doc="Datagrams undecodable or not self-consistent.")
    stale = property(attrgetter("_in.stale"), doc="Datagrams repeated or older than the last accepted.")
    _last_data = property(attrgetter("_in.last_data"), doc="The last accepted datagram (the log writer's row).")
    answered = property(attrgetter("_out.answered"), doc="Replies sent.")
    position_commands = property(attrgetter("_out.position_commands"), doc="Replies carrying a joint position.")
    prepared_replies = property(attrgetter("_out.prepared_replies"), doc="Replies prepared the cycle before.")
    unanswered_at_start = property(attrgetter("_out.unanswered_at_start"), doc="Messages before the first reply.")
    latencies = property(attrgetter("_out.latencies"), doc="[ns] receive → reply of each reply sent.")
    client_sequence = property(attrgetter("_out.client_sequence"), doc="Counter of the last reply (−1: none yet).")
    missed = property(attrgetter("_link.missed"), doc="The controller's messages that never arrived.")
    lost_replies = property(attrgetter("_link.lost_replies"), doc="Replies the controller reported not received.")
    period_s = property(attrgetter("_link.clock.period_s"), doc="[s] Command period (send period × multiplier).")
    braking_cycles = property(attrgetter("_link.braking_cycles"), doc="Cycles of the client side's braking stop.")
    extrapolated_cycles = property(attrgetter("_link.extrapolated_cycles"), doc="Periods the controller bridged.")
    _motion = property(attrgetter("_link.motion"), doc="The executed motion (once the period is known).")
    _sup = property(attrgetter("_link.sup"), doc="The supervision (once the period is known).")

    # -- the loop --------------------------------------------------------------------------------------------
    def run(self, duration_s: float | None = None) -> SessionResult:
        """Step until the session ends (or ``duration_s`` [s] after the first message); the result."""
        with loop_settings():
            self.start(duration_s)
            while self.step():
                pass
        assert self.result is not None
        return self.result

    def start(self, duration_s: float | None = None) -> None:
        """Prepare a session (``step`` calls it if needed): bind, reset counters, tell the observers."""
        self.connect()
        self._reset(duration_s)
        self._started, self.client.command_period_s = True, None
        for o in list(self.observers):
            self._end.call_observer(self, o, "on_start", self)

    def step(self) -> bool:
        """Process one datagram (or a receive timeout). False once the session has ended.

        Before the reply only what decides it: decoding, the sequence, self-consistency, the robot side's ends, the
        client's command and the guard — or, when the client prepared this cycle's command (``prepare_command``)
        and the message is the expected next one, the reply prepared and guarded after the previous cycle. The
        supervision of the session's trends (clock, replies, tracking), the client's confirming ``command`` call of
        a prepared cycle and the observers run after it; a problem found there brakes from the next command.
        The phases, in order: receive and decode (:class:`~lbrcli.fri.inbound.Inbound`), the prepared reply, the
        session's state (:meth:`_update_session`, ``SessionEnding.robot_side``), the client's callback
        (``SessionEnding.ask_client``), the guarded reply (:meth:`_send_reply`), then the bookkeeping after it (``_after``)."""
        if not self._started:
            self.start(self._link.clock.duration_s)
        end = self._end
        if end.ended or (self._interrupt is not None and end.stop is None and end.interrupted(self, self._interrupt)):
            return False
        # ---- receive and decode --------------------------------------------------------------------------
        t_wait = time.monotonic()
        data = self.transport.receive()  # type: ignore[union-attr]
        now = time.monotonic()
        if data is None:
            return self._on_silence(t_wait, now)
        t_rx = time.perf_counter_ns()
        inbound = self._in
        if inbound.codec is None and not self._open(data):
            return self._check_clocks(now)
        d = inbound.decode(data)
        if d < 0:  # malformed, stale or not self-consistent: never answered
            return self._check_clocks(now)
        mon = inbound.mon
        seq = mon.header.sequenceCounter
        state = mon.connectionInfo.sessionState
        # our reply to the previous message never reached the controller (it reflects an older one): it bridged that
        # period by extrapolation instead of executing our command
        link = self._link
        lost_reply = link.reply_lost(mon, d)
        # ---- the reply prepared after the previous cycle, if this is the message it was made for -----------
        out = self._out
        prepared = out.prepared
        if prepared is not None:
            out.prepared = None
            if (seq == prepared[0] and state == CMD_ACTIVE and end.stop is None and self._interrupt is None
                    and not lost_reply and commanding_end(mon, CMD_ACTIVE, True, link.clock.period_key) is None):  # fmt: skip
                return self._send_prepared(prepared, mon, seq, now, t_rx)
        # ---- the session's state: clock, counters, the period, state changes and robot-side ends -----------
        skipped = self._update_session(mon, seq, d, lost_reply, now)
        if skipped < 0:
            return False
        # what the supervision after the reply judges this message against: the command in force when it was sent
        motion = link.motion
        supervised = (state == CMD_ACTIVE and motion is not None and not motion.braking,
                      motion is not None and motion.moving, motion.prev if motion is not None else (),
                      out.client_sequence)  # fmt: skip
        going_on = self._robot_side(mon, state, now)
        if going_on is not None:
            return going_on
        # ---- receive multiplier: callbacks every message, a reply every k-th --------------------------------
        self._send_counter += 1
        due = self._send_counter >= (mon.connectionInfo.receiveMultiplier or 1)
        if due:
            self._send_counter = 0
        client = self.client
        client.reply_due, client.skipped = due, skipped
        # ---- the client's answer, then the guarded reply ---------------------------------------------------
        stop = end.ask_client(state, motion, inbound.command, self.transformation_client, self.cycle)
        if stop is not None:  # a stop the client side requested ends the session here (nothing to answer)
            end.finish(self, *stop, observe=True)
            return False
        if not due:
            return self._after(now, mon, seq, supervised, answered=False)
        if not self._send_reply(mon, state, seq, t_rx):
            return False
        return self._after(now, mon, seq, supervised, answered=True)

    # -- the phases of a cycle -------------------------------------------------------------------------------
    def _open(self, data: bytes) -> bool:
        """The session's wire format from its first datagram: the codec, the state and command the client sees and
        the reply message; False if ``data`` tells none."""
        inbound = self._in
        if not inbound.open(data):
            return False
        self.version, self.state = inbound.version, inbound.state
        self.client.robot_state, self.client.robot_command = inbound.state, inbound.command  # type: ignore[assignment]
        self._out.open(inbound.codec)
        return True

    def _update_session(self, mon: Any, seq: int, d: int, lost_reply: bool, now: float) -> int:
        """Account for an accepted message ``d`` sequence steps after the last (0: the first): the link (clock, lost
        messages and replies), the counters and, once the period is known, the motion and its supervision. The
        command periods the client missed, or −1 if too many messages were lost (the session ended)."""
        link, end = self._link, self._end
        first = link.clock.t_first is None
        skipped = link.received(mon, d, lost_reply, (d > 1 or lost_reply) and end.moving(), now)
        if skipped < 0:  # longer than any controller bridges: where the robot is, is unknown — it stopped it itself
            end.finish(self, Outcome.STOPPED, EndReason.SUPERVISION, f"supervision: {d - 1} messages of the "
                       "controller were lost in a row: no command is safe from here")  # fmt: skip
            return -1
        self.client.replies_lost = 1 if lost_reply else 0
        self.cycles += 1
        cyc = self.cycle
        if first:
            cyc.command = tuple(mon.monitorData.measuredJointPosition.value)
            end.cpu0 = time.thread_time()
        cyc.begin(link.clock.t, mon.connectionInfo.sessionState)
        if link.learn_period(mon):  # the first message outside IDLE: the motion, the busy-wait
            send_period_ms = mon.connectionInfo.sendPeriod
            end.motion = link.motion
            self.client.executed, self.client.command_period_s = link.motion, link.clock.period_s
            link.motion.replans = self.client.replans  # type: ignore[union-attr]
            if self.busy_wait_s > 0.0:
                self.transport.expect_period(send_period_ms * 1e-3)  # type: ignore[union-attr]
                self.transport.warm = self._warm  # type: ignore[union-attr]
            end.check_send_period(send_period_ms, self.send_period_s)
        return skipped

    def _warm(self) -> None:
        """Between messages (the transport's busy-wait): the last good message decoded and checked again."""
        self._in.warm(self._link.clock.period_key)

    def _robot_side(self, mon: Any, state: int, now: float) -> bool | None:
        """The session state as the robot reports it: state changes (told to the client), the robot side's ends,
        IDLE (observed, not answered). The step's result when the cycle ends here, else None."""
        end = self._end
        seen_session = end.seen_session
        clock = self._link.clock
        stop = end.robot_side(mon, state, clock.period_key, now - clock.t_first)  # type: ignore[operator]
        if stop is not None:
            self._end.finish(self, *stop, observe=True)
            return False
        if state == IDLE:
            if not seen_session:
                self.cycle.command = tuple(mon.monitorData.measuredJointPosition.value)
            self._end.observe(self)
            return self._check_clocks(now)
        if state == CMD_ACTIVE:
            self.active_cycles += 1
        return None

    def _send_reply(self, mon: Any, state: int, seq: int, t_rx: int) -> bool:
        """Build this cycle's reply (the guarded motion in the commanding states, the header in the monitoring
        ones; IO writes, transformations) and send it; False if that ended the session."""
        cmd, out = self._in.command, self._out
        if state >= CMD_WAIT:
            motion = self._link.motion
            if motion is None:
                self._end.finish(self, Outcome.REFUSED, EndReason.GUARD,
                             "the controller did not send its send period; no command is safe", observe=True)  # fmt: skip
                return False
            stop = out.build_motion(mon, state, cmd, motion, self.client, self.cycle)
            if stop is not None:
                if not stop[1]:  # refused: nothing sent
                    self._end.finish(self, *stop[0], observe=True)
                    return False
                self._end.stop_braking(*stop[0])  # it brakes from this command
        else:
            out.message.header_only()  # type: ignore[union-attr]  # plus IO writes, in the monitoring states
        out.set_extras(cmd)  # type: ignore[arg-type]  # IO writes, transformations
        problem = out.send(self.transport, out.message.datagram(out.client_seq, seq), t_rx)  # type: ignore[union-attr]
        if problem is not None:
            self._end.finish(self, Outcome.STOPPED, EndReason.SILENT, problem, observe=True)
            return False
        return True

    # -- after the reply -------------------------------------------------------------------------------------
    def _after(self, now: float, mon: Any, seq: int, supervised: Supervised, answered: bool) -> bool:
        """The cycle after its reply went out (or was not due): counters, supervision, the hold, observers, and
        the next cycle's prepared reply."""
        link, out, end, cyc = self._link, self._out, self._end, self.cycle
        if answered:
            end.call("after_reply")
            link.replied(cyc, out.client_seq, seq)
            out.sent(cyc, link.missed)
        if link.sup is not None and end.stop is None:
            stamp = None if self.paced_by_replies else getattr(self.transport, "received_ns", None)
            problem = link.supervise(mon, seq, supervised, mon.ipoData.clientCommandMode in (_POSITION, _CARTESIAN),
                                     stamp() if stamp is not None else None)  # fmt: skip
            if problem is not None:
                end.stop_braking(Outcome.STOPPED, EndReason.SUPERVISION, f"supervision: {problem}")
        motion = link.motion
        if answered and motion is not None and motion.held_long_enough():
            end.finish(self, *end.stop, observe=True)  # type: ignore[misc]
            return False
        end.observe(self)
        if cyc.state == CMD_ACTIVE and self.prepares and end.stop is None and not end.ended and motion is not None:
            out.prepare(seq, mon, motion, self.client)  # type: ignore[arg-type]
        return end.check_clocks(self, link.clock, now)

    def _send_prepared(self, prepared: Prepared, mon: Any, seq: int, now: float, t_rx: int) -> bool:
        """Send the reply prepared for this message, then what the full cycle records, the client's confirming
        ``command`` call (:meth:`~lbrcli.fri.replying.Replier.confirm`) and the rest of the cycle."""
        q = prepared[2]
        problem = self._out.send(self.transport, prepared[1], t_rx)
        if problem is not None:
            self._end.finish(self, Outcome.STOPPED, EndReason.SILENT, problem)
            return False
        link = self._link
        link.clock.received(now, 1, mon.connectionInfo.sendPeriod)
        self.cycles += 1
        self.active_cycles += 1
        motion = link.motion
        supervised = (True, motion.moving, motion.prev, self._out.client_sequence)  # type: ignore[union-attr]
        self.cycle.begin(link.clock.t, CMD_ACTIVE)
        motion.sent(q, CMD_ACTIVE, True)  # type: ignore[union-attr]  # before the client's call: a stop brakes from q
        self._out.confirm(q, self.client, self._in.command, self._end, self.cycle)
        return self._after(now, mon, seq, supervised, answered=True)

    # -- time-outs -------------------------------------------------------------------------------------------
    def _check_clocks(self, now: float) -> bool:
        """Time-outs and the monitoring duration; False once the session ended."""
        return self._end.check_clocks(self, self._link.clock, now)

    def _on_silence(self, t_wait: float, now: float) -> bool:
        """A receive timeout: the controller is quiet since ``t_wait`` [s]; the watchdog may end the session."""
        clock = self._link.clock
        if clock.quiet_from is None:
            clock.quiet_from = t_wait
        self._out.prepared = None
        if self.watchdog is not None:
            problem = self.watchdog()
            if problem:
                self._end.ended = True
                raise FriError(problem)
        return self._check_clocks(now)
