"""Typer options shared by the FRI commands (execute, monitor, ptp)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

DEFAULT_BALL_LENGTH = 0.25  # [m] string length of the simulated ball without --length

RobotOpt = Annotated[
    Optional[str],
    typer.Option(
        "--robot",
        help="The robot controller's FRI address (thesis lab: 192.170.10.2). The ONLY way a real robot is "
        "commanded; without it the built-in simulator is started on loopback.",
    ),
]
PortOpt = Annotated[
    int, typer.Option("--port", help="Local UDP port from the robot's FRI configuration (0: any free port, simulator).")
]
BindOpt = Annotated[
    Optional[str],
    typer.Option("--bind", help="Local address to bind (default: all interfaces; 127.0.0.1 with the simulator)."),
]
VersionOpt = Annotated[
    Optional[str],
    typer.Option(
        "--fri-version",
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
    typer.Option("--wait", help="Seconds to wait for the first FRI message \\[s] (default 60 with --robot, 20 simulated)."),
]
PeriodOpt = Annotated[
    Optional[int],
    typer.Option(
        "--period",
        help="Send period \\[ms]: the simulator's (default: the file's step), or with --robot the period the "
        "controller must have.",
    ),
]
LengthOpt = Annotated[
    Optional[float],
    typer.Option("--length", help=f"Simulated ball string length \\[m] (default {DEFAULT_BALL_LENGTH}; 0: no ball)."),
]
SimStartOpt = Annotated[
    Optional[str],
    typer.Option("--sim-start", help="Simulator only: where the simulated robot stands at start (7 angles, deg/rad)."),
]
MultiplierOpt = Annotated[
    int, typer.Option("--receive-multiplier", help="Simulator only: the client answers every k-th message.")
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
    typer.Option(
        "--busy-wait",
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
TrackingErrorOpt = Annotated[
    Optional[float],
    typer.Option(
        "--max-tracking-error",
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
BaudOpt = Annotated[int, typer.Option("--baud", help="Baud rate of the pendulum module's serial port.")]
PendZeroOpt = Annotated[int, typer.Option("--pendulum-zero", help="Encoder count (0..4095) of the hanging pendulum.")]
MqttOpt = Annotated[
    Optional[str],
    typer.Option("--mqtt", help="Publish the state as JSON to mqtt://HOST:PORT/TOPIC (off the FRI loop; see `lbr listen`)."),
]
MqttRateOpt = Annotated[float, typer.Option("--mqtt-rate", help="Telemetry messages per second \\[Hz].")]


def validate_version(version: str | None) -> str | None:
    from trajectories.errors import OptionError

    if version is not None and version not in ("1.15", "2.7"):
        raise OptionError(f"--fri-version must be 1.15 or 2.7, got {version!r}")
    return version


def validate_port(port: int) -> None:
    from trajectories.errors import OptionError

    if not 0 <= port <= 65535:
        raise OptionError(f"--port: not a UDP port: {port}")


def validate_wait(wait: float | None) -> None:
    import math

    from trajectories.errors import OptionError

    if wait is not None and not (math.isfinite(wait) and 0 < wait <= 3600):
        raise OptionError(f"--wait must be in (0, 3600] s, got {wait:g}")


def validate_tracking_error(bound: float | None) -> None:
    import math

    from trajectories.errors import OptionError

    if bound is not None and not (math.isfinite(bound) and 0 < bound <= 3.0):
        raise OptionError(f"--max-tracking-error must be in (0, 3] rad, got {bound:g}")


def validate_period(period: int | None) -> None:
    from trajectories.errors import OptionError

    if period is not None and not 1 <= period <= 100:
        raise OptionError(f"--period must be 1..100 ms, got {period}")


def busy_wait_seconds(busy_wait_ms: float | None) -> float | None:
    """--busy-wait [ms] in seconds (None: the default for the session); OptionError outside 0..5 ms."""
    import math

    from trajectories.errors import OptionError

    if busy_wait_ms is None:
        return None
    if not (math.isfinite(busy_wait_ms) and 0 <= busy_wait_ms <= 5):
        raise OptionError(f"--busy-wait must be 0..5 ms, got {busy_wait_ms:g}")
    return busy_wait_ms * 1e-3


def validate_session(version: str | None, port: int, wait: float | None, period: int | None,
                     max_tracking_error: float | None = None, busy_wait: float | None = None) -> None:  # fmt: skip
    """The session options every FRI command shares (OptionError naming the first bad one)."""
    busy_wait_seconds(busy_wait)
    validate_version(version)
    validate_port(port)
    validate_wait(wait)
    validate_tracking_error(max_tracking_error)
    validate_period(period)


def check_simulator_only(robot: str | None, options: dict[str, bool]) -> None:
    """OptionError when a simulator-only option (name → whether it was given) is used with --robot; the text names
    all of the command's simulator-only options."""
    from trajectories.errors import OptionError

    if robot is not None and any(options.values()):
        names = list(options)
        raise OptionError(f"{', '.join(names[:-1])} and {names[-1]} apply to the simulator only, not with --robot")
