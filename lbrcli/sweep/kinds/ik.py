"""Kind ``ik``: `lbr ik TASK.csv` in the worker (``lbrcli.commands.kinematics.ik_path``, the command's own function);
vary ``task`` over a set of paths (a list, or ``{ glob = "paths/*.csv" }``)."""

from __future__ import annotations

from typing import Any, Mapping

from . import Outcome, RunKind, python_args


def run(options: Mapping[str, Any], timeout: float | None = None) -> Outcome:
    """IK of the task file; a pose that cannot be reached is exit 1 with the command's message."""
    from lbrcli.commands.kinematics import ik_path
    from lbrcli.console import _jsonable
    from trajectories.csvio import read_task_csv

    kw = python_args(options)
    traj, figures = ik_path(read_task_csv(kw.pop("task")), **kw)
    figures.pop("violations")
    return Outcome(_jsonable(figures), joints=traj)


KIND = RunKind(
    name="ik",
    command=("ik",),
    run=run,
    options=("task", "q0", "flange", "tool", "limits", "nullspace-rate", "no-speed-limits", "smooth"),
    summary="lbr ik: IK of task paths inside the joint limits",
    required=("task",),
    paths=("task", "limits"),
    arguments=("task",),
)
