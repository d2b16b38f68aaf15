"""Pure-Python FRI client session: answers the controller's monitoring messages over UDP.

The session binds the local port (the one in the robot's FRI configuration), accepts datagrams only from the
controller's IP (any source port) and replies to each datagram's source. Per session state it answers
(facts/fri.md): IDLE nothing; MONITORING_WAIT/READY a header only; COMMANDING_WAIT the ipo joint position
(mirror); COMMANDING_ACTIVE the next row of the plan (after the per-cycle guard) or, without a plan, the mirror.
With receiveMultiplier k it answers every k-th message (KUKA's counting). Counters: its own sequenceCounter from
0, +1 per command; reflectedSequenceCounter = the answered message's sequenceCounter.

The stream ends cleanly (the client stops answering, the controller stops the robot) on: plan completed
(after the settle rows), safety stop, drives not active or POOR quality once commanding started, the session
leaving COMMANDING_ACTIVE, IDLE after a session, a silent controller, a guard refusal or an interrupt (the last
command is held for a few cycles first). Foreign datagrams (other IP), malformed ones and stale ones
(sequence counter not newer) are counted and ignored; gaps in the controller's sequence counter count as missed.
"""

from __future__ import annotations

import contextlib
import gc
import math
import signal
from operator import sub as _sub
import socket
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Iterator, Sequence

from trajectories.errors import FriDecodeError, FriError, InputError
from trajectories.limits import JointLimits

from .codec import FriCodec
from .constants import COMMAND_MESSAGE_ID, DEFAULT_PORT, ConnectionQuality, DriveState, SafetyState, SessionState
from .guard import CommandGuard
from .log import PHASE_HOLD, PHASE_MIRROR, PHASE_NONE, PHASE_SETTLE, ExecutionLog, LogLayout
from .messages import FriVersion
from .motion import Plan

IDLE = int(SessionState.IDLE)
MON_WAIT = int(SessionState.MONITORING_WAIT)
MON_READY = int(SessionState.MONITORING_READY)
CMD_WAIT = int(SessionState.COMMANDING_WAIT)
CMD_ACTIVE = int(SessionState.COMMANDING_ACTIVE)
_DRIVE_ACTIVE = int(DriveState.ACTIVE)
_POOR = int(ConnectionQuality.POOR)
_RECV_TIMEOUT = 0.05  # [s] socket timeout: how often the loop looks at the interrupt flag and the clocks

# outcomes
COMPLETED = "completed"  # plan (or monitoring duration) finished
INTERRUPTED = "interrupted"  # Ctrl-C / interrupt()
STOPPED = "stopped"  # the robot side ended or broke the session
REFUSED = "refused"  # the guard refused a command

PrepareFn = Callable[[Any, float], "Plan | None"]  # (first monitoring message, command period [s]) -> plan
ExtraFn = Callable[[Any], Sequence[float]]  # monitoring message -> extra log values


@dataclass(frozen=True)
class SessionResult:
    """What happened in a session (figures in SI units, latencies in ms)."""

    outcome: str  # completed | interrupted | stopped | refused
    end_reason: str
    cycles: int  # monitoring messages accepted
    answered: int  # command messages sent
    position_commands: int  # of which carried a joint position
    missed: int  # gaps in the controller's sequence counter (lost or never sent)
    stale: int  # datagrams whose sequence counter was not newer (duplicates, reordering): ignored
    foreign: int  # datagrams from another address: ignored
    malformed: int  # datagrams that did not decode: ignored
    skipped: int  # datagrams that queued up while the plan was prepared: dropped unanswered (also in missed)
    prepare_ms: float | None  # [ms] checking and planning at the first session message (excluded from latencies)
    states_seen: tuple[int, ...]  # distinct session states in order
    period_s: float | None  # command period (send period × receive multiplier) [s]
    move_rows: int  # rows of the move to the start commanded
    trajectory_rows: int  # rows of the trajectory commanded
    settle_rows: int
    active_cycles: int  # cycles in COMMANDING_ACTIVE
    min_tracking: float | None  # lowest trackingPerformance in COMMANDING_ACTIVE
    max_tracking_error: float | None  # max |measured − commanded| [rad] in COMMANDING_ACTIVE (same cycle)
    max_tracking_error_prev: float | None  # ... against the command of the cycle before (one cycle of lag) [rad]
    max_ball_theta: float | None  # [rad] largest simulated (or measured) ball tilt, 'ball_theta' IO value
    residual_ball_theta: float | None  # [rad] largest tilt while settling (after the last trajectory row)
    latency_p50_ms: float | None  # receive → reply, inside the client
    latency_p99_ms: float | None
    latency_max_ms: float | None
    cpu_us_per_cycle: float | None  # CPU time of the session thread per accepted message [µs]
    log_rows: int

    @property
    def ok(self) -> bool:
        return self.outcome == COMPLETED

    def to_dict(self) -> dict[str, Any]:
        d = {k: getattr(self, k) for k in self.__dataclass_fields__}
        d["states_seen"] = [SessionState(s).name for s in self.states_seen]
        d["ok"] = self.ok
        return d


@dataclass
class _Stats:
    cycles: int = 0
    answered: int = 0
    position_commands: int = 0
    missed: int = 0
    stale: int = 0
    foreign: int = 0
    malformed: int = 0
    states: list[int] = field(default_factory=list)
    active: int = 0
    min_tracking: float = math.inf
    max_err: float = 0.0
    max_err_prev: float = 0.0
    max_ball: float = -math.inf
    residual_ball: float = -math.inf
    move_rows: int = 0
    traj_rows: int = 0
    settle_rows: int = 0
    skipped: int = 0
    latencies: list[int] = field(default_factory=list)  # [ns]


def resolve_ip(host: str) -> str:
    """The IPv4 address of ``host`` (an address or a name)."""
    try:
        return socket.getaddrinfo(host, None, socket.AF_INET, socket.SOCK_DGRAM)[0][4][0]
    except (socket.gaierror, IndexError):
        raise InputError(f"--robot: cannot resolve {host!r} to an IPv4 address") from None


def _percentile_ms(sorted_ns: list[int], p: float) -> float | None:
    if not sorted_ns:
        return None
    k = min(len(sorted_ns) - 1, max(0, int(math.ceil(p / 100.0 * len(sorted_ns))) - 1))
    return sorted_ns[k] * 1e-6


class FriSession:
    """One FRI client session on a bound UDP socket (bound at construction, so ``.port`` is known early)."""

    def __init__(
        self,
        robot_ip: str,
        port: int = DEFAULT_PORT,
        *,
        bind_host: str = "",
        version: FriVersion | str = FriVersion.V1_15,
        limits: JointLimits | None = None,
        first_message_timeout_s: float = 60.0,
        silence_timeout_s: float = 1.0,
        commanding_timeout_s: float | None = None,
        hold_cycles: int = 10,
    ) -> None:
        self.robot_ip = resolve_ip(robot_ip)
        self.version = FriVersion(version)
        self.codec = FriCodec(self.version)
        self.limits = limits
        self.first_message_timeout_s = first_message_timeout_s
        self.silence_timeout_s = silence_timeout_s
        self.commanding_timeout_s = commanding_timeout_s
        self.hold_cycles = max(1, hold_cycles)
        self._interrupted = False
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            sock.bind((bind_host, port))
        except OSError as exc:
            sock.close()
            where = f"{bind_host or '*'}:{port}"
            raise FriError(f"cannot bind the FRI port {where}: {exc.strerror}") from None
        sock.settimeout(_RECV_TIMEOUT)
        self.sock = sock
        self.port: int = sock.getsockname()[1]

    # -- control ---------------------------------------------------------------------------------------------
    def interrupt(self) -> None:
        """Ask the loop to end: hold the last command a few cycles if commanding, then stop (signal-safe)."""
        self._interrupted = True

    def close(self) -> None:
        self.sock.close()

    def __enter__(self) -> "FriSession":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- the loop --------------------------------------------------------------------------------------------
    def run(
        self,
        prepare: PrepareFn | None = None,
        log: ExecutionLog | None = None,
        *,
        duration_s: float | None = None,
        extra_names: Sequence[str] = (),
        extra: ExtraFn | None = None,
        watchdog: Callable[[], str | None] | None = None,
        tap: Callable[[float, Any], None] | None = None,
    ) -> SessionResult:
        """Answer the controller until an end condition; return the statistics.

        ``prepare(message, period_s)`` is called once, at the first message of a session (not IDLE), before
        anything is sent, and returns the plan to stream in COMMANDING_ACTIVE (None: never command motion, mirror ipo). It may
        raise (e.g. CheckFailed for a far start): the session then ends without having sent anything, the log
        holding that first message. ``duration_s`` [s] ends the session after that wall time from the first
        message. ``extra(mon)`` adds the ``extra_names`` columns to each log row. ``watchdog()`` is asked whenever
        no datagram came for a while; a text it returns ends the session with FriError (e.g. the simulator died).
        ``tap(t, mon)`` is called every cycle after the reply went out (telemetry); it must return at once.
        """
        gc.collect()
        gc_was = gc.isenabled()
        gc.disable()
        try:
            return self._loop(prepare, log, duration_s, tuple(extra_names), extra, watchdog, tap)
        finally:
            if gc_was:
                gc.enable()

    def _loop(self, prepare, log, duration_s, extra_names, extra, watchdog, tap=None) -> SessionResult:  # noqa: C901
        codec = self.codec
        sock = self.sock
        recvfrom = sock.recvfrom
        sendto = sock.sendto
        robot = self.robot_ip
        mon = codec.new_monitoring()
        decode = codec.decode_monitoring
        frame = codec.frame
        cmd_hdr = codec.new_command()
        cmd_hdr.header.messageIdentifier = COMMAND_MESSAGE_ID
        cmd_hdr.header.sequenceCounter = 0
        cmd_hdr.header.reflectedSequenceCounter = 0
        cmd_pos = codec.new_command()
        cmd_pos.header.messageIdentifier = COMMAND_MESSAGE_ID
        cmd_pos.header.sequenceCounter = 0
        cmd_pos.header.reflectedSequenceCounter = 0
        jp = cmd_pos.commandData.jointPosition.value
        jp.extend([0.0] * 7)
        perf = time.perf_counter_ns
        mono = time.monotonic

        st = _Stats()
        lat = st.latencies
        layout: LogLayout | None = None
        plan: Plan | None = None
        rows: list[list[float]] = []
        guard: CommandGuard | None = None
        ball_k: int | None = None
        period_s: float | None = None
        prepare_ms: float | None = None
        period_key: tuple[int, int] | None = None  # (sendPeriod [ms], receiveMultiplier) the plan was made for
        t_per_tick = 0.0  # [s] per controller sequence step
        use_local_clock = False
        t_local0 = 0.0
        tick = 0
        last_seq = -1
        last_state = -1
        seen_session = False  # a non-IDLE state was seen
        commanding = False  # COMMANDING_WAIT or ACTIVE was seen
        was_active = False
        send_counter = 0
        backlog = 0  # messages dropped after preparing; they count toward receiveMultiplier like received ones
        client_seq = 0
        i_row = 0
        holding = 0  # remaining hold cycles
        hold_end: tuple[str, str] | None = None
        last_cmd: Sequence[float] | None = None
        cmd_in_force: Sequence[float] = (0.0,) * 7
        cmd_before: Sequence[float] = cmd_in_force
        prev_active = False
        outcome = end_reason = ""
        t_open = mono()
        t_first = None
        t_last_rx = t_open
        cpu0 = time.thread_time()
        cycles0 = 0

        while True:
            # ---- interrupt -------------------------------------------------------------------------------
            if self._interrupted and hold_end is None:
                if last_state == CMD_ACTIVE and plan is not None and last_cmd is not None:
                    holding = self.hold_cycles
                    hold_end = (INTERRUPTED, "interrupted (Ctrl-C): held the last command, then stopped")
                else:
                    outcome, end_reason = INTERRUPTED, "interrupted (Ctrl-C)"
                    break
            # ---- receive ---------------------------------------------------------------------------------
            try:
                data, addr = recvfrom(2048)
            except (TimeoutError, BlockingIOError, InterruptedError):
                now = mono()
                if watchdog is not None:
                    problem = watchdog()
                    if problem:
                        raise FriError(problem)
                if t_first is None:
                    if now - t_open > self.first_message_timeout_s:
                        raise FriError(self._no_message_text(st, now - t_open)) from None
                else:
                    if now - t_last_rx > self.silence_timeout_s:
                        outcome, end_reason = STOPPED, f"the controller was silent for {now - t_last_rx:.2f} s"
                        break
                    if duration_s is not None and now - t_first >= duration_s:
                        outcome, end_reason = COMPLETED, f"monitored for {duration_s:g} s"
                        break
                continue
            t_rx = perf()
            if addr[0] != robot:
                st.foreign += 1
                continue
            try:
                decode(data, mon)
            except FriDecodeError:
                st.malformed += 1
                continue
            seq = mon.header.sequenceCounter
            if last_seq >= 0:
                d = (seq - last_seq) & 0xFFFFFFFF
                if d == 0 or d > 0x7FFFFFFF:
                    st.stale += 1
                    continue
                st.missed += d - 1
                tick += d
            last_seq = seq
            st.cycles += 1
            now = mono()
            t_last_rx = now
            ci = mon.connectionInfo
            state = ci.sessionState
            if state != last_state:
                st.states.append(state)
                last_state = state
            ipo_q = mon.ipoData.jointPosition.value

            # ---- first message: columns and time base; first session message: period and plan ------------
            if t_first is None:
                t_first = now
                if ci.sendPeriod:
                    t_per_tick = ci.sendPeriod * 1e-3
                else:
                    use_local_clock = True
                    t_local0 = time.perf_counter()
                layout = LogLayout(mon, self.version, extra_names)
                ball_k = layout.io_column("ball_theta")
                if log is not None:
                    log.start(layout)
                cmd_in_force = tuple(ipo_q) if len(ipo_q) == 7 else tuple(mon.monitorData.measuredJointPosition.value)
            t = (time.perf_counter() - t_local0) if use_local_clock else tick * t_per_tick
            if period_key is None and state != IDLE:
                period_key = (ci.sendPeriod, ci.receiveMultiplier or 1)
                period_s = ci.sendPeriod * 1e-3 * period_key[1] if ci.sendPeriod else None
                if prepare is not None:
                    try:
                        if period_s is None:
                            raise FriError("the controller did not send its send period; cannot stream a trajectory")
                        if self.limits is None:
                            raise FriError("a session that commands motion needs the joint limits for its guard")
                        plan = prepare(mon, period_s)
                    except BaseException:
                        if log is not None:
                            log.write(self._row(layout, t, mon, cmd_in_force, -1, 0, 0, PHASE_NONE, -1, extra))
                        raise
                    if plan is not None:
                        rows = plan.rows.tolist()  # Python floats, one list per row (fast to hand to protobuf)
                        guard = CommandGuard.from_limits(self.limits, period_s)
                    # messages that queued up while preparing are stale: drop them (the sequence gap counts them
                    # as missed) so that the next reply goes to a fresh message, not to a backlog
                    backlog = self._drain()
                    st.skipped += backlog
                    t_ready = perf()
                    prepare_ms = (t_ready - t_rx) * 1e-6
                    t_rx = t_ready  # the reply latency statistics exclude the one-off preparation
                cpu0 = time.thread_time()  # the per-cycle cost excludes the one-off preparation
                cycles0 = st.cycles

            # ---- end conditions seen in this message -----------------------------------------------------
            end: tuple[str, str] | None = None
            ri = mon.robotInfo
            if state == IDLE:
                if seen_session:
                    end = (STOPPED, "the robot application closed the FRI session (IDLE)")
            else:
                seen_session = True
                if state >= CMD_WAIT:
                    commanding = True
                if plan is not None:
                    if (ci.sendPeriod, ci.receiveMultiplier or 1) != period_key:
                        end = (
                            STOPPED,
                            f"the controller changed its period from {period_key[0]} ms × {period_key[1]} to "  # type: ignore[index]
                            f"{ci.sendPeriod} ms × {ci.receiveMultiplier or 1}",
                        )
                    elif ri.safetyState != 0:
                        end = (STOPPED, f"safety stop ({SafetyState(ri.safetyState).name})")
                    elif commanding:
                        drives = ri.driveState
                        if drives and min(drives) != _DRIVE_ACTIVE:  # ACTIVE is the highest drive state
                            end = (STOPPED, "drives not active")
                        elif ci.quality == _POOR:
                            end = (STOPPED, "connection quality POOR")
                        elif was_active and state != CMD_ACTIVE:
                            end = (STOPPED, f"the session left COMMANDING_ACTIVE ({SessionState(state).name})")
                    if end is None and not commanding and self.commanding_timeout_s is not None:
                        if now - t_first > self.commanding_timeout_s:
                            end = (
                                STOPPED,
                                f"the robot application did not start commanding within {self.commanding_timeout_s:g} s "
                                f"(session state {SessionState(state).name})",
                            )
            if end is None and duration_s is not None and now - t_first >= duration_s:
                end = (COMPLETED, f"monitored for {duration_s:g} s")

            # ---- reply -----------------------------------------------------------------------------------
            cmd_before = cmd_in_force  # the command the controller has been executing until this cycle
            answered = sent = 0
            phase = PHASE_NONE
            row_idx = -1
            reply = None
            if end is None and state != IDLE:
                send_counter += 1
                due = send_counter >= (ci.receiveMultiplier or 1)
                if due:
                    send_counter = 0
                if backlog:  # they arrived after this message: every k-th stays aligned with the controller
                    send_counter = (send_counter + backlog) % (ci.receiveMultiplier or 1)
                    backlog = 0
                if due:
                    if state == CMD_ACTIVE:
                        was_active = True
                        if plan is None:
                            jp[:] = ipo_q
                            cmd_in_force = last_cmd = tuple(ipo_q)
                            phase = PHASE_MIRROR
                            reply = cmd_pos
                        else:
                            if last_cmd is None:  # ACTIVE without a COMMANDING_WAIT before: start from ipo
                                last_cmd = tuple(ipo_q)
                            if holding:
                                q = last_cmd
                                phase = PHASE_HOLD
                                holding -= 1
                            elif i_row < len(rows):
                                q = rows[i_row]
                                phase, row_idx = plan.phase(i_row)
                                reason = guard.refuse(last_cmd, q)  # type: ignore[union-attr]
                                if reason is not None:
                                    q = last_cmd
                                    phase, row_idx = PHASE_HOLD, -1
                                    holding = self.hold_cycles - 1
                                    hold_end = (REFUSED, f"guard refused the command for plan row {i_row}: {reason}")
                                else:
                                    i_row += 1
                                    if phase == PHASE_SETTLE:
                                        st.settle_rows += 1
                                    elif row_idx >= 0:
                                        st.traj_rows += 1
                                    else:
                                        st.move_rows += 1
                            else:
                                q = None
                                end = (COMPLETED, "trajectory streamed and settled")
                            if q is not None:
                                jp[:] = q
                                cmd_in_force = last_cmd = q
                                reply = cmd_pos
                                if hold_end is not None and holding == 0:
                                    end = hold_end
                    elif state == CMD_WAIT:
                        jp[:] = ipo_q
                        cmd_in_force = last_cmd = tuple(ipo_q)
                        reply = cmd_pos
                    else:
                        reply = cmd_hdr
                        if len(ipo_q) == 7:
                            cmd_in_force = tuple(ipo_q)
                    if reply is not None:
                        h = reply.header
                        h.sequenceCounter = client_seq
                        h.reflectedSequenceCounter = seq
                        sendto(frame(reply.SerializeToString()), addr)
                        lat.append(perf() - t_rx)
                        answered = 1
                        sent = 1 if reply is cmd_pos else 0
                        client_seq = (client_seq + 1) & 0xFFFFFFFF
                        st.answered += 1
                        st.position_commands += sent
            elif state == IDLE and len(ipo_q) == 7 and not commanding:
                cmd_in_force = tuple(ipo_q)

            # ---- log and figures (after the reply went out) ----------------------------------------------
            if log is not None:
                log.write(
                    layout.format(  # type: ignore[union-attr]
                        t, mon, cmd_in_force, client_seq - 1 if answered else -1, answered, sent, phase, row_idx,
                        extra(mon) if extra is not None else (),
                    )
                )  # fmt: skip
            elif ball_k is not None:
                layout.update_io(mon)  # type: ignore[union-attr]
            if tap is not None:
                tap(t, mon)
            if state == CMD_ACTIVE:
                st.active += 1
                tp = mon.ipoData.trackingPerformance
                if tp < st.min_tracking:
                    st.min_tracking = tp
                msr = mon.monitorData.measuredJointPosition.value
                if len(msr) == 7 and plan is not None:
                    e = max(map(abs, map(_sub, msr, cmd_in_force)))
                    if e > st.max_err:
                        st.max_err = e
                    if prev_active:
                        e = max(map(abs, map(_sub, msr, cmd_before)))
                        if e > st.max_err_prev:
                            st.max_err_prev = e
                prev_active = True
            else:
                prev_active = False
            if ball_k is not None:
                b = layout.io_values[ball_k]  # type: ignore[union-attr]
                if b > st.max_ball:
                    st.max_ball = b
                if phase == PHASE_SETTLE and b > st.residual_ball:
                    st.residual_ball = b
            if end is not None:
                outcome, end_reason = end
                break

        cpu = time.thread_time() - cpu0
        lat.sort()
        return SessionResult(
            outcome=outcome,
            end_reason=end_reason,
            cycles=st.cycles,
            answered=st.answered,
            position_commands=st.position_commands,
            missed=st.missed,
            stale=st.stale,
            foreign=st.foreign,
            malformed=st.malformed,
            skipped=st.skipped,
            prepare_ms=prepare_ms,
            states_seen=tuple(st.states),
            period_s=period_s,
            move_rows=st.move_rows,
            trajectory_rows=st.traj_rows,
            settle_rows=st.settle_rows,
            active_cycles=st.active,
            min_tracking=st.min_tracking if st.active else None,
            max_tracking_error=st.max_err if (st.active and plan is not None) else None,
            max_tracking_error_prev=st.max_err_prev if (st.active > 1 and plan is not None) else None,
            max_ball_theta=st.max_ball if ball_k is not None and st.cycles else None,
            residual_ball_theta=st.residual_ball if st.settle_rows and ball_k is not None else None,
            latency_p50_ms=_percentile_ms(lat, 50),
            latency_p99_ms=_percentile_ms(lat, 99),
            latency_max_ms=lat[-1] * 1e-6 if lat else None,
            cpu_us_per_cycle=cpu / (st.cycles - cycles0) * 1e6 if st.cycles > cycles0 else None,
            log_rows=log.rows if log is not None else 0,
        )

    def _drain(self) -> int:
        """Discard the datagrams waiting in the socket; their number."""
        n = 0
        self.sock.setblocking(False)
        try:
            while True:
                self.sock.recvfrom(2048)
                n += 1
        except (BlockingIOError, InterruptedError):
            pass
        finally:
            self.sock.settimeout(_RECV_TIMEOUT)
        return n

    @staticmethod
    def _row(layout, t, mon, cmd, client_seq, answered, sent, phase, row, extra) -> str:
        return layout.format(t, mon, cmd, client_seq, answered, sent, phase, row, extra(mon) if extra else ())

    def _no_message_text(self, st: _Stats, waited: float) -> str:
        text = f"no FRI monitoring message from {self.robot_ip} on UDP port {self.port} within {waited:.1f} s"
        hints = []
        if st.malformed:
            hints.append(f"{st.malformed} datagrams from it did not decode as FRI {self.version.value} (--fri-version?)")
        if st.foreign:
            hints.append(f"{st.foreign} datagrams came from other addresses (--robot?)")
        if not hints:
            hints.append("is the robot application running with this PC's address and port, and the firewall open?")
        return text + "; " + "; ".join(hints)


@contextlib.contextmanager
def sigint_interrupts(session: FriSession) -> Iterator[None]:
    """While active, Ctrl-C (SIGINT) and SIGTERM ask the session to end cleanly instead of raising."""
    handler = lambda signum, frame: session.interrupt()  # noqa: E731
    old_int = signal.signal(signal.SIGINT, handler)
    old_term = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old_int)
        signal.signal(signal.SIGTERM, old_term)
