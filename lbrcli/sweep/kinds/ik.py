"""Kind ``ik``: `lbr ik TASK.csv` in the worker (``lbrcli.commands.kinematics.ik_path``, the command's own function);
vary ``task`` over a set of paths (a list, or ``{ glob = "paths/*.csv" }``), or ``suite-path`` over the paths of the
IK benchmark's suite (``trajectories.ik_paths.build_suite``, seeded by ``suite-seed``; judged against its witness)."""

from __future__ import annotations

import functools
from typing import Any, Mapping

from . import Outcome, RunKind, python_args, warm_robot


@functools.lru_cache(maxsize=4)
def _suite(seed: int) -> tuple:
    from trajectories.ik_paths import build_suite
    from trajectories.limits import default_limits
    from trajectories.robot import Robot

    return tuple(build_suite(Robot(), default_limits(), seed=seed))


def run(options: Mapping[str, Any], timeout: float | None = None) -> Outcome:
    """IK of the task file (or suite path); a pose that cannot be reached is exit 1 with the command's message."""
    from lbrcli.commands.kinematics import ik_path
    from lbrcli.console import _jsonable
    from trajectories.csvio import read_task_csv
    from trajectories.errors import OptionError, SettingError

    kw = python_args(options)
    index, seed = kw.pop("suite_path", None), int(kw.pop("suite_seed", 0))
    if (index is None) == ("task" not in kw):
        raise OptionError("ik: give either task (a task CSV) or suite-path (a path of the IK benchmark's suite)")
    if index is None:
        traj, figures = ik_path(read_task_csv(kw.pop("task")), **kw)
    else:
        from trajectories.ik_paths import verify_joint_path
        from trajectories.limits import default_limits
        from trajectories.poses import quaternions_from_matrices
        from trajectories.trajectory import TaskTrajectory

        suite = _suite(seed)
        if not (isinstance(index, int) and 0 <= index < len(suite)):
            raise SettingError("ik", "suite-path", f"must be 0..{len(suite) - 1}, got {index!r}")
        path = suite[index]
        task = TaskTrajectory(t=path.t, position=path.position, quaternion=quaternions_from_matrices(path.rotation))
        traj, figures = ik_path(task, **kw)
        from lbrcli.options import DEFAULT_FLANGE, make_robot

        check = verify_joint_path(make_robot(kw.get("flange", DEFAULT_FLANGE), kw.get("tool")), path, traj.q,
                                  default_limits())  # fmt: skip
        figures.update(path=path.name, path_kind=path.kind, solved=check.ok(), witness=path.witness is not None)
    figures.pop("violations")
    return Outcome(_jsonable(figures), joints=traj)


KIND = RunKind(
    name="ik",
    command=("ik",),
    run=run,
    options=(
        "task",
        "q0",
        "flange",
        "tool",
        "limits",
        "nullspace-rate",
        "no-speed-limits",
        "smooth",
        "suite-path",
        "suite-seed",
    ),
    summary="lbr ik: IK of task paths (files, or the IK benchmark's suite) inside the joint limits",
    paths=("task", "limits"),
    arguments=("task",),
    kind_only=("suite-path", "suite-seed"),
    warm_up=warm_robot,
)
