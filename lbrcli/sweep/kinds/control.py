"""Kinds ``control-damp`` and ``control-upright``: `lbr control damp|upright` on the built-in simulator, each run its
own `lbr` process (an FRI session at 1–5 ms in real time, with the simulator in another process, as the command
runs it; ``--port 0`` so that runs sharing a machine do not collide; the simulator's lenient connection quality is
the commands' default, ``sim-strict = true`` asks for the real controller's).

``control-damp`` streams ``joint-csv``, or the anti-sway move planned from the inline table ``plan`` (anti-sway
options; planned once per worker process and options)."""

from __future__ import annotations

import atexit
import functools
import shutil
import tempfile
from pathlib import Path
from typing import Any, Mapping

from . import Outcome, RunKind, option_words
from ._process import run_lbr

DAMP_OPTIONS = ("length", "damp-time", "sensor", "io-names", "module-axis", "sensor-delay", "sensor-rate", "open-loop",
                "move-to-start", "start-tolerance", "start-sway", "sway-wait", "sim-length", "sim-delay", "sim-start",
                "wait", "sim-lenient", "sim-strict", "flange", "tool", "limits", "dt", "port", "fri-version")  # fmt: skip
UPRIGHT_OPTIONS = ("rod-length", "rod-mass", "tip-mass", "hold", "swing-timeout", "travel", "q-start", "move-to-start",
                   "sensor-rate", "sensor-delay", "sim-delay", "sim-jitter", "push", "period", "wait", "sim-lenient",
                   "sim-strict", "limits", "port", "fri-version")  # fmt: skip
SESSION = {"port": 0}


@functools.lru_cache(maxsize=8)
def _planned(plan: tuple) -> str:
    """The joint CSV of an anti-sway plan (the options of the inline table), kept for this worker process."""
    from .antisway import run as plan_run

    from trajectories.csvio import write_joint_csv
    from trajectories.errors import PlanningError

    outcome = plan_run(dict(plan), None)
    if outcome.exit_code:
        raise PlanningError(f"control-damp: the plan failed: {outcome.error}")
    folder = tempfile.mkdtemp(prefix="lbr-sweep-plan-")
    atexit.register(shutil.rmtree, folder, True)
    path = Path(folder) / "plan.csv"
    write_joint_csv(path, outcome.joints)
    return str(path)


def run_damp(options: Mapping[str, Any], timeout: float | None = None) -> Outcome:
    from trajectories.errors import OptionError

    opts = dict(options)
    plan, csv = opts.pop("plan", None), opts.pop("joint-csv", None)
    if (plan is None) == (csv is None):
        raise OptionError("control-damp: give either joint-csv or plan (an inline table of anti-sway options)")
    if plan is not None:
        csv = _planned(tuple(plan))
    return run_lbr(["control", "damp", str(csv), *option_words(opts)], timeout)


def run_upright(options: Mapping[str, Any], timeout: float | None = None) -> Outcome:
    return run_lbr(["control", "upright", *option_words(options, ("push",))], timeout)


KINDS = (
    RunKind(
        name="control-damp",
        command=("control", "damp"),
        run=run_damp,
        options=("joint-csv", "plan") + DAMP_OPTIONS,
        summary="lbr control damp on the simulator: a joint CSV (or an anti-sway plan) streamed with sway damping",
        paths=("joint-csv", "limits"),
        arguments=("joint-csv",),
        kind_only=("plan",),
        defaults=SESSION,
    ),
    RunKind(
        name="control-upright",
        command=("control", "upright"),
        run=run_upright,
        options=UPRIGHT_OPTIONS,
        summary="lbr control upright on the simulator: swing the pendulum module up and balance it",
        paths=("limits",),
        repeatable=("push",),
        defaults=SESSION,
    ),
)
