"""`lbr fk` and `lbr ik`: forward and inverse kinematics of whole trajectory files."""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Annotated, Optional

import typer

from ..options import DEFAULT_FLANGE, DtOpt, FlangeOpt, JsonOpt, LimitsOpt, ToolOpt


def fk(
    joint_csv: Annotated[Path, typer.Argument(help="Joint trajectory t,q1..q7 \\[s, rad].")],
    out: Annotated[Path, typer.Option("-o", "--out", help="Task trajectory to write: t,x,y,z,qw,qx,qy,qz \\[s, m].")],
    flange: FlangeOpt = DEFAULT_FLANGE,
    tool: ToolOpt = None,
    dt: DtOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Forward kinematics: the flange (or tool) pose in the base frame for every sample."""
    from trajectories.csvio import read_joint_csv, write_task_csv
    from trajectories.poses import quaternions_from_matrices
    from trajectories.trajectory import TaskTrajectory

    from ..console import Reporter
    from ..options import check_number, make_robot
    from ..outputs import guard_outputs

    rep = Reporter(json_out)
    check_number("--dt", dt, 1e-4, 1.0, unit="s")
    guard_outputs({"JOINT_CSV": joint_csv}, {"-o": out})
    robot = make_robot(flange, tool)
    traj = read_joint_csv(joint_csv, dt)
    pos, rot = robot.fk_path(traj.q)
    write_task_csv(out, TaskTrajectory(t=traj.t, position=pos, quaternion=quaternions_from_matrices(rot)))
    rep.print(f"wrote {out}: {len(traj)} poses over {traj.duration:.3f} s")
    rep.emit({"samples": len(traj), "duration_s": traj.duration, "out": str(out)})


def ik(
    task_csv: Annotated[Path, typer.Argument(help="Task trajectory t,x,y,z,qw,qx,qy,qz \\[s, m] of the flange (or tool).")],
    out: Annotated[Path, typer.Option("-o", "--out", help="Joint trajectory to write: t,q1..q7 \\[s, rad].")],
    q0: Annotated[
        Optional[str],
        typer.Option(
            "--q0",
            help="Start guess and redundancy target (7 angles, deg/rad suffixes). Default: chosen for the whole "
            "path among the inverse solutions of the first pose (the one keeping the path furthest from the limits).",
        ),
    ] = None,
    flange: FlangeOpt = DEFAULT_FLANGE,
    tool: ToolOpt = None,
    limits: LimitsOpt = None,
    nullspace_rate: Annotated[
        float, typer.Option("--nullspace-rate", help="Pull toward the start configuration in the null space \\[1/s].")
    ] = 1.0,
    no_speed_limits: Annotated[
        bool, typer.Option("--no-speed-limits", help="Bound joint positions only, not joint speeds and accelerations.")
    ] = False,
    smooth: Annotated[
        bool,
        typer.Option(
            "--smooth",
            help="Without --q0: when the joint accelerations exceed the limit, also plan the arm angle over the "
            "whole path (0.5–4 s more) and keep the path with the lower peak acceleration.",
        ),
    ] = False,
    json_out: JsonOpt = False,
) -> None:
    """Inverse kinematics of a whole path inside the joint position, speed and acceleration limits.

    Each Newton step is a box-constrained least-squares problem (position limits, q̇max·Δt, q̈max·Δt²), the
    redundancy is pulled toward the start at --nullspace-rate per second. Without --q0 the start is chosen for
    the whole path and reported. Exits 1 naming the first pose that cannot be reached and why: out of reach
    (by how much), a joint held at its position limit, or a joint speed the path needs above its limit.
    """
    from trajectories.csvio import read_task_csv, write_joint_csv

    from ..console import Reporter

    rep = Reporter(json_out)
    task = read_task_csv(task_csv)
    with rep.progress("IK", len(task)) as update:
        traj, figures = ik_path(task, q0, flange, tool, limits, nullspace_rate, no_speed_limits, smooth, update)
    write_joint_csv(out, traj)
    figures["out"] = str(out)
    start_deg = ", ".join(f"{math.degrees(v):.1f}" for v in figures["q_start_rad"])
    typer.echo(f"start ({'--q0' if q0 is not None else figures['start']}): [{start_deg}] deg", err=True)
    rep.print(
        f"wrote {out}: {len(traj)} poses in {figures['solve_time_s']:.2f} s; max error "
        f"{figures['max_position_error_m']:.2e} m, {figures['max_rotation_error_rad']:.2e} rad; peak speed "
        f"{figures['peak_velocity_ratio'] * 100:.0f} %, acceleration {figures['peak_acceleration_ratio'] * 100:.0f} % "
        "of the limits"
    )
    if figures["peak_acceleration_ratio"] > 1.0 and not no_speed_limits:
        rep.warn(
            f"joint accelerations reach {figures['peak_acceleration_ratio'] * 100:.0f} % of the limit "
            f"({figures['acceleration_relaxed_samples']} samples could not keep the acceleration bound); see "
            f"`lbr check {out}`"
        )
    if not figures["limits_ok"]:
        rep.warn(f"the joint path violates limits ({figures['violations']} violations); see `lbr check {out}`")
    figures.pop("violations")
    rep.emit(figures)


def ik_path(task, q0: str | None = None, flange: str = DEFAULT_FLANGE, tool: str | None = None,
            limits: Path | None = None, nullspace_rate: float = 1.0, no_speed_limits: bool = False,
            smooth: bool = False, progress=None):
    """`lbr ik` of a read task trajectory without the output file: (JointTrajectory, the JSON figures but ``out``;
    ``violations`` counts the limit check's findings). ``lbr sweep`` calls it too."""
    from trajectories.check import check_trajectory
    from trajectories.errors import OptionError
    from trajectories.ik import IkOptions, solve_ik_path
    from trajectories.poses import matrices_from_quaternions
    from trajectories.trajectory import JointTrajectory

    from ..options import limits_from, make_robot
    from ..parsing import parse_joint_vector

    q_ref = parse_joint_vector(q0, "--q0") if q0 is not None else None
    if not (math.isfinite(nullspace_rate) and nullspace_rate >= 0):
        raise OptionError(f"--nullspace-rate: expected a rate >= 0 [1/s], got {nullspace_rate}")
    robot = make_robot(flange, tool)
    lim = limits_from(limits)
    rot = matrices_from_quaternions(task.quaternion)
    options = IkOptions(
        nullspace_rate=nullspace_rate, nullspace_gain=None, speed_limits=not no_speed_limits, smooth=smooth
    )
    t0 = time.perf_counter()
    res = solve_ik_path(robot, task.position, rot, q_ref, lim, options, times=task.t, progress=progress)
    elapsed = time.perf_counter() - t0
    traj = JointTrajectory(t=task.t, q=res.q)
    report = check_trajectory(traj, lim) if len(traj) > 1 else None
    return traj, {
        "samples": len(traj),
        "solve_time_s": elapsed,
        "max_position_error_m": res.max_position_error,
        "max_rotation_error_rad": res.max_rotation_error,
        "start": "q0" if q_ref is not None else res.start,
        "q_start_rad": res.q[0].tolist() if len(res.q) else [],
        "peak_velocity_ratio": res.velocity_ratio,
        "peak_acceleration_ratio": res.acceleration_ratio,
        "acceleration_relaxed_samples": res.acceleration_relaxed,
        "limits_ok": report.ok if report is not None else True,
        "violations": len(report.failing) if report is not None else 0,
    }


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("fk")(fk)
    app.command("ik")(ik)
