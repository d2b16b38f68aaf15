"""`lbr track film`: render the simulated ball of an execution log as a lab camera would film it (an mp4)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

from ..cup_options import CupSpecOpt
from ..options import DEFAULT_FLANGE, FlangeOpt, JsonOpt, ToolOpt

TRUTH_COLUMNS = ("t", "u", "v", "pivot_u", "pivot_v", "theta")


def film(
    log: Annotated[Path, typer.Argument(metavar="LOG", help="Execution log of `lbr execute` on the simulator (ball_theta_y, msr_q1..7).")],
    out: Annotated[Path, typer.Option("-o", "--out", help="Video to write (.mp4).")],
    length: Annotated[float, typer.Option("--length", help="String length \\[m] the simulator used (`lbr execute --length`).")] = 0.25,
    size: Annotated[str, typer.Option("--size", help="Frame size WIDTHxHEIGHT \\[px]; the scale follows the width (1300 px/m at 1280).")] = "1280x720",
    fps: Annotated[float, typer.Option("--fps", help="Frame rate \\[1/s].")] = 60.0,
    truth: Annotated[Optional[Path], typer.Option("--truth", help="Write what was drawn per frame: t,u,v,pivot_u,pivot_v,theta \\[s, px, rad].")] = None,
    cup: CupSpecOpt = None,
    flange: FlangeOpt = DEFAULT_FLANGE,
    tool: ToolOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Film the simulated ball of an execution log: a camera on +x looking at the base y–z plane (image u = base +y,
    θ positive toward the image's right, as `lbr track video` measures it), a green marker on the pivot for
    `--pivot-color green`. Stands in for the experiment video when there is no camera (the README's example). With
    --cup (the spec `lbr execute --cup` simulated) the ball is drawn where the log puts it — flying on a slack string
    too — and the cup on the pivot (a clear cup: the ball stays visible inside)."""
    import numpy as np

    from trajectories.csvio import write_table
    from trajectories.errors import OptionError
    from trajectories.robot import parse_flange, parse_tool

    from ..console import Reporter
    from ..demo.render import Camera, film_execution_log
    from ..options import check_number
    from ..outputs import atomic_path, guard_outputs

    rep = Reporter(json_out)
    check_number("--length", length, 0.01, 5.0, unit="m")
    check_number("--fps", fps, 1.0, 1000.0, unit="1/s")
    try:
        w, h = (int(p) for p in size.lower().split("x"))
    except ValueError:
        raise OptionError(f"--size: expected WIDTHxHEIGHT in pixels (e.g. 1280x720), got {size!r}") from None
    if not (64 <= w <= 7680 and 64 <= h <= 4320):
        raise OptionError(f"--size must be between 64x64 and 7680x4320 px, got {size!r}")
    parse_flange(flange)
    model = None
    if cup is not None:
        from ..cup_options import parse_cup_spec

        model = parse_cup_spec(cup, length)
    guard_outputs({"LOG": log}, {"-o": out, "--truth": truth})
    k = w / 1280.0
    camera = Camera(px_per_m=1300.0 * k, pivot0_uv=(w / 2.0, 260.0 * h / 720.0), size=(w, h), fps=fps)
    with atomic_path(out) as tmp, rep.progress("film", None) as update:
        footage = film_execution_log(log, tmp, length, camera, flange=flange, tool=parse_tool(tool),
                                     progress=update, cup=model)
    gt = footage.truth
    if truth is not None:
        write_table(truth, TRUTH_COLUMNS, np.column_stack([gt.t, gt.ball_uv, gt.pivot_uv, gt.theta]), fmt="%.6f")
    rep.print(f"wrote {out}: {len(gt.t)} frames, {w}x{h} px at {fps:g} FPS, {gt.t[-1]:.2f} s from log time "
              f"{footage.t0_log:.3f} s")
    rep.emit({"out": str(out), "frames": int(len(gt.t)), "video_s": float(gt.t[-1]), "t0_log_s": footage.t0_log,
              "truth": str(truth) if truth is not None else None})


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    groups["track"].command("film")(film)
