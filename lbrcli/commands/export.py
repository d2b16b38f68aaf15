"""`lbr export`: execution logs and plans to MCAP in ROS 2's standard messages (Foxglove, rosbag2, RViz)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ..fri_options import DEFAULT_BALL_LENGTH, DrawnLengthOpt
from ..options import DEFAULT_FLANGE, FlangeOpt, JsonOpt, LimitsOpt, ToolOpt, choice


def _ros_name(text: str) -> str:
    """typer ``parser`` of --prefix: a ROS name (a letter, then letters, digits, _)."""
    import re

    if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]{0,63}", str(text)):
        raise typer.BadParameter(f"must be a ROS name (a letter, then up to 63 letters, digits, _), got {text!r}")
    return str(text)


def export(
    files: Annotated[
        list[Path],
        typer.Argument(
            metavar="FILE...", help="An execution log (`lbr execute --log`) and/or a plan (joint trajectory t,q1..q7)."
        ),
    ],
    out: Annotated[Path, typer.Option("-o", "--out", help="MCAP file to write (.mcap).")],
    prefix: Annotated[
        str,
        typer.Option(
            "--prefix",
            parser=_ros_name,
            metavar="NAME",
            help="Robot name: topic namespace, joint names <prefix>_A1..A7 and frames <prefix>_link_0.. as lbr-stack's driver uses them.",
        ),
    ] = "lbr",
    length: DrawnLengthOpt = DEFAULT_BALL_LENGTH,
    compression: Annotated[
        str,
        choice(
            "--compression",
            choices=("zstd", "lz4", "none"),
            help="Chunk compression (1 MiB chunks): zstd (level 1, libmcap's and rosbag2's default), lz4 (less CPU, ≈ 30 % larger) or none.",
        ),
    ] = "zstd",
    flange: FlangeOpt = DEFAULT_FLANGE,
    tool: ToolOpt = None,
    limits: LimitsOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Write an execution log and/or a plan as an MCAP file of standard ROS 2 messages.

    Joint states (measured with measured torques, commanded, ipo, external torques) as sensor_msgs/JointState,
    the measured arm and the flange/TCP as TF, the simulated ball as geometry_msgs/PointStamped (and a TF frame),
    the plan as one trajectory_msgs/JointTrajectory on /<prefix>/joint_trajectory_controller/joint_trajectory (what
    lbr-stack's joint_trajectory_controller takes) plus its rows as joint states, the robot description (URDF of
    --flange/--tool, limits of --limits) latched on /<prefix>/robot_description and attached. Times are the log's
    (the controller's timestamps when logged); a plan given with a log is placed where the log commanded its first
    row. Opens in Foxglove; `ros2 bag play` (rosbag2's MCAP storage) replays it.
    """
    import time

    from trajectories.csvio import read_joint_csv, read_table
    from trajectories.description import urdf
    from trajectories.errors import CsvFormatError, OptionError

    from ..console import Reporter
    from ..fri.log import LOG_COLUMNS, NAN_COLUMNS
    from ..options import limits_from, make_robot
    from ..outputs import atomic_path, guard_outputs
    from ..ros import bag as rosbag
    from ..view.inputs import JOINT, LOG, file_kind

    t0 = time.perf_counter()
    rep = Reporter(json_out)
    if out.suffix.lower() != ".mcap":
        raise OptionError(f"-o: the output is an MCAP file (.mcap), got {out}")
    seen: dict[Path, Path] = {}
    for p in files:
        if p.resolve() in seen:
            raise OptionError(f"FILE {p} is given twice (as {seen[p.resolve()]}): one execution log and/or one plan")
        seen[p.resolve()] = p
    guard_outputs({f"FILE {p}": p for p in files} | {"--limits": limits}, {"-o": out})
    kinds = {p: file_kind(p) for p in files}
    logs = [p for p, k in kinds.items() if k == LOG]
    plans = [p for p, k in kinds.items() if k == JOINT]
    for p, k in kinds.items():
        if k not in (LOG, JOINT):
            raise CsvFormatError(f"lbr export takes execution logs and plans, this is a {k}", file=str(p), row=1)
    if len(logs) > 1 or len(plans) > 1:
        raise OptionError("give at most one execution log and one plan (one run per MCAP file)")
    robot = make_robot(flange, tool)
    description = urdf(robot, limits_from(limits), prefix)
    t_read = 0.0
    series = plan = None
    if logs:
        t1 = time.perf_counter()
        table = read_table(logs[0], LOG_COLUMNS, time="increasing", nan_columns=NAN_COLUMNS)
        t_read = time.perf_counter() - t1
        series = rosbag.read_log_series(table)
    if plans:
        plan = read_joint_csv(plans[0])
    with atomic_path(out) as tmp:
        bag = rosbag.Bag(Path(tmp), compression)
        try:
            start = int(series.time_ns[0]) if series is not None else 0
            rosbag.write_description(bag, description, prefix, start)
            if series is not None:
                rosbag.write_log(bag, series, robot, prefix, length)
            if plan is not None:
                plan_start = series.plan_start_ns if series is not None and series.plan_start_ns is not None else start
                rosbag.write_plan(bag, plan.t, plan.q, robot, prefix, plan_start, with_tf=series is None)
        finally:
            bag.close()
    seconds = time.perf_counter() - t0
    size = out.stat().st_size
    messages = sum(bag.counts.values())
    for topic, count in bag.counts.items():
        rep.print(f"  {topic}: {count} messages")
    rep.print(
        f"wrote {out}: {messages} messages on {len(bag.counts)} topics, {size / 1e6:.1f} MB in {seconds:.2f} s"
        + (f" (clock: {series.clock} timestamps)" if series is not None else "")
    )
    rep.emit(
        {
            "out": str(out),
            "messages": messages,
            "topics": bag.counts,
            "size_bytes": size,
            "seconds": seconds,
            "read_s": t_read,
            "clock": series.clock if series is not None else "plan",
            "log": str(logs[0]) if logs else None,
            "plan": str(plans[0]) if plans else None,
        }
    )


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("export")(export)
