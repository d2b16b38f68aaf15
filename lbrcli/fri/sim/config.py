"""What the simulated controller is configured with: the robot application, its FRI configuration, faults, timing.

``SimConfig`` is frozen and picklable (it crosses into the simulator process); ``validate()`` raises SettingError
naming the field (``SimConfig.period_ms``; the command line names its option). ``IoChannel`` is one IO of the
application's FRI IO configuration.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from trajectories.errors import SettingError
from trajectories.start_poses import THESIS_START

from ..constants import N_JOINTS, OperationMode
from ..messages import FriVersion

THESIS_Q0 = THESIS_START  # [rad], thesis §5.3.2 start pose
"""The thesis start pose (§5.3.2) [rad]: where the simulated robot stands unless told otherwise."""
OPERATION_MODES = {
    "T1": OperationMode.TEST_MODE_1,
    "T2": OperationMode.TEST_MODE_2,
    "AUT": OperationMode.AUTOMATIC_MODE,
}
COMMAND_MODES = ("position", "torque", "wrench", "cartesian")  # the overlay's client command mode (cartesian: 2.7)
MAX_TRANSFORMATIONS = 5  # requested transformations a 2.7 message carries at most (KUKA's SDK: 5, names < 64 bytes)
IO_TYPES = ("boolean", "digital", "analog")  # FriIOType 0, 1, 2
IO_DIRECTIONS = ("in", "out")  # FriIODirection INPUT = 0, OUTPUT = 1


@dataclass(frozen=True)
class IoChannel:
    """One IO of the robot application's FRI IO configuration (sent in every monitoring message)."""

    name: str
    type: str = "analog"  # boolean, digital or analog
    direction: str = "in"  # in (INPUT: the controller reports it) or out (OUTPUT: the client may write it)
    value: float = 0.0  # initial value (boolean: 0/1, digital: unsigned integer)

    @property
    def is_output(self) -> bool:
        return self.direction == "out"

    @property
    def is_analog(self) -> bool:
        return self.type == "analog"

    def validate(self) -> None:
        if not self.name or len(self.name) > 60:
            raise SettingError(IoChannel, "name", f"channel name must be 1..60 characters, got {self.name!r}")
        if self.type not in IO_TYPES:
            raise SettingError(
                IoChannel, "type", f"{self.name}: type must be one of {', '.join(IO_TYPES)}, got {self.type!r}"
            )
        if self.direction not in IO_DIRECTIONS:
            raise SettingError(
                IoChannel, "direction", f"{self.name}: direction must be in or out, got {self.direction!r}"
            )
        if not math.isfinite(self.value) or (not self.is_analog and (self.value < 0 or self.value != int(self.value))):
            raise SettingError(IoChannel, "value", f"{self.name}: bad initial value {self.value!r}")


def parse_io(text: str) -> IoChannel:
    """``NAME:TYPE:DIRECTION[:VALUE]`` (TYPE boolean|digital|analog, DIRECTION in|out) → IoChannel.
    The name may itself contain no colon; SettingError (``IoChannel.spec``) on anything else."""
    parts = text.split(":")
    if len(parts) not in (3, 4):
        raise SettingError(IoChannel, "spec", f"expected NAME:TYPE:DIRECTION[:VALUE], got {text!r}")
    value = 0.0
    if len(parts) == 4:
        try:
            value = float(parts[3])
        except ValueError:
            raise SettingError(IoChannel, "value", f"initial value must be a number, got {parts[3]!r}") from None
    ch = IoChannel(parts[0], parts[1].lower(), parts[2].lower(), value)
    ch.validate()
    return ch


# IO configurations of KUKA's example applications (the IOAccess client aborts if a channel is missing)
IO_PRESETS: dict[str, tuple[IoChannel, ...]] = {
    "kuka-ioaccess": (
        IoChannel("FRI.Out_Analog_Deci_Seconds", "analog", "out"),
        IoChannel("FRI.Out_Integer_Seconds", "digital", "out"),
        IoChannel("FRI.In_Bool_Clock_Enabled", "boolean", "in", 1.0),
    ),
}
"""IO channel sets of KUKA's example applications by name (the simulator's IO presets); the IOAccess client aborts if a
channel is missing."""


def lenient_quality(period_ms: int, receive_multiplier: int = 1) -> dict[str, float | int]:
    """SimConfig quality thresholds that tolerate a loaded PC: a 1 s window, GOOD at 50 % timely replies (default:
    50 cycles, 90 %, as strict as the real controller)."""
    return dict(
        quality_window=max(50, round(1000 / (period_ms * receive_multiplier))),
        quality_good=0.5,
        quality_fair=0.3,
        quality_excellent=0.9,
    )


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
    tool: tuple[float, float, float] = (0.0, 0.0, 0.0)  # [m] in the flange frame: the TCP (Cartesian pose, plants)
    commanding_after_s: float = 0.2  # [s] from the first MONITORING_READY until the overlay starts
    session_duration_s: float | None = None  # [s] COMMANDING_ACTIVE length (no overlay: from the first READY)
    max_runtime_s: float | None = None  # [s] hard stop of the simulator (it closes the session: IDLE)
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
    # robot application: FRI overlay configuration
    operation_mode: str = "T1"  # T1, T2 or AUT
    overlay: bool = True  # False: the application only monitors the session (no COMMANDING states)
    command_mode: str = "position"  # position (joint position overlay), torque (joint impedance), wrench (Cartesian
    # impedance), cartesian (FRI 2.7 CARTESIAN_POSE: the client commands the TCP pose and E1, position control)
    transformations: tuple[str, ...] = ()  # FRI 2.7: frames the application asks the client to provide (names)
    joint_stiffness: float = 1000.0  # [Nm/rad] joint impedance (torque mode), every joint
    cartesian_stiffness: tuple[float, float] = (2000.0, 200.0)  # [N/m], [Nm/rad] Cartesian impedance (wrench mode)
    nullspace_stiffness: float = 20.0  # [Nm/rad] joint stiffness in the null space of the Cartesian impedance
    damping_ratio: float = 0.7  # Lehr's damping of the impedance controllers
    io: tuple[IoChannel, ...] = ()  # the application's FRI IO configuration (plants add their inputs)
    plants: tuple = ()  # PlantSpec objects (see lbrcli.fri.sim.plant): things attached to the flange
    # robot
    limits_path: str | None = None  # TOML overriding the joint limits
    torque_noise: float = 0.0  # [Nm] standard deviation added to the measured torques
    external_torque: tuple[float, ...] = (0.0,) * N_JOINTS  # [Nm] a constant push on the joints (by the environment)
    external_force: tuple[float, ...] = (0.0,) * 6  # [N, Nm] a constant wrench on the TCP, base-frame axes
    # timing
    spin_us: float = 200.0  # [µs] busy-wait before each send deadline (sleep until then)
    realtime: bool = False  # run the loop with real-time scheduling (SCHED_FIFO) if the OS permits
    # lock-step: after each message the client must answer, wait for its reply (at most this long [s]) before the
    # next cycle; the session's clock and the plants advance one period per cycle whatever the wall clock does, so
    # a closed loop behaves the same on a busy machine (it only runs slower). None: real time, as a controller.
    lockstep_timeout_s: float | None = None
    # lock-step only: start the next cycle as soon as the reply is in instead of on the period's grid — the session
    # runs as fast as client and simulator compute (its clock, plants and sensors still one period per cycle)
    lockstep_free: bool = False

    @property
    def fri_version(self) -> FriVersion:
        return FriVersion(self.version)

    def validate(self) -> None:
        """Raise SettingError naming the bad field (``SimConfig.field``)."""

        def bad(field: str, msg: str) -> None:
            raise SettingError(SimConfig, field, msg)

        if not (isinstance(self.period_ms, int) and 1 <= self.period_ms <= 100):
            bad("period_ms", f"send period must be an integer 1..100 ms, got {self.period_ms}")
        if not (isinstance(self.receive_multiplier, int) and 1 <= self.receive_multiplier <= 100):
            bad("receive_multiplier", f"must be an integer 1..100, got {self.receive_multiplier}")
        try:
            FriVersion(self.version)
        except ValueError:
            bad("version", f"must be 1.15 or 2.7, got {self.version!r}")
        for name, p in (("loss", self.loss), ("malformed", self.malformed)):
            if not 0.0 <= p <= 1.0:
                bad(name, f"probability must be in [0, 1], got {p:g}")
        for name, v in (("delay_ms", self.delay_ms), ("jitter_ms", self.jitter_ms)):
            if not (math.isfinite(v) and 0.0 <= v <= 1000.0):
                bad(name, f"must be 0..1000 ms, got {v:g}")
        if len(self.q0) != N_JOINTS or not all(math.isfinite(x) for x in self.q0):
            bad("q0", f"expected {N_JOINTS} finite joint angles")
        for name, port in (("port", self.port), ("client_port", self.client_port)):
            if not 0 <= port <= 65535:
                bad(name, f"not a UDP port: {port}")
        if self.client_port == 0:
            bad("client_port", "the client port must not be 0")
        if self.operation_mode not in OPERATION_MODES:
            bad("operation_mode", f"one of {', '.join(OPERATION_MODES)}, got {self.operation_mode!r}")
        if self.command_mode not in COMMAND_MODES:
            bad("command_mode", f"one of {', '.join(COMMAND_MODES)}, got {self.command_mode!r}")
        if self.command_mode == "cartesian" and self.version != "2.7":
            bad("command_mode", "the CARTESIAN_POSE command mode exists only in FRI 2.7")
        if self.transformations:
            self._validate_transformations(bad)
        if not (math.isfinite(self.joint_stiffness) and 0.0 < self.joint_stiffness <= 1e5):
            bad("joint_stiffness", f"joint stiffness must be in (0, 1e5] Nm/rad, got {self.joint_stiffness:g}")
        kx, kr = self.cartesian_stiffness
        if not (math.isfinite(kx) and 0.0 < kx <= 1e5 and math.isfinite(kr) and 0.0 < kr <= 1e4):
            bad("cartesian_stiffness", f"needs (0, 1e5] N/m and (0, 1e4] Nm/rad, got {kx:g}, {kr:g}")
        if not (math.isfinite(self.nullspace_stiffness) and 0.0 <= self.nullspace_stiffness <= 1e4):
            bad("nullspace_stiffness", f"nullspace stiffness must be 0..1e4 Nm/rad, got {self.nullspace_stiffness:g}")
        if not (math.isfinite(self.damping_ratio) and 0.0 <= self.damping_ratio <= 10.0):
            bad("damping_ratio", f"must be 0..10, got {self.damping_ratio:g}")
        if len(self.external_torque) != N_JOINTS or not all(math.isfinite(x) for x in self.external_torque):
            bad("external_torque", f"expected {N_JOINTS} finite values [Nm]")
        if len(self.external_force) != 6 or not all(math.isfinite(x) for x in self.external_force):
            bad("external_force", "expected 6 finite values [N, Nm]")
        if not (math.isfinite(self.torque_noise) and self.torque_noise >= 0):
            bad("torque_noise", f"must be >= 0 Nm, got {self.torque_noise:g}")
        names = [c.name for c in self.io]
        for ch in self.io:
            ch.validate()
        if len(set(names)) != len(names):
            bad("io", f"channel configured twice: {sorted({n for n in names if names.count(n) > 1})[0]}")
        for spec in self.plants:
            check = getattr(spec, "validate", None)
            if check is not None:
                check()
        self._validate_timing(bad)

    def _validate_transformations(self, bad) -> None:
        if self.version != "2.7":
            bad("transformations", "transformation requests exist only in FRI 2.7")
        if len(self.transformations) > MAX_TRANSFORMATIONS:
            bad("transformations", f"at most {MAX_TRANSFORMATIONS} frames, got {len(self.transformations)}")
        for name in self.transformations:
            if not (isinstance(name, str) and 0 < len(name.encode()) < 64):
                bad("transformations", f"a frame name must be 1..63 bytes, got {name!r}")
        if len(set(self.transformations)) != len(self.transformations):
            bad("transformations", "a frame is named twice")

    def _validate_timing(self, bad) -> None:
        if not 0.0 < self.quality_good <= 1.0:
            bad("quality_good", f"share of timely cycles must be in (0, 1], got {self.quality_good:g}")
        if not 0.0 <= self.quality_fair <= self.quality_good <= self.quality_excellent <= 1.0:
            bad("quality_good", "quality thresholds must satisfy 0 <= fair <= good <= excellent <= 1")
        if not 1 <= self.quality_window <= 100_000:
            bad("quality_window", f"must be 1..100000 cycles, got {self.quality_window}")
        if self.wait_cycles < 1:
            bad("wait_cycles", f"must be >= 1, got {self.wait_cycles}")
        if self.lockstep_timeout_s is not None and not (
            math.isfinite(self.lockstep_timeout_s) and 0.0 < self.lockstep_timeout_s <= 60.0
        ):
            bad("lockstep_timeout_s", f"the reply wait must be in (0, 60] s, got {self.lockstep_timeout_s:g}")
        if self.lockstep_free and self.lockstep_timeout_s is None:
            bad("lockstep_free", "runs the simulator in lock-step: it needs the reply wait of lock-step")
        for name, v in (("session_duration_s", self.session_duration_s), ("max_runtime_s", self.max_runtime_s)):
            if v is not None and not (math.isfinite(v) and v > 0):
                bad(name, f"must be > 0 s, got {v:g}")
