"""`lbr fk` and `lbr ik`: forward and inverse kinematics of whole trajectory files."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated, Optional

import typer

from ..options import DEFAULT_FLANGE, THESIS_Q_START, DtOpt, FlangeOpt, JsonOpt, LimitsOpt, ToolOpt


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
    from ..options import make_robot

    rep = Reporter(json_out)
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
        str,
        typer.Option("--q0", help="Reference configuration: start of the solve and redundancy target (7 angles, deg/rad suffixes)."),
    ] = THESIS_Q_START,
    flange: FlangeOpt = DEFAULT_FLANGE,
    tool: ToolOpt = None,
    limits: LimitsOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Inverse kinematics of a whole path: warm-started damped least squares on pinocchio.

    Joint limits are respected and the redundancy is resolved toward --q0, so the arm never flips
    configuration mid-path. Exits 1 naming the first unreachable pose and its remaining error.
    """
    from trajectories.check import check_trajectory
    from trajectories.csvio import read_task_csv, write_joint_csv
    from trajectories.ik import solve_ik_path
    from trajectories.poses import matrices_from_quaternions
    from trajectories.trajectory import JointTrajectory

    from ..console import Reporter
    from ..options import limits_from, make_robot
    from ..parsing import parse_joint_vector

    rep = Reporter(json_out)
    q_ref = parse_joint_vector(q0, "--q0")
    robot = make_robot(flange, tool)
    lim = limits_from(limits)
    task = read_task_csv(task_csv)
    rot = matrices_from_quaternions(task.quaternion)
    t0 = time.perf_counter()
    with rep.progress("IK", len(task)) as update:
        res = solve_ik_path(robot, task.position, rot, q_ref, lim, times=task.t, progress=update)
    elapsed = time.perf_counter() - t0
    traj = JointTrajectory(t=task.t, q=res.q)
    write_joint_csv(out, traj)
    report = check_trajectory(traj, lim) if len(traj) > 1 else None
    rep.print(
        f"wrote {out}: {len(traj)} poses in {elapsed:.2f} s; max error {res.max_position_error:.2e} m, "
        f"{res.max_rotation_error:.2e} rad"
    )
    if report is not None and not report.ok:
        rep.warn(f"the joint path violates limits ({len(report.failing)} violations); see `lbr check {out}`")
    rep.emit(
        {
            "samples": len(traj),
            "solve_time_s": elapsed,
            "max_position_error_m": res.max_position_error,
            "max_rotation_error_rad": res.max_rotation_error,
            "limits_ok": report.ok if report is not None else True,
            "out": str(out),
        }
    )


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("fk")(fk)
    app.command("ik")(ik)
