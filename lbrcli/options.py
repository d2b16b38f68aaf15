"""Options shared by several commands, and the objects built from them."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

JsonOpt = Annotated[
    bool, typer.Option("--json", help="Print one JSON object with the figures on stdout; text goes to stderr.")
]
FlangeOpt = Annotated[
    str,
    typer.Option("--flange", help="Media flange: touch-electric (d7 = 0.152 m), standard (0.126 m), touch-pneumatic (0.187 m)."),
]
ToolOpt = Annotated[
    Optional[str], typer.Option("--tool", help="Tool offset x,y,z \\[m] in the flange frame (e.g. the string attachment).")
]
LimitsOpt = Annotated[
    Optional[Path], typer.Option("--limits", help="TOML file overriding the limit tables (see trajectories/data).")
]
DtOpt = Annotated[
    Optional[float], typer.Option("--dt", help="Sample step \\[s] of a headerless 7-column joint file.")
]

DEFAULT_FLANGE = "touch-electric"
THESIS_Q_START = "0,0.071,0,-1.3523,0,0.1301,0"  # [rad], thesis §5.3.2 start pose


def robot_config(flange: str, tool: str | None):
    """RobotConfig from --flange and --tool."""
    from trajectories.robot import RobotConfig, parse_flange, parse_tool

    return RobotConfig(flange=parse_flange(flange), tool=parse_tool(tool))


def make_robot(flange: str, tool: str | None):
    """Robot from --flange and --tool."""
    from trajectories.robot import Robot

    return Robot(robot_config(flange, tool))


def limits_from(path: Path | None):
    from trajectories.limits import load_limits

    return load_limits(path)


def check_margin(margin: float) -> float:
    """--margin in [0, 1)."""
    return check_number("--margin", margin, 0.0, 1.0, high_open=True)


def check_number(
    option: str,
    value: float | None,
    low: float | None = None,
    high: float | None = None,
    *,
    low_open: bool = False,
    high_open: bool = False,
    unit: str = "",
) -> float | None:
    """``value`` if it is a finite number inside the range, else OptionError (exit 2) in one line.

    The range is [low, high] (open at an end with ``low_open``/``high_open``; None: unbounded). NaN and ±inf are
    always refused; None (an option not given) passes through.
    """
    import math

    from trajectories.errors import OptionError

    if value is None:
        return None
    ok = math.isfinite(value)
    if ok and low is not None:
        ok = value > low if low_open else value >= low
    if ok and high is not None:
        ok = value < high if high_open else value <= high
    if not ok:
        u = f" {unit}" if unit else ""
        if low is not None and high is not None:
            want = f"in {'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}{u}"
        elif low is not None:
            want = f"{'>' if low_open else '≥'} {low:g}{u}"
        elif high is not None:
            want = f"{'<' if high_open else '≤'} {high:g}{u}"
        else:
            want = "a finite number"
        raise OptionError(f"{option} must be {want}, got {value:g}")
    return value
