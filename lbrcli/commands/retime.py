"""`lbr retime`: the fastest timing of an ordinary joint path within the limits (toppra)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

from ..options import DtOpt, JsonOpt, LimitsOpt, number


def retime(
    joint_csv: Annotated[Path, typer.Argument(help="Joint trajectory t,q1..q7 \\[s, rad] (an ordinary path).")],
    out: Annotated[Path, typer.Option("-o", "--out", help="Re-timed joint trajectory to write.")],
    step: Annotated[
        Optional[float],
        number(
            "--step",
            low=1e-4,
            high=1.0,
            unit="s",
            help="Output sample step \\[s] (default: the input's step, e.g. the FRI period).",
        ),
    ] = None,
    margin: Annotated[
        float,
        number(
            "--margin",
            low=0,
            high=1,
            high_open=True,
            help="Use the limits scaled by (1 − margin); the samples are verified against them.",
        ),
    ] = 0.02,
    limits: LimitsOpt = None,
    dt: DtOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Re-time a joint path to the fastest timing within the velocity and acceleration limits (toppra).

    [bold]Never use it on anti-sway or swing-up plans[/bold]: their timing is what damps or pumps the
    swing; re-timing detunes them. Lower the planner's acceleration instead.

    The samples are verified by central and forward differences against the limits × (1 − margin); toppra is rerun
    slower until they pass. Exit 1 without writing when they cannot (e.g. the path leaves the position limits).
    """
    from trajectories.csvio import read_joint_csv, write_joint_csv
    from trajectories.errors import CheckFailed, OptionError, PlanningError
    from trajectories.retime import retime_within

    from ..console import Reporter
    from ..options import check_number, limits_from
    from ..outputs import guard_outputs
    from .check import print_report, run_check

    rep = Reporter(json_out)
    guard_outputs({"JOINT_CSV": joint_csv, "--limits": limits}, {"-o": out})
    lim = limits_from(limits)
    traj = read_joint_csv(joint_csv, dt)
    h = step if step is not None else traj.dt
    if not h or h <= 0:
        raise OptionError("--step must be positive (a single-sample file has no step; give --step)")
    check_number("the step (--step or the input's)", h, 1e-4, 1.0, unit="s")
    # toppra bounds the spline; the samples are verified (central and forward differences) against the limits
    # × (1 − margin) and re-timed slower until they pass; a file outside the limits is never written.
    try:
        result, ratios = retime_within(traj, lim.scaled(1.0 - margin), h, scale=1.0)
    except (CheckFailed, PlanningError) as exc:
        raise type(exc)(f"{joint_csv}: {exc}; nothing written to {out}") from None
    report = run_check(result.trajectory, lim, margin, False, False)
    if not report.ok:  # retime_within verified the same limits: a bug if reached
        raise CheckFailed(f"{joint_csv}: the re-timed path fails the limit check; nothing written to {out}")
    write_joint_csv(out, result.trajectory)
    print_report(rep, report, str(out))
    if ratios["jerk"] > 1.0:
        rep.warn(
            f"joint jerk peaks at {ratios['jerk']:.2f}× the jerk limit (toppra bounds velocity and acceleration "
            "only; `lbr check --jerk` fails such files)"
        )
    rep.print(
        f"wrote {out}: {result.duration_in:.3f} s → {result.duration_out:.3f} s at step {h:g} s "
        f"(limits × {1 - margin:.2f}; toppra at {result.scale:.3f} of them after {result.attempts} attempt(s))"
    )
    rep.emit(
        {
            "duration_in_s": result.duration_in,
            "duration_s": result.duration_out,
            "step_s": h,
            "limits_ok": report.ok,
            "ratios": ratios,
            "toppra_scale": result.scale,
            "attempts": result.attempts,
            "out": str(out),
        }
    )


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("retime")(retime)
