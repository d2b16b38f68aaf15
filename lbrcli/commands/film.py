"""`lbr track film`: render the simulated ball of an execution log as a lab camera would film it (an mp4)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

from ..cup_options import CupSpecOpt
from ..options import DEFAULT_FLANGE, FlangeOpt, JsonOpt, ToolOpt, grid, number

TRUTH_COLUMNS = ("t", "u", "v", "pivot_u", "pivot_v", "theta")


def film(
    log: Annotated[
        Path,
        typer.Argument(
            metavar="LOG", help="Execution log of `lbr execute` on the simulator (ball_theta_y, msr_q1..7)."
        ),
    ],
    out: Annotated[Path, typer.Option("-o", "--out", help="Video to write (.mp4).")],
    length: Annotated[
        float,
        number(
            "--length",
            low=0.01,
            high=5.0,
            unit="m",
            help="String length \\[m] the simulator used (`lbr execute --length`).",
        ),
    ] = 0.25,
    size: Annotated[
        tuple,
        grid(
            "--size",
            low=64,
            high=7680,
            metavar="WIDTHxHEIGHT",
            help="Frame size WIDTHxHEIGHT \\[px] (height at most 4320); the scale follows the width (1300 px/m at 1280).",
        ),
    ] = "1280x720",
    fps: Annotated[float, number("--fps", low=1, high=1000, unit="1/s", help="Frame rate \\[1/s].")] = 60.0,
    truth: Annotated[
        Optional[Path],
        typer.Option("--truth", help="Write what was drawn per frame: t,u,v,pivot_u,pivot_v,theta \\[s, px, rad]."),
    ] = None,
    partial: Annotated[
        bool,
        typer.Option(
            "--partial",
            help="Film a log whose session stopped early too (refused otherwise: the film would not show the experiment).",
        ),
    ] = False,
    cup: CupSpecOpt = None,
    flange: FlangeOpt = DEFAULT_FLANGE,
    tool: ToolOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Film the simulated ball of an execution log: a camera on +x looking at the base y–z plane (image u = base +y,
    θ positive toward the image's right, as `lbr track video` measures it), a green marker on the pivot for
    `--pivot-color green`. Stands in for the experiment video when there is no camera (the film-and-track tutorial). The
    ball is drawn where the log puts it (the simulator's ball_y, ball_z: flying on a slack string too, the string
    sagging); with --cup (the spec `lbr execute --cup` simulated) the cup is drawn on the pivot (a clear cup: the
    ball stays visible inside) and the ball has the spec's radius.

    A log whose session did not complete (stopped early: see its file_rows/phase columns) is refused unless --partial.
    Exit 1 when the video could not be written whole (nothing is left under its name)."""
    import numpy as np

    from trajectories.csvio import write_table
    from trajectories.errors import OptionError
    from trajectories.robot import parse_tool

    from ..console import Reporter
    from tracking.video import check_video_name, check_written

    from ..demo.render import Camera, film_execution_log, read_film_log
    from ..session_end import require_complete
    from ..outputs import atomic_path, guard_outputs

    rep = Reporter(json_out)
    w, h = size
    if h > 4320:
        raise OptionError(f"--size: the height must be at most 4320 px, got {w}x{h}")
    check_video_name(out, "-o")
    model = None
    if cup is not None:
        from ..cup_options import parse_cup_spec

        model = parse_cup_spec(cup, length)
    guard_outputs({"LOG": log}, {"-o": out, "--truth": truth})
    k = w / 1280.0
    camera = Camera(px_per_m=1300.0 * k, pivot0_uv=(w / 2.0, 260.0 * h / 720.0), size=(w, h), fps=fps)
    table = read_film_log(log)
    require_complete(table, partial, rep, option="--partial")
    with atomic_path(out) as tmp, rep.progress("film", None) as update:
        footage = film_execution_log(
            table, tmp, length, camera, flange=flange, tool=parse_tool(tool), progress=update, cup=model, target=out
        )
        check_written(tmp, len(footage.truth.t), out)  # OpenCV does not report a full disk
    gt = footage.truth
    if truth is not None:
        write_table(truth, TRUTH_COLUMNS, np.column_stack([gt.t, gt.ball_uv, gt.pivot_uv, gt.theta]), fmt="%.6f")
    rep.print(
        f"wrote {out}: {len(gt.t)} frames, {w}x{h} px at {fps:g} FPS, {gt.t[-1]:.2f} s from log time "
        f"{footage.t0_log:.3f} s"
    )
    rep.emit(
        {
            "out": str(out),
            "frames": int(len(gt.t)),
            "video_s": float(gt.t[-1]),
            "t0_log_s": footage.t0_log,
            "truth": str(truth) if truth is not None else None,
        }
    )


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    groups["track"].command("film")(film)
