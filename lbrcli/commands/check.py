"""`lbr check`: joint trajectory against the position, velocity, acceleration and jerk limits."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

from ..options import DEFAULT_FLANGE, DtOpt, FlangeOpt, JsonOpt, LimitsOpt, MarginOpt, ToolOpt


def run_check(traj, lim, margin: float, jerk: bool, t1: bool, robot=None):
    """The check behind `lbr check` (also used by `lbr execute` and the planners' reports)."""
    from trajectories.check import check_trajectory
    from trajectories.robot import FLANGE_FRAME

    cart = robot.fk_path(traj.q, FLANGE_FRAME)[0] if t1 else None
    return check_trajectory(traj, lim, margin, jerk=jerk, cartesian_positions=cart)


def print_report(rep, report, name: str) -> None:
    """Per-joint table of peak/limit ratios [%] and the violations."""
    from rich.table import Table

    from trajectories.check import JERKS

    table = Table(
        title=f"{name}: peak / limit [%] (limits × {1 - report.margin:.2f}); central differences (thesis) "
        "and per step (forward, from and to rest: what the controller executes)"
    )
    table.add_column("joint")
    columns = ("position", "velocity", "acceleration", "jerk", "step velocity", "step acceleration", "step jerk")
    for qname in columns:
        table.add_column(qname.replace("step ", "step\n"), justify="right")
    ratios = report.ratios()
    for j in range(7):
        cells = []
        for qname in columns:
            r = ratios[qname][j] * 100
            style = "red" if r > 100 and (qname not in JERKS or report.jerk_enforced) else ("yellow" if r > 100 else "")
            cells.append(f"[{style}]{r:.1f}[/{style}]" if style else f"{r:.1f}")
        table.add_row(f"A{j + 1}", *cells)
    rep.print(table)
    if report.cartesian_speed_peak is not None:
        rep.print(
            f"T1 flange speed peak {report.cartesian_speed_peak * 1e3:.1f} mm/s "
            f"(limit {report.cartesian_speed_limit * 1e3:.0f} mm/s)"
        )
    for v in report.violations:
        fails = v.quantity not in JERKS or report.jerk_enforced
        tag = "[red]violation[/red]" if fails else "[yellow]note (jerk not enforced)[/yellow]"
        rep.print(f"{tag}: {v.describe()}")
    rep.print(
        "[green]OK[/green]: within limits" if report.ok else f"[red]FAILED[/red]: {len(report.failing)} violations"
    )


def check(
    joint_csv: Annotated[Path, typer.Argument(help="Joint trajectory t,q1..q7 \\[s, rad].")],
    plot: Annotated[
        Optional[Path], typer.Option("--plot", help="PNG of joint velocity and acceleration with the limits.")
    ] = None,
    margin: MarginOpt = 0.0,
    jerk: Annotated[
        bool, typer.Option("--jerk", help="Fail on jerk violations too (jerk is always reported).")
    ] = False,
    t1: Annotated[
        bool, typer.Option("--t1", help="Also check the Cartesian flange speed against T1's 250 mm/s.")
    ] = False,
    flange: FlangeOpt = DEFAULT_FLANGE,
    tool: ToolOpt = None,
    limits: LimitsOpt = None,
    dt: DtOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Check a joint trajectory against the limits; exit 1 on any violation.

    Derivatives by central differences (thesis eq. 5.7) applied repeatedly, and per step as the controller executes
    the rows (forward differences, the robot at rest before the first row and after the last). The file must start
    and end at rest. Values exactly at a limit pass (relative tolerance 1e-9). Jerk fails only with --jerk: in
    position mode the controller's interpolator smooths jerk.
    """
    from trajectories.csvio import read_joint_csv

    from ..console import Reporter
    from ..options import limits_from, make_robot
    from ..outputs import guard_outputs

    rep = Reporter(json_out)
    guard_outputs({"JOINT_CSV": joint_csv, "--limits": limits}, {"--plot": plot})
    lim = limits_from(limits)
    robot = make_robot(flange, tool)  # also without --t1: a bad --flange or --tool is an error, never ignored
    traj = read_joint_csv(joint_csv, dt)
    report = run_check(traj, lim, margin, jerk, t1, robot if t1 else None)
    print_report(rep, report, str(joint_csv))
    if plot is not None:
        from ..plots.check import plot_check

        plot_check(report, plot, title=joint_csv.name)
        rep.print(f"plot: {plot}")
    rep.emit({"file": str(joint_csv), "samples": len(traj), "duration_s": traj.duration, **report.to_dict()})
    if not report.ok:
        raise typer.Exit(1)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("check")(check)
