"""Kind ``swing-up``: `lbr plan swing-up` in the worker (``plan_swing_up_files``, the command's own function), judged by
the ball simulated under the written joints with the string off by the judge's errors."""

from __future__ import annotations

import math
import tempfile
from pathlib import Path
from typing import Any, Mapping

from . import Judge, Outcome, RunKind, warm_robot

# command-line name → keyword of plan_swing_up_files, where they differ; angles are parsed as the command does
RENAMED = {"ke": "k_e", "kp": "k_p", "kd": "k_d", "max-travel": "travel"}
ANGLES = {"theta-d": None, "theta0": "0", "tolerance": "2deg"}  # option → the command's default text
OPTIONS = (
    "length",
    "mass",
    "theta-d",
    "method",
    "theta0",
    "push",
    "ke",
    "kp",
    "kd",
    "duration",
    "dt",
    "q-start",
    "max-travel",
    "taut",
    "tolerance",
    "margin",
    "orientation",
    "workers",
    "side",
    "flange",
    "tool",
    "limits",
)


def run(options: Mapping[str, Any], timeout: float | None = None) -> Outcome:
    """Plan, write the joints to a scratch folder (as the command) and read them back for the judge."""
    from lbrcli.commands.plan_swingup import plan_swing_up_files
    from lbrcli.console import _jsonable
    from lbrcli.parsing import parse_angle
    from trajectories.csvio import read_joint_csv

    kw: dict[str, Any] = {}
    for name, value in options.items():
        kw[RENAMED.get(name, name.replace("-", "_"))] = value
    for name, default in ANGLES.items():
        key = name.replace("-", "_")
        kw[key] = parse_angle(str(options.get(name, default)), f"--{name}")
    with tempfile.TemporaryDirectory(prefix="lbr-sweep-") as tmp:
        out = Path(tmp) / "swing-up.csv"
        figures = plan_swing_up_files(out=out, **kw)
        joints = read_joint_csv(out)
    figures.pop("out", None)
    context = {k: kw.get(k) for k in ("length", "theta_d", "theta0", "tolerance", "flange", "tool")}
    return Outcome(_jsonable(figures), 1 if figures["failure"] else 0, figures["failure"], joints, context)


def judge(outcome: Outcome, spec: Judge) -> dict:
    """Largest verified |θ| [deg] with the string off by each error, the worst of them, and the share of errors
    for which θ_d − tolerance is still reached (the planners' nonlinear ball model; no independent one here)."""
    from lbrcli.options import DEFAULT_FLANGE, make_robot
    from planners.swingup_robot import verify

    ctx = outcome.context
    robot = make_robot(ctx["flange"] or DEFAULT_FLANGE, ctx["tool"])
    reached = math.degrees(ctx["theta_d"] - ctx["tolerance"])
    peaks = [
        math.degrees(verify(robot, outcome.joints, ctx["length"] * (1 + e), ctx["theta0"]).max_theta)
        for e in spec.errors
    ]
    return {
        "judged_max_theta_deg": min(peaks),
        "judged_reached_share": sum(p >= reached for p in peaks) / len(peaks),
        "judged_max_theta_by_error_deg": peaks,
    }


KIND = RunKind(
    name="swing-up",
    command=("plan", "swing-up"),
    run=run,
    options=OPTIONS,
    summary="lbr plan swing-up: energy or fast swing-up to θ_d; judged: max θ over the string band",
    required=("length", "mass", "theta-d"),
    paths=("limits",),
    defaults={"workers": 1},  # the study is the parallelism: one process per run (same plan as with 2)
    judge=judge,
    warm_up=warm_robot,
)
