"""Typer options shared by the FRI commands (execute, monitor, ptp)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

from .options import JointVector, choice, joints, number

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
    int, number("--port", low=0, high=65535, integer=True,
                help="Local UDP port from the robot's FRI configuration (0: any free port, simulator).")
]
BindOpt = Annotated[
    Optional[str],
    typer.Option("--bind", parser=parse_ip, metavar="IP",
                 help="Local IP address to bind (default: all interfaces; 127.0.0.1 with the simulator)."),
]
VersionOpt = Annotated[
    Optional[str],
    choice(
        "--fri-version", choices=("1.15", "2.7"),
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
    number("--wait", low=0, high=3600, low_open=True, unit="s",
           help="Seconds to wait for the first FRI message \\[s] (default 60 with --robot, 20 simulated)."),
]
PeriodOpt = Annotated[
    Optional[int],
    number("--period", low=1, high=100, unit="ms", integer=True,
           help="Send period \\[ms]: the simulator's (default: the file's step), or with --robot the period the "
           "controller must have."),
]
SessionPeriodOpt = Annotated[  # commands that play no file
    Optional[int],
    number("--period", low=1, high=100, unit="ms", integer=True,
           help="Send period \\[ms]: the simulator's (default 1), or with --robot the period the controller must have "
           "(default: whatever it sends)."),
]
LengthOpt = Annotated[
    Optional[float],
    number("--length", low=0, high=5, unit="m",
           help=f"Simulated ball string length \\[m] (default {DEFAULT_BALL_LENGTH}; 0: no ball)."),
]
SimStartOpt = Annotated[
    Optional[JointVector],
    joints("--sim-start", help="Simulator only: where the simulated robot stands at start (7 angles, deg/rad)."),
]
MultiplierOpt = Annotated[
    int, number("--receive-multiplier", low=1, high=100, integer=True,
                help="Simulator only: the client answers every k-th message.")
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
        "--busy-wait", low=0, high=5, unit="ms",
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
        "--max-tracking-error", low=0, high=3, low_open=True, unit="rad",
        help="End the stream with a braking stop when a joint's measured position is farther than this from the "
        "command \\[rad] (default: its velocity limit × max(20 ms, 8 command periods)).",
    ),
]


PlotOpt = Annotated[
    Optional[Path], typer.Option("--plot", help="PNG: commanded vs measured joints, tracking, simulated ball sway.")
]
PendulumOpt = Annotated[
    Optional[str],
    typer.Option("--pendulum", help="Serial port of the pendulum module (thesis ch. 6, e.g. /dev/ttyUSB0); 'sim': the "
                 "simulator's emulated module on a pseudo-terminal. Logs pend_theta \\[rad], pend_omega \\[rad/s]."),
]
BaudOpt = Annotated[int, number("--baud", low=50, high=4_000_000, integer=True,
                                 help="Baud rate of the pendulum module's serial port.")]
PendZeroOpt = Annotated[int, number("--pendulum-zero", low=0, high=4095, integer=True,
                                    help="Encoder count of the hanging pendulum.")]
MqttOpt = Annotated[
    Optional[str],
    typer.Option("--mqtt", help="Publish the state as JSON to mqtt://HOST:PORT/TOPIC (off the FRI loop; see `lbr listen`)."),
]
MqttRateOpt = Annotated[float, number("--mqtt-rate", low=0, high=1000, low_open=True, unit="Hz",
                                      help="Telemetry messages per second \\[Hz].")]


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
