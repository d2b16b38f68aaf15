"""Kind ``anti-sway``: `lbr plan anti-sway` in the worker (``lbrcli.antisway.plan_anti_sway``), judged over a band of
string lengths with the planners' pendulum model."""

from __future__ import annotations

import inspect
import math
from typing import Any, Mapping

from . import Judge, Outcome, RunKind, python_args, warm_robot


def run(options: Mapping[str, Any], timeout: float | None = None) -> Outcome:
    """Plan as the command does; a plan that cannot be used is exit 1 with the command's message."""
    from lbrcli.antisway import plan_anti_sway
    from lbrcli.commands.plan_antisway import FLAGS, anti_sway_inputs
    from lbrcli.console import _jsonable
    from lbrcli.option_groups import settings_named

    kw = anti_sway_inputs(**python_args(options))
    with settings_named(FLAGS):  # the error names the option, as the command's does
        result = plan_anti_sway(**kw)
    return Outcome(
        _jsonable(result.figures()),
        joints=result.joints,
        context={
            "stop_time": result.stop_time,
            "length": float(options["length"]),
            "flange": kw["flange"],
            "tool": kw["tool"],
        },
    )


def judge(outcome: Outcome, spec: Judge) -> dict:
    """Residual (after the last stop) and peak sway [deg] of the written joints for each string length error."""
    from lbrcli.antisway import predict_band
    from lbrcli.options import make_robot
    from planners.sway_judge import judge_sway

    ctx = outcome.context
    robot = make_robot(ctx["flange"], ctx["tool"])
    lengths = [ctx["length"] * (1 + e) for e in spec.errors]
    if spec.model == "independent":
        pos, _ = robot.fk_path(outcome.joints.q)
        res, peak = zip(*(judge_sway(pos, outcome.joints.dt, ln, ctx["stop_time"]) for ln in lengths))
    else:
        band = predict_band(outcome.joints, robot, lengths, ctx["stop_time"])
        res, peak = (tuple(math.degrees(v) for v in band.residual), tuple(math.degrees(v) for v in band.peak))
    return {
        "judged_residual_sway_deg": max(res),
        "judged_peak_sway_deg": max(peak),
        "judged_residual_sway_by_error_deg": list(res),
    }


def _option_names() -> tuple[str, ...]:
    from lbrcli.commands.plan_antisway import anti_sway_inputs

    return tuple(p.replace("_", "-") for p in inspect.signature(anti_sway_inputs).parameters)


KIND = RunKind(
    name="anti-sway",
    command=("plan", "anti-sway"),
    run=run,
    options=_option_names(),
    summary="lbr plan anti-sway: crane move through turning points; judged: residual sway over the string band",
    required=("length", "a-max"),
    paths=("obstacles", "limits"),
    judge=judge,
    warm_up=warm_robot,
)
