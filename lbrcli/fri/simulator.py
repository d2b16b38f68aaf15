"""The FRI controller simulator: the robot side of an FRI session on real UDP sockets.

Every send period the simulator sends a monitoring message to the client and collects the client's command
messages until the next send. A cycle counts as timely when a reply to the message just sent arrives before
the next send (with receiveMultiplier k: one such reply within k cycles); the connection quality is the share
of timely cycles in a sliding window, and the session state follows it (``sim_session``). In
COMMANDING_ACTIVE the commanded joint positions drive an interpolator within the velocity and acceleration
limits (tracking performance < 1 when it clips); the measured torques are the inverse dynamics of the
interpolated motion; a ball on a string hanging from the TCP is integrated with the shared pendulum model and
reported as analog IO values. Faults (loss, delay, jitter, malformed datagrams) can be injected.

The ball reported in the message of cycle k is its state at cycle k−1: the TCP acceleration at a sample is
the second difference of the TCP positions around it (as ``planners.pendulum.SampledAcceleration``).
"""

from __future__ import annotations

import gc
import heapq
import math
import multiprocessing as mp
import os
import random
import select
import signal
import socket
import struct
import time
from dataclasses import asdict, dataclass, field
from typing import Callable

import numpy as np

from trajectories.errors import FriDecodeError, FriError, FriForeignMessage, OptionError

from .codec import FriCodec
from .constants import (
    COMMAND_MESSAGE_ID,
    MAX_DATAGRAM,
    MONITORING_MESSAGE_ID,
    N_JOINTS,
    ClientCommandMode,
    ConnectionQuality,
    ControlMode,
    DriveState,
    OperationMode,
    OverlayType,
    SafetyState,
    SessionState,
)
from .messages import FriVersion
from .sim_session import QualityMonitor, QualityThresholds, SessionMachine, SessionTiming

THESIS_Q0 = (0.0, 0.071, 0.0, -1.3523, 0.0, 0.1301, 0.0)  # [rad], thesis §5.3.2 start pose
BALL_IO_NAMES = ("ball_theta", "ball_phi", "ball_theta_x", "ball_theta_y")  # [rad], analog readIORequest values
OPERATION_MODES = {"T1": OperationMode.TEST_MODE_1, "T2": OperationMode.TEST_MODE_2, "AUT": OperationMode.AUTOMATIC_MODE}
_RING = 1 << 19  # per-cycle records kept for the timing statistics (8.7 min at 1 kHz)
_U32 = 0xFFFFFFFF
_SO_TIMESTAMPNS = getattr(socket, "SO_TIMESTAMPNS", None)
_TIMESPEC = struct.Struct("@qq")  # struct timespec (64-bit Linux)
_ANC_SIZE = socket.CMSG_SPACE(_TIMESPEC.size) if _SO_TIMESTAMPNS is not None else 0


@dataclass(frozen=True)
class SimConfig:
    """Everything the simulated controller needs; picklable (it crosses into the simulator process)."""

    client_host: str = "127.0.0.1"  # where monitoring messages are sent
    client_port: int = 30200
    host: str = "127.0.0.1"  # simulator's own bind address
    port: int = 0  # 0 = ephemeral
    period_ms: int = 1  # send period [ms], 1..100
    receive_multiplier: int = 1  # the client answers every k-th message
    version: str = "1.15"
    q0: tuple[float, ...] = THESIS_Q0  # [rad], robot standing here at start
    flange: str = "touch-electric"
    tool: tuple[float, float, float] = (0.0, 0.0, 0.0)  # [m] in the flange frame; the ball hangs from the TCP
    ball_length: float | None = None  # [m] string length of the simulated ball (None: no ball)
    ball_damping: float = 0.0  # [1/s]
    commanding_after_s: float = 0.2  # time in MONITORING_READY before the overlay starts
    session_duration_s: float | None = None  # COMMANDING_ACTIVE length before the app ends the session
    max_runtime_s: float | None = None  # hard stop of the simulator
    loss: float = 0.0  # probability of dropping an outgoing monitoring message
    delay_ms: float = 0.0  # [ms] added to every outgoing message
    jitter_ms: float = 0.0  # [ms] extra uniform random delay 0..jitter
    malformed: float = 0.0  # probability of sending a corrupted datagram instead of the message
    seed: int = 0
    # session and quality
    quality_window: int = 50  # [cycles] sliding window of the connection quality
    quality_fair: float = 0.5  # share of timely cycles for FAIR
    quality_good: float = 0.9  # ... for GOOD (needed for commanding)
    quality_excellent: float = 0.98  # ... for EXCELLENT
    wait_cycles: int = 10  # mirroring commands needed in COMMANDING_WAIT
    mirror_tolerance: float = 1e-3  # [rad] command vs ipo position in COMMANDING_WAIT
    end_delay_s: float = 0.1  # monitoring after the overlay ended, before IDLE
    idle_messages: int = 3
    # robot
    operation_mode: str = "T1"  # T1, T2 or AUT
    limits_path: str | None = None  # TOML overriding the joint limits
    torque_noise: float = 0.0  # [Nm] standard deviation added to the measured torques
    # timing
    spin_us: float = 200.0  # [µs] busy-wait before each send deadline (sleep until then)
    realtime: bool = False  # run the loop with real-time scheduling (SCHED_FIFO) if the OS permits
    # the thesis's pendulum module (ch. 6) emulated on a pseudo-terminal: the ball's planar angle θy and its rate
    # as AS5600 lines, the path is reported by SimulatorProcess.pendulum_path (needs ball_length)
    pendulum_pty: bool = False
    pendulum_rate_hz: float = 200.0  # [Hz] readings per second on the serial line

    def validate(self) -> None:
        """Raise OptionError naming the bad value."""

        def bad(msg: str) -> None:
            raise OptionError(msg)

        if not (isinstance(self.period_ms, int) and 1 <= self.period_ms <= 100):
            bad(f"--period: send period must be an integer 1..100 ms, got {self.period_ms}")
        if not (isinstance(self.receive_multiplier, int) and 1 <= self.receive_multiplier <= 100):
            bad(f"--receive-multiplier: must be an integer 1..100, got {self.receive_multiplier}")
        try:
            FriVersion(self.version)
        except ValueError:
            bad(f"--fri-version: must be 1.15 or 2.7, got {self.version!r}")
        for name, p in (("--loss", self.loss), ("--malformed", self.malformed)):
            if not 0.0 <= p <= 1.0:
                bad(f"{name}: probability must be in [0, 1], got {p:g}")
        for name, v in (("--delay", self.delay_ms), ("--jitter", self.jitter_ms)):
            if not (math.isfinite(v) and 0.0 <= v <= 1000.0):
                bad(f"{name}: must be 0..1000 ms, got {v:g}")
        if len(self.q0) != N_JOINTS or not all(math.isfinite(x) for x in self.q0):
            bad(f"--q0: expected {N_JOINTS} finite joint angles")
        if self.pendulum_pty and self.ball_length is None:
            bad("the pendulum module emulation needs a simulated ball (--length)")
        if not (math.isfinite(self.pendulum_rate_hz) and 1.0 <= self.pendulum_rate_hz <= 10000.0):
            bad(f"pendulum rate must be 1..10000 Hz, got {self.pendulum_rate_hz:g}")
        if self.ball_length is not None and not (math.isfinite(self.ball_length) and self.ball_length > 0):
            bad(f"--length: string length must be > 0 m, got {self.ball_length:g}")
        if not (math.isfinite(self.ball_damping) and self.ball_damping >= 0):
            bad(f"--damping: must be >= 0 1/s, got {self.ball_damping:g}")
        for name, port in (("--port", self.port), ("--client port", self.client_port)):
            if not 0 <= port <= 65535:
                bad(f"{name}: not a UDP port: {port}")
        if self.client_port == 0:
            bad("--client: the client port must not be 0")
        if self.operation_mode not in OPERATION_MODES:
            bad(f"--operation-mode: one of {', '.join(OPERATION_MODES)}, got {self.operation_mode!r}")
        if not 0.0 < self.quality_good <= 1.0:
            bad(f"--quality-good: share of timely cycles must be in (0, 1], got {self.quality_good:g}")
        if not 0.0 <= self.quality_fair <= self.quality_good <= self.quality_excellent <= 1.0:
            bad("quality thresholds must satisfy 0 <= fair <= good <= excellent <= 1")
        if not 1 <= self.quality_window <= 100_000:
            bad(f"--quality-window: must be 1..100000 cycles, got {self.quality_window}")
        if self.wait_cycles < 1:
            bad(f"wait_cycles must be >= 1, got {self.wait_cycles}")
        for name, v in (("--duration", self.session_duration_s), ("--timeout", self.max_runtime_s)):
            if v is not None and not (math.isfinite(v) and v > 0):
                bad(f"{name}: must be > 0 s, got {v:g}")


@dataclass(frozen=True)
class SimStats:
    """What happened in a simulated session (counts of cycles and datagrams, timing in ms)."""

    cycles: int  # monitoring cycles run
    replies: int  # valid command messages received
    late_replies: int  # replies to an earlier message than the last one sent
    missed_replies: int  # reply slots (k cycles) without a timely reply, counted from the first reply on
    malformed_received: int  # undecodable datagrams (ignored)
    foreign_received: int  # datagrams from another host or with a foreign message identifier (ignored)
    states_seen: tuple[int, ...]  # sequence of distinct session states in order
    safety_stop: bool
    min_tracking_performance: float  # over COMMANDING_ACTIVE cycles (1.0 if never active)
    commanded_rows: int  # commands executed in COMMANDING_ACTIVE
    max_ball_theta: float | None  # [rad]
    # additions (simulator helper)
    end_reason: str = ""  # duration, quality, safety_stop, stopped, max_runtime, or "" (still running)
    lost_sent: int = 0  # monitoring messages dropped by the loss injection
    malformed_sent: int = 0  # corrupted datagrams sent by the malformed injection
    client_sequence_gaps: int = 0  # client sequenceCounter not incremented by one
    overruns: int = 0  # cycles that started more than one period late (schedule re-synchronised)
    active_cycles: int = 0  # cycles in COMMANDING_ACTIVE
    period_ms_p50: float | None = None  # actual send period statistics [ms]
    period_ms_p99: float | None = None
    period_ms_max: float | None = None
    reply_latency_ms_p50: float | None = None  # send of a message → arrival of the reply reflecting it [ms]
    reply_latency_ms_p99: float | None = None
    reply_latency_ms_max: float | None = None
    final_q: tuple[float, ...] = ()  # [rad] robot position at the end
    work_us_p50: float | None = None  # per-cycle computation (state, interpolator, dynamics, ball, encode) [µs]
    work_us_p99: float | None = None
    cpu_fraction: float = 0.0  # CPU time of the loop / wall time (1.0 = a whole core)
    realtime: bool = False  # the loop ran with real-time scheduling

    def to_dict(self) -> dict:
        d = asdict(self)
        d["states_seen"] = [SessionState(s).name for s in self.states_seen]
        return d


def _percentiles(values: np.ndarray) -> tuple[float | None, float | None, float | None]:
    if len(values) == 0:
        return None, None, None
    p50, p99 = np.percentile(values, [50, 99])
    return float(p50), float(p99), float(values.max())


def _corrupt(data: bytes, rng: random.Random, framed: bool) -> bytes:
    """A damaged copy of a datagram that no FRI decoder accepts: truncated, a flipped byte, or garbage.

    1.x (no CRC): truncation inside the header field, or a byte sequence starting with the invalid tag 0.
    2.7: truncation (length mismatch) or one flipped payload byte (CRC-32 mismatch).
    """
    kind = rng.randrange(3)
    if kind == 0:  # truncated
        cut = rng.randrange(2, data[1] + 2) if not framed else rng.randrange(1, len(data) - 1)
        return data[:cut]
    if kind == 1 and framed:  # one payload byte flipped
        b = bytearray(data)
        b[rng.randrange(4, len(b) - 4)] ^= 1 << rng.randrange(8)
        return bytes(b)
    return b"\x00" + bytes(rng.getrandbits(8) for _ in range(rng.randrange(0, 64)))


class Simulator:
    """One simulated controller bound to a UDP socket; ``run()`` drives the session until it ends."""

    def __init__(
        self,
        config: SimConfig,
        stop: Callable[[], bool] | None = None,
        on_state: Callable[[SessionState, ConnectionQuality, float], None] | None = None,
    ) -> None:
        import pinocchio as pin

        from trajectories.limits import load_limits
        from trajectories.robot import Flange, Robot, RobotConfig

        from planners.pendulum import rk4_step_floats

        from .interpolator import Interpolator

        config.validate()
        self.cfg = config
        self._stop = stop or (lambda: False)
        self._on_state = on_state
        self.period = config.period_ms * 1e-3  # [s]
        self.codec = FriCodec(config.version)
        self.limits = load_limits(config.limits_path)
        if np.any(np.abs(config.q0) > self.limits.position):
            j = int(np.argmax(np.abs(config.q0) - self.limits.position))
            raise OptionError(f"--q0: q{j + 1} = {config.q0[j]:.4f} rad is outside the position limit "
                              f"±{self.limits.position[j]:.4f} rad")
        self.robot = Robot(RobotConfig(flange=Flange(config.flange), tool=tuple(config.tool)))
        self._pin = pin
        self._rk4 = rk4_step_floats
        k = config.receive_multiplier
        self.interp = Interpolator(np.array(config.q0, dtype=float), self.limits.velocity, self.limits.acceleration,
                                   self.period)
        self.quality_monitor = QualityMonitor(
            QualityThresholds(config.quality_window, config.quality_fair, config.quality_good, config.quality_excellent)
        )
        self.machine = SessionMachine(
            SessionTiming(config.commanding_after_s, config.wait_cycles, config.session_duration_s,
                          config.end_delay_s, config.idle_messages)
        )
        self._rng = random.Random(config.seed)
        self._nprng = np.random.default_rng(config.seed)
        self._mult = k
        try:
            self.client_ip = socket.gethostbyname(config.client_host)
        except OSError as exc:
            raise OptionError(f"--client: cannot resolve {config.client_host!r} ({exc})") from None
        self.client_addr = (self.client_ip, config.client_port)
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self.sock.bind((config.host, config.port))
        except OSError as exc:
            self.sock.close()
            raise FriError(f"simulator cannot bind {config.host}:{config.port} ({exc})") from None
        self.sock.setblocking(False)
        if _SO_TIMESTAMPNS is not None:
            self.sock.setsockopt(socket.SOL_SOCKET, _SO_TIMESTAMPNS, 1)
        self._build_messages()
        self._init_state()

    # -- setup -----------------------------------------------------------------------------------------------
    @property
    def address(self) -> tuple[str, int]:
        return self.sock.getsockname()[:2]

    def _build_messages(self) -> None:
        cfg = self.cfg
        m = self.codec.new_monitoring()
        m.header.messageIdentifier = MONITORING_MESSAGE_ID
        m.header.sequenceCounter = 0
        m.header.reflectedSequenceCounter = 0
        ri = m.robotInfo
        ri.numberOfJoints = N_JOINTS
        ri.safetyState = SafetyState.NORMAL_OPERATION
        ri.driveState.extend([DriveState.ACTIVE] * N_JOINTS)
        ri.operationMode = OPERATION_MODES[cfg.operation_mode]
        ri.controlMode = ControlMode.POSITION_CONTROLMODE
        ci = m.connectionInfo
        ci.sessionState = SessionState.MONITORING_WAIT
        ci.quality = ConnectionQuality.POOR
        ci.sendPeriod = cfg.period_ms
        ci.receiveMultiplier = cfg.receive_multiplier
        md = m.monitorData
        zeros = [0.0] * N_JOINTS
        md.commandedTorque.value.extend(zeros)
        md.externalTorque.value.extend(zeros)
        self._v_msr_q = md.measuredJointPosition.value
        self._v_msr_tau = md.measuredTorque.value
        self._v_ext_tau = md.externalTorque.value
        self._has_cmd_q = "commandedJointPosition" in md.DESCRIPTOR.fields_by_name
        self._v_cmd_q = md.commandedJointPosition.value if self._has_cmd_q else None
        self._ts = md.timestamp
        self._ts.sec = 0
        self._ts.nanosec = 0
        ipo = m.ipoData
        ipo.clientCommandMode = ClientCommandMode.POSITION
        ipo.overlayType = OverlayType.JOINT
        ipo.trackingPerformance = 0.0
        self._v_ipo_q = ipo.jointPosition.value
        self._io = []
        if cfg.ball_length is not None:
            ana = self.codec.msgs.enums["FriIOType"]["ANALOG"]
            inp = self.codec.msgs.enums["FriIODirection"]["INPUT"]
            for name in BALL_IO_NAMES:
                io = md.readIORequest.add()
                io.name, io.type, io.direction, io.analogValue = name, ana, inp, 0.0
                self._io.append(io)
        self.mon = m
        self._cmd = self.codec.new_command()

    def _init_state(self) -> None:
        n = N_JOINTS
        self._hold = self.interp.q.copy()  # [rad] where the robot stands outside COMMANDING_ACTIVE
        self._cmd_q = np.zeros(n)  # last received command [rad]
        self._cmd_refl = -1  # the monitoring counter the last received command reflects
        self._last_cmd = self.interp.q.copy()  # last command used [rad]
        self._last_refl = -1  # ... and the counter it reflected
        self._vel_est = np.zeros(n)  # commanded velocity [rad/cycle], for late or missing commands
        self._vel_cap = self.limits.velocity * self.period  # [rad/cycle] no faster extrapolation than allowed
        self._cmd_fresh = False  # a command with 7 positions arrived in this interval
        self._header_only = False  # a reply without joint positions arrived in this interval
        self._target = self.interp.q.copy()
        self._sub = 0  # fine-interpolation sub-step within a receive-multiplier slot
        self._sub_from = self.interp.q.copy()
        self._sub_to = self.interp.q.copy()
        self._seq = -1  # last monitoring sequence counter used
        self._reflect = 0  # last client sequence counter received
        self._last_client_seq: int | None = None
        self._timely = False
        self._since_timely = 0
        self._any_reply = False
        self._send_time = np.full(_RING, np.nan)  # actual send time of message seq % _RING (time.time) [s]
        self._cycle_time = np.empty(_RING)  # send instant of each cycle (perf_counter) [s]
        self._latency = np.empty(_RING)
        self._work = np.empty(_RING)  # computation time of each cycle [s]
        self._cpu_fraction = 0.0
        self._realtime = False
        self._n_latency = 0
        self._delay_line: list[tuple[float, int, bytes]] = []
        self._safety = False
        self._state = SessionState.MONITORING_WAIT
        self._quality = ConnectionQuality.POOR
        self._states_seen: list[int] = []
        self._tracking = 0.0
        self._min_tracking = 1.0
        self.counts = dict(
            cycles=0, replies=0, late=0, missed=0, malformed_rx=0, foreign_rx=0, commanded=0, lost=0,
            malformed_tx=0, gaps=0, overruns=0, active=0,
        )
        # ball
        self._ball = self.cfg.ball_length is not None
        p0 = self._tcp(self.interp.q).tolist()
        self._p0, self._p1 = p0, p0  # TCP positions at the last two cycles [m] (at rest before the start)
        self._acc_prev = (0.0, 0.0, 0.0)  # TCP acceleration at the sample before [m/s^2]
        self._s = (0.0, 0.0, -1.0)  # string direction (hanging)
        self._sdot = (0.0, 0.0, 0.0)  # [1/s]
        self._ball_angles = [0.0, 0.0, 0.0, 0.0]
        self._max_theta = 0.0
        self._pend = None
        self._pend_t = 0.0  # [s] simulated time of the pendulum emulation
        if self.cfg.pendulum_pty:
            from lbrcli.lab.pendulum_serial import PendulumEmulator

            self._pend = PendulumEmulator(rate_hz=self.cfg.pendulum_rate_hz)

    @property
    def pendulum_path(self) -> str | None:
        """Device path of the emulated pendulum module's serial port (None without the emulation)."""
        return self._pend.path if self._pend is not None else None

    def _tcp(self, q: np.ndarray) -> np.ndarray:
        pin, model, data = self._pin, self.robot.model, self.robot.data
        pin.forwardKinematics(model, data, q)
        pin.updateFramePlacement(model, data, self.robot.tcp_id)
        return data.oMf[self.robot.tcp_id].translation

    # -- receiving -------------------------------------------------------------------------------------------
    def _on_datagram(self, data: bytes, addr: tuple, arrival: float) -> None:
        """One received datagram; ``arrival`` its receive time (time.time seconds)."""
        c = self.counts
        if addr[0] != self.client_ip:
            c["foreign_rx"] += 1
            return
        cmd = self._cmd
        try:
            self.codec.decode_command(data, into=cmd)
        except FriForeignMessage:
            c["foreign_rx"] += 1
            return
        except FriDecodeError:
            c["malformed_rx"] += 1
            return
        c["replies"] += 1
        self._any_reply = True
        h = cmd.header
        seq = h.sequenceCounter
        if self._last_client_seq is not None and seq != ((self._last_client_seq + 1) & _U32):
            c["gaps"] += 1
        self._last_client_seq = seq
        self._reflect = seq
        refl = h.reflectedSequenceCounter
        if refl == (self._seq & _U32):
            self._timely = True
        else:
            c["late"] += 1
        sent = self._send_time[refl % _RING]
        if sent == sent and refl <= self._seq:  # not NaN: the message was actually sent
            self._latency[self._n_latency % _RING] = arrival - sent
            self._n_latency += 1
        jp = cmd.commandData.jointPosition.value
        if len(jp) == N_JOINTS:
            self._cmd_q[:] = jp
            self._cmd_fresh = True
            self._cmd_refl = refl
        else:
            self._header_only = True

    def _drain(self) -> None:
        """Read every datagram waiting in the socket (non-blocking)."""
        sock = self.sock
        while True:
            try:
                data, anc, _, addr = sock.recvmsg(MAX_DATAGRAM + 64, _ANC_SIZE)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:  # e.g. ICMP port unreachable reported on loopback: the client is not there (yet)
                continue
            arrival = None
            for level, kind, cdata in anc:  # the kernel's receive time: the latency without our own delays
                if level == socket.SOL_SOCKET and kind == _SO_TIMESTAMPNS and len(cdata) >= _TIMESPEC.size:
                    sec, nsec = _TIMESPEC.unpack_from(cdata)
                    arrival = sec + nsec * 1e-9
            self._on_datagram(data, addr, time.time() if arrival is None else arrival)

    def _flush_delay_line(self, now: float) -> float:
        """Send delayed datagrams that are due; returns the next due time (inf if none)."""
        line = self._delay_line
        while line and line[0][0] <= now:
            _, seq, data = heapq.heappop(line)
            self._sendto(data, seq)
        return line[0][0] if line else math.inf

    def _sendto(self, data: bytes, seq: int) -> None:
        """Send a datagram; ``seq`` >= 0 records its send time for the reply latency (on loopback the kernel
        delivers inside sendto, so the time is taken before)."""
        t = time.time()
        try:
            self.sock.sendto(data, self.client_addr)
        except OSError:
            return
        if seq >= 0:
            self._send_time[seq % _RING] = t

    def _wait_until(self, deadline: float) -> None:
        """Receive replies (and send delayed datagrams) until ``deadline`` (perf_counter seconds)."""
        spin = self.cfg.spin_us * 1e-6
        fd = [self.sock]
        while True:
            now = time.perf_counter()
            due = self._flush_delay_line(now) if self._delay_line else math.inf
            remaining = deadline - now
            if remaining <= 0.0:
                return
            timeout = min(remaining - spin, due - now)
            r, _, _ = select.select(fd, (), (), timeout if timeout > 0.0 else 0.0)
            if r:
                self._drain()

    # -- one cycle -------------------------------------------------------------------------------------------
    def _evaluate_interval(self) -> None:
        """Timeliness of the interval that just ended → quality."""
        if self._timely:
            self._since_timely = 0
        else:
            self._since_timely += 1
            if self._any_reply and self._since_timely % self._mult == 0:
                self.counts["missed"] += 1
        self._quality = self.quality_monitor.push(self._since_timely < self._mult)
        self._timely = False

    def _motion(self, state: SessionState, was: SessionState) -> None:
        ip = self.interp
        if state is SessionState.COMMANDING_ACTIVE:
            k = self._mult
            if was is not SessionState.COMMANDING_ACTIVE:
                # just entered: hold the mirrored position until the first command
                self._sub, self._sub_from[:], self._vel_est[:] = k, self._sub_to, 0.0
            elif self._cmd_fresh and self._cmd_refl > self._last_refl:
                # a new command, meant for the cycle after the message it reflects; a late one (reflecting an
                # older message) is carried forward by its lateness at the commands' velocity [rad/cycle]
                gap = self._cmd_refl - self._last_refl
                np.subtract(self._cmd_q, self._last_cmd, out=self._vel_est)
                self._vel_est /= gap if gap < 64 else np.inf
                np.clip(self._vel_est, -self._vel_cap, self._vel_cap, out=self._vel_est)
                self._last_cmd[:] = self._cmd_q
                self._last_refl = self._cmd_refl
                late = (self._seq & _U32) - self._cmd_refl
                self._sub_from[:] = self._target
                np.multiply(self._vel_est, late if 0 < late < 64 else 0, out=self._sub_to)
                self._sub_to += self._cmd_q
                self._sub = 0
                self.counts["commanded"] += 1
            elif self._sub >= k:
                # no command in time: bridge by extrapolating at the commands' velocity
                self._sub_from[:] = self._sub_to
                self._sub_to += k * self._vel_est
                self._sub = 0
            self._sub = min(self._sub + 1, k)
            w = self._sub / k
            np.multiply(self._sub_from, 1.0 - w, out=self._target)
            self._target += w * self._sub_to
            self._tracking = ip.step(self._target)
            if self._tracking < self._min_tracking:
                self._min_tracking = self._tracking
            self.counts["active"] += 1
        else:
            if was is SessionState.COMMANDING_ACTIVE:
                # leave the overlay: brake to a stop within the acceleration limits
                self._hold[:] = ip.q + ip.v * np.abs(ip.v) / (2.0 * ip.amax)
            ip.step(self._hold)
            self._tracking = 0.0
        self._cmd_fresh = False
        self._header_only = False

    def _check_command(self, state: SessionState) -> tuple[bool | None, bool]:
        """(mirror_ok for COMMANDING_WAIT, safety stop) from this interval's command."""
        if state is SessionState.COMMANDING_WAIT:
            if self._cmd_fresh:
                ok = bool(np.all(np.abs(self._cmd_q - self.interp.q) <= self.cfg.mirror_tolerance))
                if ok:
                    self._sub_from[:] = self._cmd_q
                    self._sub_to[:] = self._cmd_q
                    self._target[:] = self._cmd_q
                    self._last_cmd[:] = self._cmd_q
                    self._last_refl = self._cmd_refl
                return ok, False
            return (False if self._header_only else None), False
        if state is SessionState.COMMANDING_ACTIVE and self._cmd_fresh and not self._safety:
            q = self._cmd_q
            if not (np.all(np.isfinite(q)) and np.all(np.abs(q) <= self.limits.position)):
                self._safety = True
                self._cmd_fresh = False
                return None, True
        return None, False

    def _ball_step(self) -> None:
        """Advance the ball by one cycle (to the previous sample; see the module docstring)."""
        h = self.period
        p2, p1 = self._p1, self._p0
        p0 = self._tcp(self.interp.q).tolist()
        ih2 = 1.0 / (h * h)
        acc = ((p0[0] - 2.0 * p1[0] + p2[0]) * ih2, (p0[1] - 2.0 * p1[1] + p2[1]) * ih2,
               (p0[2] - 2.0 * p1[2] + p2[2]) * ih2)  # TCP acceleration at the previous sample [m/s^2]
        self._p0, self._p1 = p0, p1
        self._s, self._sdot = self._rk4(self._s, self._sdot, self._acc_prev, acc, h, self.cfg.ball_length,
                                        self.cfg.ball_damping)
        self._acc_prev = acc
        sx, sy, sz = self._s
        theta = math.acos(max(-1.0, min(1.0, -sz)))
        a = self._ball_angles
        a[0], a[1], a[2], a[3] = theta, math.atan2(sy, sx), math.atan2(sx, -sz), math.atan2(sy, -sz)
        if theta > self._max_theta:
            self._max_theta = theta
        for io, v in zip(self._io, a):
            io.analogValue = v
        if self._pend is not None:
            self._pend_t += h
            vx, vy, vz = self._sdot
            # θy = atan2(sy, −sz) and its rate, as the module's encoder on a y–z plane pendulum would read them
            omega = (sy * vz - sz * vy) / (sy * sy + sz * sz)
            self._pend.feed(self._pend_t, a[3], omega)

    def _fill_and_send(self, state: SessionState) -> None:
        m = self.mon
        ip = self.interp
        self._seq += 1
        seq = self._seq & _U32
        m.header.sequenceCounter = seq
        m.header.reflectedSequenceCounter = self._reflect
        m.connectionInfo.sessionState = state
        m.connectionInfo.quality = self._quality
        q = ip.q.tolist()
        self._v_msr_q[:] = q
        self._v_ipo_q[:] = q
        if self._v_cmd_q is not None:
            self._v_cmd_q[:] = self._target.tolist() if state is SessionState.COMMANDING_ACTIVE else q
        tau = self._pin.rnea(self.robot.model, self.robot.data, ip.q, ip.v, ip.a)
        if self.cfg.torque_noise > 0.0:
            tau = tau + self._nprng.normal(0.0, self.cfg.torque_noise, N_JOINTS)
        self._v_msr_tau[:] = tau.tolist()
        m.ipoData.trackingPerformance = self._tracking
        self._cycle_time[self._seq % _RING] = time.perf_counter()  # the send instant of this cycle
        ns = time.time_ns()
        self._ts.sec = (ns // 1_000_000_000) & _U32
        self._ts.nanosec = ns % 1_000_000_000
        data = self.codec.encode(m)
        cfg, rng = self.cfg, self._rng
        if cfg.loss > 0.0 and rng.random() < cfg.loss:
            self.counts["lost"] += 1
            return
        if cfg.malformed > 0.0 and rng.random() < cfg.malformed:
            self.counts["malformed_tx"] += 1
            data = _corrupt(data, rng, self.codec.framed)
            seq_mark = -1
        else:
            seq_mark = self._seq
        delay = cfg.delay_ms + (rng.random() * cfg.jitter_ms if cfg.jitter_ms > 0.0 else 0.0)
        if delay > 0.0:
            heapq.heappush(self._delay_line, (time.perf_counter() + delay * 1e-3, seq_mark, data))
        else:
            self._sendto(data, seq_mark)

    def _set_robot_info(self) -> None:
        ri = self.mon.robotInfo
        if self._safety and ri.safetyState != SafetyState.SAFETY_STOP_LEVEL_1:
            ri.safetyState = SafetyState.SAFETY_STOP_LEVEL_1
        if self._safety and not np.any(self.interp.v) and ri.driveState[0] != DriveState.OFF:
            ri.driveState[:] = [DriveState.OFF] * N_JOINTS  # stop category 1: stopped, then drives off

    # -- the loop --------------------------------------------------------------------------------------------
    def _enter_realtime(self) -> bool:
        """SCHED_FIFO for this process (Linux, needs the privilege); False if not granted."""
        try:
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(10))
            return True
        except (AttributeError, OSError):
            return False

    def run(self) -> SimStats:
        """Drive the session until it ends (IDLE sent), ``stop()`` says so, or max_runtime_s elapses."""
        period = self.period
        cfg = self.cfg
        c = self.counts
        self._realtime = self._enter_realtime() if cfg.realtime else False
        gc.collect()
        gc.freeze()  # the objects built so far are never collected again: short collections in the loop
        t0 = time.perf_counter()
        cpu0 = time.process_time()
        next_t = t0
        ppid = os.getppid()
        end_reason = ""
        k = 0
        try:
            while True:
                now = time.perf_counter()
                if now - next_t > period:  # fell behind by more than a cycle: re-synchronise
                    c["overruns"] += 1
                    next_t = now
                rel = next_t - t0
                was = self._state
                self._drain()  # replies waiting now arrived before the next send, even if this loop was late
                if k > 0 and was is not SessionState.IDLE:
                    self._evaluate_interval()
                mirror_ok, safety = self._check_command(was)
                state = self.machine.advance(rel, self._quality, mirror_ok, safety)
                self._motion(state, was)
                if self._ball:
                    self._ball_step()
                self._set_robot_info()
                if state is not was or not self._states_seen:
                    self._states_seen.append(int(state))
                    if self._on_state is not None:
                        self._on_state(state, self._quality, rel)
                self._state = state
                self._fill_and_send(state)
                self._work[k % _RING] = time.perf_counter() - now
                c["cycles"] += 1
                if state is SessionState.IDLE:
                    self.machine.note_idle_sent()
                    if self.machine.finished:
                        end_reason = self.machine.end_reason or "idle"
                        break
                if self._stop():
                    end_reason = "stopped"
                    break
                if cfg.max_runtime_s is not None and rel >= cfg.max_runtime_s:
                    end_reason = "max_runtime"
                    break
                if k % 512 == 0 and os.getppid() != ppid:
                    end_reason = "parent_exited"
                    break
                k += 1
                next_t += period
                self._wait_until(next_t)
            if self._delay_line:  # let in-flight delayed datagrams go out
                self._wait_until(min(max(d[0] for d in self._delay_line), time.perf_counter() + 0.2) + 1e-4)
        finally:
            self.sock.close()
            if self._pend is not None:
                self._pend.close()
            gc.unfreeze()
        wall = time.perf_counter() - t0
        self._cpu_fraction = (time.process_time() - cpu0) / wall if wall > 0 else 0.0
        return self._stats(c["cycles"], end_reason)

    def _stats(self, ncycles: int, end_reason: str) -> SimStats:
        c = self.counts
        n = min(ncycles, _RING)
        periods = np.diff(self._cycle_time[:n]) * 1e3 if ncycles <= _RING else np.diff(
            np.roll(self._cycle_time, -(ncycles % _RING))) * 1e3
        lat = self._latency[: min(self._n_latency, _RING)] * 1e3
        pp = _percentiles(periods)
        lp = _percentiles(lat)
        wp = _percentiles(self._work[:n] * 1e6)
        return SimStats(
            cycles=c["cycles"], replies=c["replies"], late_replies=c["late"], missed_replies=c["missed"],
            malformed_received=c["malformed_rx"], foreign_received=c["foreign_rx"],
            states_seen=tuple(self._states_seen), safety_stop=self._safety,
            min_tracking_performance=self._min_tracking, commanded_rows=c["commanded"],
            max_ball_theta=self._max_theta if self._ball else None, end_reason=end_reason,
            lost_sent=c["lost"], malformed_sent=c["malformed_tx"], client_sequence_gaps=c["gaps"],
            overruns=c["overruns"], active_cycles=c["active"],
            period_ms_p50=pp[0], period_ms_p99=pp[1], period_ms_max=pp[2],
            reply_latency_ms_p50=lp[0], reply_latency_ms_p99=lp[1], reply_latency_ms_max=lp[2],
            final_q=tuple(float(x) for x in self.interp.q),
            work_us_p50=wp[0], work_us_p99=wp[1], cpu_fraction=self._cpu_fraction, realtime=self._realtime,
        )


# -- the simulator in its own process ------------------------------------------------------------------------
def _child_main(config: SimConfig, conn, stop_event) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent decides when the simulator stops
    try:
        sim = Simulator(config, stop=stop_event.is_set)
    except BaseException as exc:  # noqa: BLE001 - reported to the parent as one line
        conn.send(("error", f"{exc}"))
        return
    conn.send(("bound", (sim.address, sim.pendulum_path)))
    try:
        stats = sim.run()
    except BaseException as exc:  # noqa: BLE001
        conn.send(("error", f"simulator failed: {type(exc).__name__}: {exc}"))
        return
    conn.send(("stats", stats))


@dataclass
class SimulatorProcess:
    """The simulator in a spawned process; context manager (``with SimulatorProcess(cfg) as sim: ...``)."""

    config: SimConfig
    address: tuple[str, int] | None = None
    pendulum_path: str | None = None  # the emulated pendulum module's serial device (config.pendulum_pty)
    stats: SimStats | None = None
    _proc: object = field(default=None, repr=False)
    _conn: object = field(default=None, repr=False)
    _stop: object = field(default=None, repr=False)

    def start(self, timeout: float = 60.0) -> "SimulatorProcess":
        """Start the process; returns once its socket is bound (``.address``). FriError if it cannot start."""
        self.config.validate()
        ctx = mp.get_context("spawn")
        parent, child = ctx.Pipe(duplex=False)
        self._stop = ctx.Event()
        self._proc = ctx.Process(target=_child_main, args=(self.config, child, self._stop), daemon=True,
                                 name="lbr-fri-sim")
        self._proc.start()
        child.close()
        self._conn = parent
        if not parent.poll(timeout):
            self._kill()
            raise FriError(f"FRI simulator did not start within {timeout:g} s")
        try:
            kind, payload = parent.recv()
        except EOFError:
            self._kill()
            raise FriError("FRI simulator process exited during start-up") from None
        if kind != "bound":
            self._proc.join(5)
            raise FriError(f"FRI simulator: {payload}")
        address, self.pendulum_path = payload
        self.address = tuple(address)
        return self

    def _receive_stats(self, timeout: float | None) -> SimStats | None:
        if self.stats is not None:
            return self.stats
        if self._conn is None:
            return None
        try:
            if not self._conn.poll(timeout):
                return None
            kind, payload = self._conn.recv()
        except (EOFError, OSError):
            self._proc.join(1)
            raise FriError("FRI simulator process ended without statistics") from None
        self._proc.join(5)
        if kind != "stats":
            raise FriError(f"FRI simulator: {payload}")
        self.stats = payload
        return payload

    def wait(self, timeout: float | None = None) -> SimStats | None:
        """Wait for the session to end by itself (IDLE or max_runtime_s); None on timeout."""
        return self._receive_stats(timeout)

    def stop(self, timeout: float = 5.0) -> SimStats:
        """End the loop, join the process and return the statistics."""
        if self.stats is not None:
            return self.stats
        if self._stop is not None:
            self._stop.set()
        stats = self._receive_stats(timeout)
        if stats is None:
            self._kill()
            raise FriError(f"FRI simulator did not stop within {timeout:g} s")
        return stats

    def _kill(self) -> None:
        if self._proc is not None and self._proc.is_alive():
            self._proc.terminate()
            self._proc.join(2)

    @property
    def running(self) -> bool:
        return self._proc is not None and self._proc.is_alive()

    def __enter__(self) -> "SimulatorProcess":
        return self if self.address is not None else self.start()

    def __exit__(self, *exc) -> None:
        if self.stats is None and self._proc is not None:
            try:
                self.stop()
            except FriError:
                pass
