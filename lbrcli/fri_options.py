"""Typer options shared by the FRI commands (execute, monitor, ptp)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Optional, Sequence

import numpy as np
import typer

from trajectories.start_poses import THESIS_START

from .lab.attach import LabOptions
from .option_groups import OptionGroup
from .options import DEFAULT_FLANGE, JointVector, choice, joints, number, string_length
from .session_settings import SessionSettings, SimulatorSettings

DEFAULT_BALL_LENGTH = 0.25  # [m] string length of the simulated ball without --length


def parse_ip(text: str | None) -> str | None:
    """--bind: an IPv4 or IPv6 address (not a host name: the FRI socket binds a local interface)."""
    import ipaddress

    if text is None:
        return None
    try:
        return str(ipaddress.ip_address(str(text).strip()))
    except ValueError:
        raise typer.BadParameter(f"expected a local IP address such as 127.0.0.1 or 0.0.0.0, got {text!r}") from None


def parse_host_port(text: str | tuple) -> tuple[str, int]:
    """HOST:PORT (port 1..65535), at parse time (sim --client, track live --udp)."""
    from trajectories.numbers import NotANumber, plain_int

    if isinstance(text, tuple):
        return text
    host, sep, port = str(text).rpartition(":")
    if not sep or not host.strip():
        raise typer.BadParameter(f"expected HOST:PORT, got {text!r}")
    try:
        number = plain_int(port)
    except NotANumber:
        raise typer.BadParameter(f"the port must be a whole number, got {port!r}") from None
    if not 1 <= number <= 65535:
        raise typer.BadParameter(f"the port must be 1..65535, got {number}")
    return host.strip(), number


RobotOpt = Annotated[
    Optional[str],
    typer.Option(
        "--robot",
        help="The robot controller's FRI address (thesis lab: 192.170.10.2). The ONLY way a real robot is "
        "commanded; without it the built-in simulator is started on loopback.",
    ),
]
PortOpt = Annotated[
    int,
    number(
        "--port",
        low=0,
        high=65535,
        integer=True,
        help="Local UDP port from the robot's FRI configuration (0: any free port, simulator).",
    ),
]
BindOpt = Annotated[
    Optional[str],
    typer.Option(
        "--bind",
        parser=parse_ip,
        metavar="IP",
        help="Local IP address to bind (default: all interfaces; 127.0.0.1 with the simulator).",
    ),
]
VersionOpt = Annotated[
    Optional[str],
    choice(
        "--fri-version",
        choices=("1.15", "2.7"),
        help="FRI wire format: 1.15 or 2.7. Default: detected from the first datagram with --robot (2.7 frames carry "
        "a length and a CRC); 1.15 for the simulator.",
    ),
]
LogOpt = Annotated[
    Optional[Path],
    typer.Option("--log", help="Execution log CSV, one row per monitoring message (valid after any ending)."),
]
WaitOpt = Annotated[
    Optional[float],
    number(
        "--wait",
        low=0,
        high=3600,
        low_open=True,
        unit="s",
        help="Seconds to wait for the first FRI message \\[s] (default 60 with --robot, 20 simulated).",
    ),
]
PeriodOpt = Annotated[
    Optional[int],
    number(
        "--period",
        low=1,
        high=100,
        unit="ms",
        integer=True,
        help="Send period \\[ms]: the simulator's (default: the file's step), or with --robot the period the "
        "controller must have.",
    ),
]
StartToleranceOpt = Annotated[  # commands that play rows from a first one (execute, control damp)
    float,
    number(
        "--start-tolerance",
        low=0,
        high=0.1,
        unit="rad",
        help="Largest |first row − measured position| accepted \\[rad].",
    ),
]
SessionPeriodOpt = Annotated[  # commands that play no file
    Optional[int],
    number(
        "--period",
        low=1,
        high=100,
        unit="ms",
        integer=True,
        help="Send period \\[ms]: the simulator's (default 1), or with --robot the period the controller must have "
        "(default: whatever it sends).",
    ),
]
LengthOpt = Annotated[
    Optional[float],
    string_length(
        "--length",
        zero_is_none=True,
        help=f"Simulated ball string length \\[m] (default {DEFAULT_BALL_LENGTH}; 0: no ball).",
    ),
]
DrawnLengthOpt = Annotated[
    float,
    string_length(
        "--length",
        help="String length \\[m] from the TCP to the ball's centre, for balls a file gives by their angles (the "
        "execution log's simulated ball).",
    ),
]
"""``lbr view`` and ``lbr export``: the string of the ball they draw from angles (default :data:`DEFAULT_BALL_LENGTH`)."""
SimStartOpt = Annotated[
    Optional[JointVector],
    joints("--sim-start", help="Simulator only: where the simulated robot stands at start (7 angles, deg/rad)."),
]
MultiplierOpt = Annotated[
    int,
    number(
        "--receive-multiplier",
        low=1,
        high=100,
        integer=True,
        help="Simulator only: the client answers every k-th message.",
    ),
]
RealtimeOpt = Annotated[
    bool,
    typer.Option(
        "--realtime",
        help="Run the FRI loop as a real-time task: SCHED_FIFO (priority 20), pinned to the last CPU, memory locked "
        "(mlockall) — replies on time however busy the PC is. Needs root or CAP_SYS_NICE and CAP_IPC_LOCK (or rtprio "
        "and memlock limits); refused with exit 2 otherwise. See docs/explanations/fri-timing.md.",
    ),
]
BusyWaitOpt = Annotated[
    Optional[float],
    number(
        "--busy-wait",
        low=0,
        high=5,
        unit="ms",
        help="Sleep-then-spin: poll the socket for this long before each controller message is due \\[ms] instead "
        "of sleeping until it arrives (default 0: block in the kernel, as KUKA's client does, ≈ 0.1 ms of CPU per "
        "message). Can shorten the reply on a quiet PC; costs that much CPU per period and, on a busy PC, makes the "
        "scheduler run the client later (it used up its share).",
    ),
]
SimLenientOpt = Annotated[
    bool,
    typer.Option(
        "--sim-lenient/--sim-strict",
        help="Simulator only: judge the connection quality leniently (default: over 1 s, GOOD with half the replies "
        "in time — the simulator shares this machine with the client and whatever else runs on it) or as strictly as "
        "the real controller (--sim-strict: over 50 cycles, 90 %).",
    ),
]
SimLockstepOpt = Annotated[
    bool,
    typer.Option(
        "--sim-lockstep",
        help="Simulator only: wait for each reply before the next cycle. The simulated time, plants and sensors advance "
        "one period per cycle, so a closed loop behaves as on an idle PC however busy this one is (it just runs slower "
        "than real time) — for tests, sweeps and rehearsals on a shared machine. Not with a camera (it renders in real "
        "time).",
    ),
]
SimFastOpt = Annotated[
    bool,
    typer.Option(
        "--sim-fast",
        help="Simulator only: lock-step (--sim-lockstep) as fast as this computer answers — each cycle starts as soon "
        "as the reply to the last is in, not on the period's grid. The session, its log and its figures are those of "
        "the same run in real time on an idle PC (simulated time advances one period per cycle); a 60 s file "
        "rehearses in seconds. Not with a camera.",
    ),
]
TrackingErrorOpt = Annotated[
    Optional[float],
    number(
        "--max-tracking-error",
        low=0,
        high=3,
        low_open=True,
        unit="rad",
        help="End the stream with a braking stop when a joint's measured position is farther than this from the "
        "command \\[rad] (default: its velocity limit × max(20 ms, 8 command periods)).",
    ),
]


PlotOpt = Annotated[
    Optional[Path], typer.Option("--plot", help="PNG: commanded vs measured joints, tracking, simulated ball sway.")
]
PendulumOpt = Annotated[
    Optional[str],
    typer.Option(
        "--pendulum",
        help="Serial port of the pendulum module (thesis ch. 6, e.g. /dev/ttyUSB0); 'sim': the "
        "simulator's emulated module on a pseudo-terminal. Logs pend_theta \\[rad], pend_omega \\[rad/s].",
    ),
]
BaudOpt = Annotated[
    int, number("--baud", low=50, high=4_000_000, integer=True, help="Baud rate of the pendulum module's serial port.")
]
PendZeroOpt = Annotated[
    int, number("--pendulum-zero", low=0, high=4095, integer=True, help="Encoder count of the hanging pendulum.")
]
MqttOpt = Annotated[
    Optional[str],
    typer.Option(
        "--mqtt", help="Publish the state as JSON to mqtt://HOST:PORT/TOPIC (off the FRI loop; see `lbr listen`)."
    ),
]
MqttRateOpt = Annotated[
    float,
    number("--mqtt-rate", low=0, high=1000, low_open=True, unit="Hz", help="Telemetry messages per second \\[Hz]."),
]


def busy_wait_seconds(busy_wait_ms: float | None) -> float | None:
    """--busy-wait [ms] in seconds (None: the default for the session)."""
    return None if busy_wait_ms is None else busy_wait_ms * 1e-3


def check_simulator_only(robot: str | None, options: dict[str, bool]) -> None:
    """OptionError when a simulator-only option (name → whether it was given) is used with --robot; the text names
    all of the command's simulator-only options."""
    from trajectories.errors import OptionError

    if robot is not None and any(options.values()):
        names = list(options)
        raise OptionError(f"{', '.join(names[:-1])} and {names[-1]} apply to the simulator only, not with --robot")


# ---------------------------------------------------------------- the FRI commands' shared options, one group each

SESSION_FLAGS = {
    "SessionSettings.port": "--port", "SessionSettings.version": "--fri-version", "SessionSettings.wait_s": "--wait",
    "SessionSettings.busy_wait_s": "--busy-wait", "SessionSettings.send_period_ms": "--period", "SessionSettings.max_tracking_error": "--max-tracking-error",
    "SimulatorSettings.period_ms": "--period", "SimulatorSettings.start": "--sim-start",
    "SimulatorSettings.ball": "--length", "BallSpec.length": "--length", "BallSpec.damping": "--damping",
    "BallSpec.model": "--cup", "BallSpec.io_delay_ms": "--sim-delay", "SimConfig.period_ms": "--period",
    "SimConfig.receive_multiplier": "--receive-multiplier", "SimConfig.q0": "--sim-start", "SimConfig.version": "--fri-version",
    "SimConfig.lockstep_timeout_s": "--sim-lockstep", "SimConfig.lockstep_free": "--sim-fast",
    "SessionSettings.realtime": "--realtime", "UdpTransport.robot": "--robot",
    "ClientApplication.robot": "--robot", "ClientApplication.version": "--fri-version",
    "TrajectoryPlayer.resample": "--resample", "TrajectoryPlayer.start_tolerance": "--start-tolerance",
    "TrajectoryPlayer.move_to_start": "--move-to-start", "SwayWatch.threshold": "--start-sway",
    "SwayWatch.max_wait_s": "--sway-wait", "ExecutionLog.path": "--log", "SimulatorSettings.lockstep": "--sim-lockstep",
}  # fmt: skip
"""The flag each setting of the session and the simulator comes from (``Class.field`` → option)."""


@dataclass(frozen=True)
class FriOptions:
    """The FRI options every FRI command shares (the session's and the simulator's), as given; ``present``: the
    parameters this command has. :meth:`session` and :meth:`simulator` make the settings with the command's own."""

    robot: str | None = None
    port: int = 30200
    bind: str | None = None
    log: Path | None = None
    fri_version: str | None = None
    wait: float | None = None  # [s]
    realtime: bool = False
    busy_wait: float | None = None  # [ms]
    period: int | None = None  # [ms] send period (None: the command's default)
    sim_start: np.ndarray | None = None  # [rad] (None: the command's default)
    length: float | None = None  # [m] the simulated ball's string (None: DEFAULT_BALL_LENGTH; 0: no ball)
    sim_lenient: bool = True
    sim_lockstep: bool = False
    sim_fast: bool = False
    present: frozenset[str] = frozenset()

    @property
    def embedded(self) -> bool:
        """No --robot: the session runs against the built-in simulator."""
        return self.robot is None

    def check_simulator_only(self, command: dict[str, bool] | None = None, *, length: bool = True) -> None:
        """OptionError when a simulator-only option was given with --robot: the group's (--sim-start, --length unless
        ``length`` is False — it also means something with a robot —, --sim-strict, --sim-lockstep, --sim-fast where the
        command has them), then the command's (flag → given)."""
        ours = {"sim_start": ("--sim-start", self.sim_start is not None),
                "length": ("--length", length and self.length is not None),
                "sim_lenient": ("--sim-strict", not self.sim_lenient), "sim_lockstep": ("--sim-lockstep", self.sim_lockstep),
                "sim_fast": ("--sim-fast", self.sim_fast)}  # fmt: skip
        given = {flag: on for name, (flag, on) in ours.items() if name in self.present and (name != "length" or length)}
        check_simulator_only(self.robot, {**given, **(command or {})})

    def refuse_log_over(self, path: Path) -> None:
        """OptionError when --log would overwrite ``path`` (the command's input)."""
        from trajectories.errors import OptionError

        if self.log is not None and self.log.resolve() == Path(path).resolve():
            raise OptionError(f"--log {self.log} is the trajectory file itself; choose another name")

    def session(self, limits: Any = None, *, duration_s: float | None = None,
                max_tracking_error: float | None = None, check_period: bool = True) -> SessionSettings:  # fmt: skip
        """The session's settings (``limits``: the JointLimits the commands are guarded with); with a robot, the send
        period given is the one it must have (``check_period`` False: the command checks the period itself)."""
        return SessionSettings(robot=self.robot, port=self.port, bind=self.bind, version=self.fri_version, limits=limits,
                               log=self.log, wait_s=self.wait, duration_s=duration_s, realtime=self.realtime,
                               busy_wait_s=busy_wait_seconds(self.busy_wait) or 0.0,
                               max_tracking_error=max_tracking_error,
                               send_period_ms=self.period if check_period else None)  # fmt: skip

    def ball_length(self) -> float:
        """[m] the simulated ball's string: --length, its default where not given (0: no ball)."""
        return DEFAULT_BALL_LENGTH if self.length is None else self.length

    def ball(self, damping: float = 0.0, model: Any = None):
        """The simulated ball of :meth:`ball_length` (a BallSpec; None for 0) with ``damping`` [1/s] and ``model``."""
        from .plants import BallSpec

        length = self.ball_length()
        return BallSpec(length, damping, model=model) if length else None

    def simulator(self, *, max_runtime_s: float, start: Sequence[float] = THESIS_START, ball: Any = None,
                  plants: Sequence[Any] = (), lab: LabOptions | None = None, period_ms: int | None = None,
                  flange: str = DEFAULT_FLANGE, tool: Sequence[float] | None = None, limits: Path | None = None,
                  receive_multiplier: int = 1) -> SimulatorSettings | None:  # fmt: skip
        """The embedded simulator's settings (None with --robot): ``start`` [rad] where --sim-start was not given,
        ``ball`` (BallSpec; None: none), further ``plants`` — the emulated pendulum module when ``lab`` asks for it and
        no plant was given — ``period_ms`` where --period was not given (default 1), --flange, --tool, --limits."""
        if self.robot is not None:
            return None
        from .plants import PendulumModuleSpec

        if lab is not None and lab.pendulum == "sim" and not plants:
            plants = (PendulumModuleSpec(),)
        q0 = self.sim_start if self.sim_start is not None else start
        return SimulatorSettings(period_ms=self.period or period_ms or 1, receive_multiplier=receive_multiplier,
                                 start=tuple(q0), flange=flange, tool=tuple(tool) if tool is not None else (0.0,) * 3,
                                 ball=ball, plants=tuple(plants), limits_path=limits, max_runtime_s=max_runtime_s,
                                 lenient=self.sim_lenient, lockstep=self.sim_lockstep, fast=self.sim_fast)  # fmt: skip


def _fri_options(
    *, present: frozenset[str] = frozenset(), robot: RobotOpt = None, port: PortOpt = 30200, bind: BindOpt = None,
    log: LogOpt = None, fri_version: VersionOpt = None, period: SessionPeriodOpt = None, sim_start: SimStartOpt = None,
    length: LengthOpt = None, wait: WaitOpt = None, realtime: RealtimeOpt = False, busy_wait: BusyWaitOpt = None,
    sim_lenient: SimLenientOpt = True, sim_lockstep: SimLockstepOpt = False, sim_fast: SimFastOpt = False,
) -> FriOptions:  # fmt: skip
    return FriOptions(robot, port, bind, log, fri_version, wait, realtime, busy_wait, period, sim_start, length,
                      sim_lenient, sim_lockstep, sim_fast, present)  # fmt: skip


FRI_OPTIONS = OptionGroup(_fri_options, flags=SESSION_FLAGS)
"""The FRI commands' shared options; a command leaves out what it does not take (``FRI_OPTIONS.without(...)``)."""

LAB_FLAGS = {"LabOptions.pendulum": "--pendulum", "LabOptions.baud": "--baud", "LabOptions.pendulum_zero": "--pendulum-zero",
             "LabOptions.mqtt": "--mqtt", "LabOptions.mqtt_rate_hz": "--mqtt-rate", "PendulumReader.port": "--pendulum"}  # fmt: skip


def _lab_options(pendulum: PendulumOpt = None, baud: BaudOpt = 115200, pendulum_zero: PendZeroOpt = 0,
                 mqtt: MqttOpt = None, mqtt_rate: MqttRateOpt = 50.0) -> LabOptions:  # fmt: skip
    return LabOptions(pendulum, baud, pendulum_zero, mqtt, mqtt_rate)


LAB_OPTIONS = OptionGroup(_lab_options, flags=LAB_FLAGS)
"""The lab's attachments: the pendulum module on a serial port and MQTT telemetry (:class:`LabOptions`)."""
