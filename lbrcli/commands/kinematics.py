"""`lbr fk` and `lbr ik`: forward and inverse kinematics of whole trajectory files."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated, Optional

import typer

from ..options import DEFAULT_FLANGE, DtOpt, FlangeOpt, JointVector, JsonOpt, LimitsOpt, ToolOpt, joints, number


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
    from ..outputs import guard_outputs

    rep = Reporter(json_out)
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
        Optional[JointVector],
        joints(
            "--q0",
            help="Start guess and redundancy target (7 angles, deg/rad suffixes; inside the position limits). "
            "Default: chosen for the whole path among the inverse solutions of the first pose (the one keeping the "
            "path furthest from the limits).",
        ),
    ] = None,
    flange: FlangeOpt = DEFAULT_FLANGE,
    tool: ToolOpt = None,
    limits: LimitsOpt = None,
    nullspace_rate: Annotated[
        float, number("--nullspace-rate", low=0, high=1e4, unit="1/s",
                      help="Pull toward the start configuration in the null space \\[1/s].")
    ] = 1.0,
    no_speed_limits: Annotated[
        bool, typer.Option("--no-speed-limits", help="Bound joint positions only, not joint speeds and accelerations.")
    ] = False,
    smooth: Annotated[
        bool,
        typer.Option(
            "--smooth",
            help="When the joint accelerations exceed the limit: without --q0 also plan the arm angle over the "
            "whole path (0.5–4 s more) and keep the path with the lower peak acceleration; then move the path "
            "along its self-motion to lower them further (done anyway when the task path starts and ends at rest).",
        ),
    ] = False,
    json_out: JsonOpt = False,
) -> None:
    """Inverse kinematics of a whole path inside the joint position, speed and acceleration limits.

    Each Newton step is a box-constrained least-squares problem (position limits, q̇max·Δt, q̈max·Δt²), the
    redundancy is pulled toward the start at --nullspace-rate per second. Without --q0 the start is chosen for
    the whole path and reported. Where the task path starts or ends at rest, the self-motion is brought to rest
    with it, so the file passes `lbr check`; when the task starts and ends at rest and the joint path still fails
    the check, the file is written and the command exits 1 naming the first violation. A path that cannot be
    followed exits 1 naming its first pose that no joint path reaches inside the limits and why: out of reach (by
    how much), beyond a joint's position limit at every arm angle, or A4 (set by the pose alone) faster than its
    limit — found at every sample before anything is solved; with --q0, also where the path from that start runs
    into a limit while the pose itself is reachable.
    """
    import math

    from trajectories.check import check_trajectory
    from trajectories.csvio import read_task_csv, write_joint_csv
    from trajectories.errors import CheckFailed, IkError
    from trajectories.ik import IkOptions, solve_ik_path
    from trajectories.poses import matrices_from_quaternions
    from trajectories.trajectory import JointTrajectory

    from ..console import Reporter
    from ..options import limits_from, make_robot, within_limits

    rep = Reporter(json_out)
    robot = make_robot(flange, tool)
    lim = limits_from(limits)
    q_ref = within_limits(q0, lim, "--q0")
    task = read_task_csv(task_csv)
    rot = matrices_from_quaternions(task.quaternion)
    options = IkOptions(
        nullspace_rate=nullspace_rate, nullspace_gain=None, speed_limits=not no_speed_limits, smooth=smooth
    )
    t0 = time.perf_counter()
    try:
        with rep.progress("IK", len(task)) as update:
            res = solve_ik_path(robot, task.position, rot, q_ref, lim, options, times=task.t, progress=update)
    except IkError as exc:
        rep.emit({"ok": False, "exit_code": 1, "error": str(exc), "refusal": exc.figures(),
                  "solve_time_s": time.perf_counter() - t0})  # fmt: skip
        raise
    elapsed = time.perf_counter() - t0
    traj = JointTrajectory(t=task.t, q=res.q)
    write_joint_csv(out, traj)
    report = check_trajectory(traj, lim) if len(traj) > 1 else None
    start_deg = ", ".join(f"{math.degrees(v):.1f}" for v in res.q[0]) if len(res.q) else ""
    typer.echo(f"start ({'--q0' if q_ref is not None else res.start}): [{start_deg}] deg", err=True)
    rep.print(
        f"wrote {out}: {len(traj)} poses in {elapsed:.2f} s; max error {res.max_position_error:.2e} m, "
        f"{res.max_rotation_error:.2e} rad; peak speed {res.velocity_ratio * 100:.0f} %, "
        f"acceleration {res.acceleration_ratio * 100:.0f} % of the limits"
    )
    rest_at_ends = all(res.at_rest)
    contract = all(res.task_at_rest) and options.speed_limits  # the file must pass `lbr check`
    if report is not None:
        moving = [end for end, ok in zip(("start", "end"), res.task_at_rest) if not ok]
        if rest_at_ends:
            rep.print("at rest at both ends (the self-motion brought to rest with the task)")
        elif moving:
            rep.warn(
                f"the task path moves at its {' and '.join(moving)}: the joint path cannot start and end at rest there, "
                f"so `lbr check` and `lbr execute` refuse it; let the task path start and end at rest"
            )
        if res.acceleration_ratio > 1.0 and options.speed_limits and not contract:
            rep.warn(
                f"joint accelerations reach {res.acceleration_ratio * 100:.0f} % of the limit ({res.acceleration_relaxed} "
                f"samples could not keep the acceleration bound); see `lbr check {out}`"
            )
        if not report.ok and not contract:
            rep.warn(f"the joint path violates limits ({len(report.failing)} violations); see `lbr check {out}`")
    check_figures = {} if report is None else report.to_dict()
    rep.emit(
        {
            "samples": len(traj),
            "solve_time_s": elapsed,
            "max_position_error_m": res.max_position_error,
            "max_rotation_error_rad": res.max_rotation_error,
            "start": "q0" if q_ref is not None else res.start,
            "q_start_rad": res.q[0].tolist() if len(res.q) else [],
            "peak_velocity_ratio": res.velocity_ratio,
            "peak_acceleration_ratio": res.acceleration_ratio,
            "acceleration_relaxed_samples": res.acceleration_relaxed,
            "rest_at_ends": rest_at_ends,
            "task_at_rest": {"start": res.task_at_rest[0], "end": res.task_at_rest[1]},
            "limits_ok": report.ok if report is not None else True,
            "check": {k: check_figures[k] for k in ("max_ratio", "violations") if k in check_figures},
            "jerk_ratio": check_figures.get("max_ratio", {}).get("jerk", 0.0),
            "out": str(out),
        }
    )
    if contract and report is not None and not report.ok:
        raise CheckFailed(
            f"{out}: written, but it fails `lbr check` although the task path starts and ends at rest: "
            f"{report.failing[0].describe()}"
        )


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("fk")(fk)
    app.command("ik")(ik)
