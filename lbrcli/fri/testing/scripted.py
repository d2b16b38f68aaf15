"""A scripted FRI controller for testing clients: exact states per cycle, in lock-step with the client.

Unlike the simulator (real time, its own session logic), this controller sends the monitoring message of each
scripted cycle, waits for the reply the FRI rules require (receiveMultiplier counted as KUKA's client does) and
records it. It can inject what the simulator doesn't produce on demand: safety stops, drives off, POOR quality,
jumps in the sequence counter, malformed datagrams and datagrams from another address (127.0.0.2).
The simulated robot is ideal: in COMMANDING_ACTIVE the ipo and measured positions become the last command; a cycle
without a command (its message lost on the way to the client, its reply lost or missing) is bridged by extrapolating
at the last velocity, as KUKA's controller does. ``executed`` records where the robot was after every cycle and
``command_at`` which of those positions a received command set — the fault campaign measures each command against
what the robot executed before it (``command_ratios``).
"""

from __future__ import annotations

import socket
import threading
import time
from dataclasses import dataclass, field
from typing import Any, Callable

from ..codec import FriCodec
from ..constants import MONITORING_MESSAGE_ID
from ..errors import FriDecodeError

from ..constants import (
    STATE_COMMANDING_ACTIVE,
    STATE_COMMANDING_WAIT,
    STATE_IDLE,
    STATE_MONITORING_READY,
    STATE_MONITORING_WAIT,
)

MW = STATE_MONITORING_WAIT
"""Session state MONITORING_WAIT in a script."""
MR = STATE_MONITORING_READY
"""Session state MONITORING_READY in a script."""
CW = STATE_COMMANDING_WAIT
"""Session state COMMANDING_WAIT in a script."""
CA = STATE_COMMANDING_ACTIVE
"""Session state COMMANDING_ACTIVE in a script."""
IDLE = STATE_IDLE
"""Session state IDLE in a script."""


@dataclass(frozen=True)
class Cycle:
    """One scripted controller cycle."""

    state: int = MR
    quality: int = 3
    safety: int = 0
    drive: int = 2
    receive_multiplier: int = 1
    send_period: int = 1  # [ms]
    seq_jump: int = 0  # extra increment of the controller's sequence counter before this message (a gap)
    raw: bytes | None = None  # send these bytes instead of a message (malformed)
    foreign: bool = False  # send the message from 127.0.0.2 instead (must be ignored)
    repeat_seq: bool = False  # reuse the previous sequence counter (stale duplicate, must be ignored)
    ball: float | None = 0.01  # analog IO 'ball_theta' [rad] (None: no IO values)
    pause_s: float = 0.0  # [s] wait after sending this message (e.g. while the client prepares its plan)
    mode: int = 1  # clientCommandMode: 1 POSITION, 2 WRENCH, 3 TORQUE
    mutate: Callable | None = None  # edits the message before it is encoded (wrong-but-decodable messages)
    io_out: tuple = ()  # extra IO channels (name, type, direction, value) — outputs reflect the client's writes
    clock_ms: float | None = None  # [ms] the timestamp advances this much per sequence step (None: send_period)
    stale_by: int = 0  # > 0: send a message this many sequence steps old (reordered), expect no reply
    drop_reply: bool = False  # the reply to this message is lost (the controller never sees it)
    push: float = 0.0  # [rad] the robot is pushed: A1's measured position is this far from where it was commanded


@dataclass
class Reply:
    """One reply the client sent to a scripted message, decoded: counters, commanded positions [rad], torques [Nm],
    wrench [N, Nm] and IO writes."""

    cycle: int  # index in the script
    state: int
    seq: int  # of the monitoring message answered (expected)
    header: tuple[int, int]  # (sequenceCounter, reflectedSequenceCounter) of the reply
    position: tuple[float, ...] | None  # commandData.jointPosition (None: header only)
    torque: tuple[float, ...] | None = None
    wrench: tuple[float, ...] | None = None
    io: tuple = ()  # (name, value) written


@dataclass
class ScriptedController:
    """A fake FRI controller for tests: sends the `script` of cycles to a client on loopback, one message per cycle,
    and records every reply (`replies`), the cycles left unanswered and replies to messages that must be ignored."""

    client_port: int
    script: list[Cycle]
    q0: tuple[float, ...]
    version: str = "1.15"
    reply_timeout: float = 3.0  # [s] per expected reply
    pace_s: float = 0.0005  # [s] pause between cycles
    replies: list[Reply] = field(default_factory=list)
    unanswered: list[int] = field(default_factory=list)  # cycles whose expected reply did not come
    unexpected: list[int] = field(default_factory=list)  # replies reflecting a message that must not be answered
    sent_seqs: list[int] = field(default_factory=list)
    on_cycle: Callable[[int], None] | None = None  # called with the script index before each cycle is sent
    inputs: Callable[[int], dict] | None = None  # analog inputs {name: value} of the message of script index i
    tolerate_unanswered: int = 0  # expected replies that may be missing (e.g. a backlog the client dropped)
    wait_for_client: float = 0.0  # [s] > 0: repeat the first expected-reply cycle (new counters) until answered
    max_bridge: int | None = None  # more cycles than this without a command in COMMANDING_ACTIVE: the controller
    # stops the robot and reports POOR quality in MONITORING_READY from then on (as a real one does); None: never

    def __post_init__(self) -> None:
        self.codec = FriCodec(self.version)
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.foreign_sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.foreign_sock.bind(("127.0.0.2", 0))
        self.client_done = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.q = list(self.q0)
        self.io_values: dict = {}
        self.clock_ns = 0  # [ns] the controller's clock (timestamps), advanced per sequence step
        self.executed: list[tuple[float, ...]] = []  # [rad] the robot's position after each cycle (COMMANDING_WAIT on)
        self.command_at: list[int] = []  # indices into executed set by a received command
        self.periods: list[float] = []  # [s] the send period of each executed cycle
        self._vel = [0.0] * 7  # [rad/cycle] last commanded velocity (for extrapolation)
        self._bridged = 0  # consecutive COMMANDING_ACTIVE cycles without a command
        self.fell_back = False  # the controller stopped commanding because commands were missing
        self._i = 0  # the script index being sent
        self.late_replies = 0  # replies that came after the controller had given up on them (dropped)

    def _robot_step(self, c: Cycle, pos: tuple[float, ...] | None) -> None:
        """The robot's motion in one cycle: to the received command, else extrapolated (COMMANDING_ACTIVE)."""
        if c.state < CW:
            self._vel = [0.0] * 7
            return
        if c.state == CA and pos is None and self.max_bridge is not None:
            self._bridged += 1
            if self._bridged > self.max_bridge:
                self.fell_back = True
        elif c.state == CA:
            self._bridged = 0
        if c.state == CA and pos is not None:
            self._vel = [a - b for a, b in zip(pos, self.q)]
            self.q = list(pos)
            self.command_at.append(len(self.executed))
        elif c.state == CA:
            self.q = [a + v for a, v in zip(self.q, self._vel)]
        else:
            self._vel = [0.0] * 7
        self.executed.append(tuple(self.q))
        self.periods.append((c.clock_ms or c.send_period) * c.receive_multiplier * 1e-3)  # the true period

    def command_ratios(self, velocity, acceleration) -> tuple[float, float]:
        """Largest |command − executed before| / (velocity limit × period) and |second difference| / (acceleration
        limit × period²) over the received commands, against the robot's executed positions."""
        return self.motion_ratios(velocity, acceleration)[:2]

    def motion_ratios(self, velocity, acceleration, jerk=None, bridged: bool = False) -> tuple[float, float, float]:
        """As :meth:`command_ratios`, and the largest third difference / (jerk limit × period³) (0 without
        ``jerk``). ``bridged``: over the controller's own bridging steps (COMMANDING_ACTIVE cycles without a
        command, extrapolated) instead of the received commands."""
        step_r = second_r = third_r = 0.0
        e = self.executed
        steps = self.command_at
        if bridged:
            got = set(steps)
            start = steps[0] if steps else len(e)
            steps = [i for i in range(start, len(e)) if i not in got]
        for i in steps:
            if i < 2:
                continue
            dt = self.periods[i]
            for j in range(7):
                step = e[i][j] - e[i - 1][j]
                second = step - (e[i - 1][j] - e[i - 2][j])
                step_r = max(step_r, abs(step) / (velocity[j] * dt))
                second_r = max(second_r, abs(second) / (acceleration[j] * dt * dt))
                if jerk is not None and i >= 3:
                    third = second - ((e[i - 1][j] - e[i - 2][j]) - (e[i - 2][j] - e[i - 3][j]))
                    third_r = max(third_r, abs(third) / (jerk[j] * dt * dt * dt))
        return step_r, second_r, third_r

    def end_velocity(self, velocity) -> float:
        """The speed of the last received command relative to what the robot executed before it, as a fraction of
        the velocity limit (0: the client left the robot at rest; more: the controller must stop it itself)."""
        if not self.command_at:
            return 0.0
        i = self.command_at[-1]
        if i < 1:
            return 0.0
        e, dt = self.executed, self.periods[i]
        return max(abs(e[i][j] - e[i - 1][j]) / (velocity[j] * dt) for j in range(7))

    def efforts(self) -> tuple[float, float]:
        """(largest |change| of the commanded torque or wrench between two replies, |last effort sent|) over the
        replies that carried one [Nm or N]."""
        last = None
        worst = 0.0
        for r in self.replies:
            eff = r.torque if r.torque is not None else r.wrench
            if eff is None:
                continue
            if last is not None and len(last) == len(eff):
                worst = max(worst, max(abs(a - b) for a, b in zip(eff, last)))
            last = eff
        return worst, (max(abs(x) for x in last) if last else 0.0)

    def start(self) -> "ScriptedController":
        self.thread.start()
        return self

    def join(self, timeout: float = 30.0) -> None:
        self.thread.join(timeout)
        self.sock.close()
        self.foreign_sock.close()

    def finish(self, app: Any = None) -> None:
        """The client is done: end the script, wait for it and close ``app`` (a ClientApplication) if given."""
        self.client_done.set()
        self.join()
        if app is not None:
            app.close()

    def _message(self, c: Cycle, seq: int, reflected: int) -> bytes:
        m = self.codec.new_monitoring()
        m.header.messageIdentifier = MONITORING_MESSAGE_ID
        m.header.sequenceCounter = seq
        m.header.reflectedSequenceCounter = reflected
        m.connectionInfo.sessionState = c.state
        m.connectionInfo.quality = c.quality
        m.connectionInfo.sendPeriod = c.send_period
        m.connectionInfo.receiveMultiplier = c.receive_multiplier
        m.robotInfo.numberOfJoints = 7
        m.robotInfo.safetyState = c.safety
        m.robotInfo.driveState.extend([c.drive] * 7)
        m.robotInfo.operationMode = 0
        m.robotInfo.controlMode = 0
        md = m.monitorData
        md.measuredJointPosition.value.extend([self.q[0] + c.push, *self.q[1:]])
        md.measuredTorque.value.extend([1.0 + j for j in range(7)])
        md.externalTorque.value.extend([0.1 * j for j in range(7)])
        md.commandedTorque.value.extend([0.0] * 7)
        if self.version == "1.15":
            md.commandedJointPosition.value.extend(self.q)
        md.timestamp.sec = 1_700_000_000 + self.clock_ns // 1_000_000_000
        md.timestamp.nanosec = self.clock_ns % 1_000_000_000
        if c.ball is not None:
            io = md.readIORequest.add()
            io.name, io.type, io.direction, io.analogValue = "ball_theta", 2, 0, c.ball
            io = md.readIORequest.add()
            io.name, io.type, io.direction, io.digitalValue = "gripper", 1, 0, 1
        if self.inputs is not None:
            for name, value in self.inputs(self._i).items():
                io = md.readIORequest.add()
                io.name, io.type, io.direction, io.analogValue = name, 2, 0, value
        for name, kind, direction, value in c.io_out:
            io = md.readIORequest.add()
            io.name, io.type, io.direction = name, kind, direction
            v = self.io_values.get(name, value)
            if kind == 2:
                io.analogValue = v
            else:
                io.digitalValue = int(v)
        m.ipoData.jointPosition.value.extend(self.q)
        m.ipoData.clientCommandMode = c.mode
        m.ipoData.overlayType = 1
        m.ipoData.trackingPerformance = 1.0 if c.state == CA else 0.0
        if c.mutate is not None:
            c.mutate(m)
        return self.codec.encode(m)

    def _await_reply(self, deadline: float, expected: int | None = None):
        """The next command message before ``deadline``; with ``expected``, replies to older messages (late ones,
        a loaded client) are dropped and counted in ``late_replies``: the cycle they answered is long gone."""
        cmd = self.codec.new_command()
        while time.monotonic() < deadline:
            if self.client_done.is_set():
                self.sock.settimeout(0.05)
            else:
                self.sock.settimeout(max(0.001, min(0.2, deadline - time.monotonic())))
            try:
                data, _ = self.sock.recvfrom(4096)
            except (TimeoutError, socket.timeout):
                if self.client_done.is_set():
                    return None
                continue
            try:
                got = self.codec.decode_command(data, cmd)
            except FriDecodeError:
                continue
            if (
                expected is not None
                and 0 < ((expected - got.header.reflectedSequenceCounter) & 0xFFFFFFFF) < 0x80000000
            ):
                self.late_replies += 1
                continue
            return got
        return None

    def _await_client(self, c: Cycle, seq: int, reflected: int, dest: tuple[str, int]) -> tuple[Any, int]:
        """A client still starting up: send cycle ``c`` again (new counters) until the client answers the latest
        message or ``wait_for_client`` [s] passes; the reply (None: none) and the sequence counter reached."""
        give_up = time.monotonic() + self.wait_for_client
        cmd = self._await_reply(time.monotonic() + 0.02)
        while (cmd is None or cmd.header.reflectedSequenceCounter != seq) and time.monotonic() < give_up:
            if self.client_done.is_set():
                break
            if cmd is None:
                seq += 1
                self.clock_ns += int(round((c.clock_ms or c.send_period) * 1e6))  # its clock runs on
                self.sock.sendto(self._message(c, seq, reflected), dest)
                self.sent_seqs.append(seq)
            cmd = self._await_reply(time.monotonic() + 0.02)
        self.wait_for_client = 0.0
        return cmd, seq

    def _record(self, i: int, c: Cycle, seq: int, cmd: Any) -> tuple[float, ...] | None:
        """Record the client's reply ``cmd`` to script cycle ``i`` (``replies``, its IO writes); the joint position it
        commands [rad] (None: none)."""
        pos = tuple(cmd.commandData.jointPosition.value) if cmd.HasField("commandData") else None
        if pos is not None and len(pos) == 0:
            pos = None
        cd = cmd.commandData
        tau = tuple(cd.jointTorque.value) or None
        wr = tuple(cd.cartesianWrenchFeedForward.element) or None
        io = tuple((w.name, w.analogValue if w.type == 2 else w.digitalValue) for w in cd.writeIORequest)
        for name, v in io:
            self.io_values[name] = v
        header = (cmd.header.sequenceCounter, cmd.header.reflectedSequenceCounter)
        self.replies.append(Reply(i, c.state, seq, header, pos, tau, wr, io))
        return pos

    def _run(self) -> None:
        seq = -1
        reflected = 0
        send_counter = 0
        dest = ("127.0.0.1", self.client_port)
        for i, c in enumerate(self.script):
            self._i = i
            if self.on_cycle is not None:
                self.on_cycle(i)
            if self.fell_back and c.state >= CW:
                self._vel = [0.0] * 7  # the controller stopped the robot
                c = Cycle(**{**c.__dict__, "state": MR, "quality": 0})
            if c.raw is not None:
                self.sock.sendto(c.raw, dest)
                time.sleep(self.pace_s)
                continue
            if c.foreign:  # another sender forging the next counter: the controller's own counter is not used
                self.foreign_sock.sendto(self._message(c, seq + 1, reflected), dest)
                time.sleep(self.pace_s)
                continue
            if not c.repeat_seq and not c.stale_by:
                seq += 1 + c.seq_jump
                if seq > 0:
                    self.clock_ns += int(round((1 + c.seq_jump) * (c.clock_ms or c.send_period) * 1e6))
                if c.state == CA:  # the cycles of the messages the client never got: bridged
                    for _ in range(c.seq_jump):
                        self._robot_step(c, None)
            data = self._message(c, max(seq - c.stale_by, 0), reflected)
            self.sock.sendto(data, dest)
            self.sent_seqs.append(seq)
            if c.pause_s:
                time.sleep(c.pause_s)
            if c.repeat_seq or c.stale_by:
                time.sleep(self.pace_s)
                continue
            expect = False
            if c.state != IDLE:
                send_counter += 1
                if send_counter >= c.receive_multiplier:
                    send_counter = 0
                    expect = True
            if not expect:
                if c.receive_multiplier == 1:  # (with k > 1 the robot interpolates between commands: not recorded)
                    self._robot_step(c, None)
                time.sleep(self.pace_s)
                continue
            if self.wait_for_client > 0:  # a client still starting up: keep sending until it answers the latest
                cmd, seq = self._await_client(c, seq, reflected, dest)
            else:
                cmd = self._await_reply(time.monotonic() + self.reply_timeout, seq)
            if cmd is None:
                self.unanswered.append(i)
                self._robot_step(c, None)
                if len(self.unanswered) <= self.tolerate_unanswered and not self.client_done.is_set():
                    continue
                return  # the client ended; so does the script
            if c.drop_reply:
                self._robot_step(c, None)
                time.sleep(self.pace_s)
                continue
            if cmd.header.reflectedSequenceCounter != seq:
                self.unexpected.append(i)
            reflected = cmd.header.sequenceCounter
            self._robot_step(c, self._record(i, c, seq, cmd))
            time.sleep(self.pace_s)


def preamble(**kw: Any) -> list[Cycle]:
    """The cycles before commanding: IDLE, MONITORING_WAIT (quality FAIR), MONITORING_READY, COMMANDING_WAIT."""
    return ([Cycle(state=IDLE, **kw)] + [Cycle(state=MW, quality=1, **kw)] * 3 + [Cycle(state=MR, **kw)] * 3
            + [Cycle(state=CW, **kw)] * 4)  # fmt: skip


def active(n: int, at: dict[int, Cycle] | None = None, **kw: Any) -> list[Cycle]:
    """n COMMANDING_ACTIVE cycles; ``at`` replaces (or, for lists, inserts) cycles at those indices."""
    out: list[Cycle] = [Cycle(state=CA, **kw)] * n
    for i in sorted(at or {}, reverse=True):
        c = at[i]
        out[i : i + 1] = c if isinstance(c, list) else [c]
    return out


def session_script(n: int, at: dict[int, Cycle] | None = None, **kw: Any) -> list[Cycle]:
    """A whole session: the preamble, then ``n`` COMMANDING_ACTIVE cycles (``at``: see :func:`active`)."""
    return preamble(**kw) + active(n, at, **kw)
