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
    from trajectories.errors import OptionError

    if not 0.0 <= margin < 1.0:
        raise OptionError(f"--margin must be in [0, 1), got {margin:g}")
    return margin
