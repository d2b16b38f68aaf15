"""`lbr retime`: the fastest timing of an ordinary joint path within the limits (toppra)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

from ..options import DtOpt, JsonOpt, LimitsOpt


def retime(
    joint_csv: Annotated[Path, typer.Argument(help="Joint trajectory t,q1..q7 \\[s, rad] (an ordinary path).")],
    out: Annotated[Path, typer.Option("-o", "--out", help="Re-timed joint trajectory to write.")],
    step: Annotated[
        Optional[float], typer.Option("--step", help="Output sample step \\[s] (default: the input's step, e.g. the FRI period).")
    ] = None,
    margin: Annotated[float, typer.Option("--margin", help="Use the limits scaled by (1 − margin).")] = 0.02,
    limits: LimitsOpt = None,
    dt: DtOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Re-time a joint path to the fastest timing within the velocity and acceleration limits (toppra).

    [bold]Never use it on anti-sway or swing-up plans[/bold]: their timing is what damps or pumps the
    swing; re-timing detunes them. Lower the planner's acceleration instead.
    """
    from trajectories.csvio import read_joint_csv, write_joint_csv
    from trajectories.errors import OptionError
    from trajectories.retime import retime as do_retime

    from ..console import Reporter
    from ..options import check_margin, limits_from
    from .check import print_report, run_check

    rep = Reporter(json_out)
    check_margin(margin)
    lim = limits_from(limits)
    traj = read_joint_csv(joint_csv, dt)
    h = step if step is not None else traj.dt
    if not h or h <= 0:
        raise OptionError("--step must be positive (a single-sample file has no step; give --step)")
    result = do_retime(traj, lim, h, scale=1.0 - margin)
    write_joint_csv(out, result.trajectory)
    report = run_check(result.trajectory, lim, 0.0, False, False)
    print_report(rep, report, str(out))
    rep.print(f"wrote {out}: {result.duration_in:.3f} s → {result.duration_out:.3f} s at step {h:g} s")
    rep.emit(
        {"duration_in_s": result.duration_in, "duration_s": result.duration_out, "step_s": h, "limits_ok": report.ok, "out": str(out)}
    )
    if not report.ok:
        raise typer.Exit(1)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("retime")(retime)
