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
how many command periods it missed (``LBRClient.skipped``).
FRI 2.7 Cartesian poses and transformation requests (``tcp_robot``, ``transformation_client``): :mod:`.replying`.
"""

from __future__ import annotations

import time
from typing import Any, Callable, Sequence

from trajectories.limits import JointLimits, default_limits

from .client import LBRClient
from .clock import SessionClock
from .codec import FriCodec, detect_version
from .command import LBRCommand
from .cycle import Cycle, Observer
from .ending import SessionEnding
from .constants import DEFAULT_PORT
from .errors import FriDecodeError
from .guard import DEFAULT_MAX_FORCE, DEFAULT_MAX_MOMENT
from .interpreter import loop_settings
from .messages import FriVersion
from .motion import ExecutedMotion
from .outcome import EndReason, Outcome, SessionResult
from .reply import ReplyMessage
from .replying import Prepared, Replying
from .state import LBRState
from .supervision import Supervisor, consistent, joint_bound
from .transformation import TransformationClient
from .transport import UdpTransport

from .constants import STATE_COMMANDING_ACTIVE as CMD_ACTIVE, STATE_COMMANDING_WAIT as CMD_WAIT, STATE_IDLE as IDLE


class ClientApplication(Replying, SessionEnding):
    """Runs one FRI session for ``client`` against the controller at ``robot`` (IPv4 address or name)."""

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
        send_period_s: float | None = None,
        prepare: bool = True,
        transformation_client: TransformationClient | None = None,
        tcp_robot: Any = None,
    ) -> None:
        self.client = client
        self.transformation_client, self.tcp_robot = transformation_client, tcp_robot
        self.prepares = prepare and type(client).prepare_command is not LBRClient.prepare_command
        self.robot, self.port_requested, self.bind_host = robot, port, bind_host
        self.version: FriVersion | None = FriVersion(version) if version is not None else None
        self.limits = limits if limits is not None else default_limits()
        self._bound = joint_bound(self.limits.position)  # [rad] |joint value| a real robot reports at most
        self._last_data: bytes | None = None  # the last datagram (re-decoded while busy-waiting: warm caches)
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
        self.send_period_s = send_period_s  # [s] the send period the controller must have (None: whatever it sends)
        self.transport: UdpTransport | None = None
        self.cycle = Cycle()
        self.state: LBRState | None = None  # view of the last accepted message
        self.result: SessionResult | None = None
        self.error: BaseException | None = None  # a client callback's or observer's exception, if one ended it
        self.watchdog: Callable[[], str | None] | None = None  # asked on receive time-outs; a text ends the session
        self._interrupt: EndReason | None = None
        self._reset()

    # -- connection ------------------------------------------------------------------------------------------
    def connect(self) -> "ClientApplication":
        """Bind the local port (``port`` tells which; 0 binds a free one)."""
        if self.transport is None:
            self.transport = UdpTransport(self.robot, self.port_requested, self.bind_host, busy_wait_s=self.busy_wait_s)
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
    def _reset(self) -> None:
        self._codec: FriCodec | None = None
        self._mon: Any = None
        self._reply: ReplyMessage | None = None
        self._prepared: Prepared | None = None  # the reply to the next message, if the client prepared it
        self._cmd: LBRCommand | None = None
        self._motion: ExecutedMotion | None = None  # built when the period is known
        self._sup: Supervisor | None = None
        self._stop: tuple[Outcome, EndReason, str] | None = None  # a stop the client side requested
        self._ended = False
        self._started = False
        self._clock = SessionClock(self.first_message_timeout_s, self.silence_timeout_s, None)
        self._last_seq = -1
        self._last_state = IDLE
        self._seen_session = False
        self._commanding = False
        self._was_active = False
        self._send_counter = 0
        self._client_seq = 0
        self._reply_seq_prev: int | None = None  # our reply to the previous message, if it carried a position
        self._answered_any = False
        self._unanswered_at_start = 0
        self._cpu0 = 0.0
        self._cycles0 = 0
        # statistics
        self.cycles = self.answered = self.position_commands = 0
        self.missed = self.stale = self.malformed = self.active_cycles = 0
        self.prepared_replies = 0  # cycles answered with the reply prepared after the previous one
        self.lost_replies = 0  # commands the controller reported not received (reflected counter) while moving
        self.states_seen: list[int] = []
        self._latencies: list[int] = []  # [ns]

    @property
    def client_sequence(self) -> int:
        """Sequence counter of the last command message sent (−1 before the first)."""
        return (self._client_seq - 1) & 0xFFFFFFFF if self.answered else -1

    @property
    def braking_cycles(self) -> int:
        return self._motion.braking_cycles if self._motion is not None else 0

    @property
    def extrapolated_cycles(self) -> int:
        return self._motion.extrapolated_cycles if self._motion is not None else 0

    @property
    def period_s(self) -> float | None:
        """Command period [s] (send period × receive multiplier), known from the first session message."""
        return self._clock.period_s

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
        self._reset()
        self._clock = SessionClock(self.first_message_timeout_s, self.silence_timeout_s, duration_s)
        self._started, self.client.command_period_s = True, None
        for o in list(self.observers):
            self._call_observer(o, "on_start", self)

    def step(self) -> bool:
        """Process one datagram (or a receive timeout). False once the session has ended.

        Before the reply only what decides it: decoding, the sequence, self-consistency, the robot side's ends, the
        client's command and the guard — or, when the client prepared this cycle's command (``prepare_command``)
        and the message is the expected next one, the reply prepared and guarded after the previous cycle. The
        supervision of the session's trends (clock, replies, tracking), the client's confirming ``command`` call of
        a prepared cycle and the observers run after it; a problem found there brakes from the next command.
        The phases, in order: receive and decode (:meth:`_decode`), the prepared reply, the session's state
        (:meth:`_update_session`, :meth:`_robot_side`), the client's callback (:meth:`_ask_client`), the guarded
        reply (:meth:`_send_reply`), then the bookkeeping after it (``_after``)."""
        if not self._started:
            self.start(self._clock.duration_s)
        if self._ended or (self._interrupt is not None and self._stop is None and self._stop_on_interrupt()):
            return False
        # ---- receive and decode --------------------------------------------------------------------------
        t_wait = time.monotonic()
        data = self.transport.receive()  # type: ignore[union-attr]
        now = time.monotonic()
        if data is None:
            return self._on_silence(t_wait, now)
        t_rx = time.perf_counter_ns()
        d = self._decode(data)
        if d < 0:  # malformed, stale or not self-consistent: never answered
            return self._check_clocks(now)
        mon = self._mon
        seq = mon.header.sequenceCounter
        state = mon.connectionInfo.sessionState
        # our reply to the previous message never reached the controller (it reflects an older one): it bridged that
        # period by extrapolation instead of executing our command
        expected = self._reply_seq_prev
        lost_reply = (expected is not None and d == 1 and self._sup is not None and self._sup.reflecting
                      and mon.header.reflectedSequenceCounter != expected)  # fmt: skip
        self._reply_seq_prev = None
        # ---- the reply prepared after the previous cycle, if this is the message it was made for -----------
        prepared = self._prepared
        if prepared is not None:
            self._prepared = None
            if (seq == prepared[0] and state == CMD_ACTIVE and self._stop is None and self._interrupt is None
                    and not lost_reply):  # fmt: skip
                going_on = self._send_prepared(prepared, mon, seq, now, t_rx)
                if going_on is not None:
                    return going_on
        # ---- the session's state: clock, counters, the period, state changes and robot-side ends -----------
        skipped = self._update_session(mon, seq, d, lost_reply, now)
        if skipped < 0:
            return False
        # what the supervision after the reply judges this message against: the command in force when it was sent
        motion = self._motion
        supervised = (state == CMD_ACTIVE and motion is not None and not motion.braking,
                      motion is not None and motion.moving, motion.prev if motion is not None else (),
                      self.client_sequence)  # fmt: skip
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
        if not self._ask_client(state, motion):
            return False
        if not due:
            return self._after(now, mon, seq, supervised, answered=False)
        if not self._send_reply(mon, state, seq, t_rx):
            return False
        return self._after(now, mon, seq, supervised, answered=True)

    # -- the phases of a cycle -------------------------------------------------------------------------------
    def _decode(self, data: bytes) -> int:
        """Decode ``data`` into the session's monitoring message and check it: the sequence step from the last
        accepted message (0 for the first), or −1 for a datagram never answered (malformed, stale, inconsistent)."""
        codec = self._codec
        if codec is None:
            version = self.version or detect_version(data)
            if version is None:
                self.malformed += 1
                return -1
            self._open_codec(version)
            codec = self._codec
        mon = self._mon
        try:
            codec.decode_monitoring(data, mon)  # type: ignore[union-attr]
        except FriDecodeError:
            self.malformed += 1
            return -1
        d = 0
        if self._last_seq >= 0:
            d = (mon.header.sequenceCounter - self._last_seq) & 0xFFFFFFFF
            if d == 0 or d > 0x7FFFFFFF:
                self.stale += 1
                return -1
        if not consistent(mon, self._bound):
            self.malformed += 1
            return -1
        self._last_data = data
        return d

    def _update_session(self, mon: Any, seq: int, d: int, lost_reply: bool, now: float) -> int:
        """Account for an accepted message ``d`` sequence steps after the last: the clock, lost messages (bridged
        by extrapolation), lost replies, the counters and, once the period is known, the motion and supervision.
        The command periods the client missed, or −1 if too many messages were lost (the session ended)."""
        skipped = 0
        clock = self._clock
        ci = mon.connectionInfo
        first = clock.t_first is None
        clock.received(now, 0 if self._last_seq < 0 else d, ci.sendPeriod)
        if self._last_seq >= 0:
            self.missed += d - 1
            if d > 1 and self._moving():
                if self._sup is not None and d - 1 > self._sup.max_reply_gap:
                    # longer than any controller bridges: where the robot is, is unknown — it stopped it itself
                    self._last_seq = seq
                    self._finish(Outcome.STOPPED, EndReason.SUPERVISION, f"supervision: {d - 1} messages of the "
                                 "controller were lost in a row: no command is safe from here", observe=False)  # fmt: skip
                    return -1
                skipped = self._motion.extrapolate((d - 1) // (clock.period_key[1] if clock.period_key else 1))  # type: ignore[union-attr]
        if lost_reply and self._moving():
            self._motion.reply_lost()  # type: ignore[union-attr]
            self.lost_replies += 1  # (late replies: the controller had not received it when it sent this message)
        self.client.replies_lost = 1 if lost_reply else 0
        self._last_seq = seq
        self.cycles += 1
        cyc = self.cycle
        if first:
            cyc.command = tuple(mon.monitorData.measuredJointPosition.value)
            self._cpu0 = time.thread_time()
            self._cycles0 = 1
        state = ci.sessionState
        cyc.begin(clock.t, state)
        if state != IDLE and clock.learn_period(ci):
            self._start_motion(mon)
        return skipped

    def _start_motion(self, mon: Any) -> None:
        """The command period is known (the first session message): the executed motion, its supervision and the
        transport's busy-wait."""
        clock, ci = self._clock, mon.connectionInfo
        self._motion = ExecutedMotion(self.limits, clock.period_s, self.max_force, self.max_moment,  # type: ignore[arg-type]
                                      self.hold_cycles, mon.monitorData.measuredJointPosition.value)  # fmt: skip
        self.client.executed, self.client.command_period_s = self._motion, clock.period_s
        self._sup = Supervisor.from_limits(self.limits.velocity, ci.sendPeriod * 1e-3, clock.period_key[1],  # type: ignore[index]
                                           self.max_tracking_error, self.reply_gap_s, self.tracking_lag_s)  # fmt: skip
        if self.busy_wait_s > 0.0:
            transport = self.transport
            transport.expect_period(ci.sendPeriod * 1e-3)  # type: ignore[union-attr]
            transport.warm = self._warm  # type: ignore[union-attr]
        self._check_send_period(ci.sendPeriod)

    def _ask_client(self, state: int, motion: ExecutedMotion | None) -> bool:
        """The client's callback for ``state`` into the cleared command (none while braking); False if a stop the
        client side requested ended the session here (nothing to answer)."""
        cmd = self._cmd
        cmd.reset()  # type: ignore[union-attr]
        braking = motion is not None and motion.braking
        self.client.braking = braking
        if self._stop is not None and not braking:
            # a stop requested outside COMMANDING_ACTIVE (or before anything moved): end without answering
            self._finish(*self._stop, observe=True)
            return False
        if braking:
            if state != CMD_ACTIVE:
                self._finish(*self._stop, observe=True)  # type: ignore[misc]
                return False
        else:
            if state == CMD_ACTIVE:
                q = self._call_client("command", self.state)
                if q is not None:
                    cmd.set_joint_position(q)  # type: ignore[union-attr]
            else:
                self._call_client("wait_for_command" if state == CMD_WAIT else "monitor", self.state)
            if self._stop is not None and not (motion is not None and motion.braking):
                self._finish(*self._stop, observe=True)
                return False
        self._provide_frames()
        cyc = self.cycle
        cyc.phase = self.client.phase
        cyc.row = self.client.row
        return True

    def _send_reply(self, mon: Any, state: int, seq: int, t_rx: int) -> bool:
        """Build this cycle's reply (the guarded motion in the commanding states, the header in the monitoring
        ones; IO writes, transformations) and send it; False if that ended the session."""
        cmd = self._cmd
        if state >= CMD_WAIT:
            if not self._build_motion(mon, state, cmd):  # it ended the session (a refusal, nothing sent)
                return False
        else:
            self._reply.header_only()  # type: ignore[union-attr]  # plus IO writes, in the monitoring states
        self._set_extras(cmd)  # type: ignore[arg-type]  # IO writes, transformations
        try:
            self.transport.send(self._reply.datagram(self._client_seq, seq))  # type: ignore[union-attr]
        except OSError as exc:
            self._finish(Outcome.STOPPED, EndReason.SILENT, f"cannot send to the controller: {exc.strerror}",
                         observe=True)  # fmt: skip
            return False
        self._latencies.append(time.perf_counter_ns() - t_rx)
        return True

    def _open_codec(self, version: FriVersion) -> None:
        self.version = version
        codec = FriCodec(version)
        self._codec = codec
        self._mon = codec.new_monitoring()
        self.state = LBRState(self._mon, version)
        self._cmd = LBRCommand(self.state)
        self.client.robot_state, self.client.robot_command = self.state, self._cmd
        self._reply = ReplyMessage(codec)
