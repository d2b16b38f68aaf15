"""One run of a study where Dask puts it: the kind's run, its judged figures, its time — and every failure as a record,
never an exception (a failing run is a row of the table, not the end of the study)."""

from __future__ import annotations

import os
import socket
import time
import traceback
from dataclasses import dataclass
from typing import Any

from .spec import Run


@dataclass(frozen=True)
class RunResult:
    """A run's record (JSON-able, as the store keeps it) and, when asked for, its joint trajectory."""

    record: dict
    joints: Any = None  # trajectories.trajectory.JointTrajectory


def status_of(exit_code: int, crashed: bool = False) -> str:
    """ok (exit 0), failed (1: the command did not reach its goal), bad-input (2), crashed (an exception that is no
    lbr error, a lost worker, a timeout, another exit code)."""
    if crashed:
        return "crashed"
    return {0: "ok", 1: "failed", 2: "bad-input"}.get(exit_code, "crashed")


def record(
    run: Run,
    exit_code: int,
    error: str | None,
    figures: dict,
    judged: dict,
    seconds: float,
    crashed: bool = False,
    worker: str | None = None,
) -> dict:
    """The JSON record of a completed run (NaN and ±inf become null, as in the commands' --json)."""
    from lbrcli.console import _jsonable

    return {
        "key": run.key,
        "kind": run.kind,
        "exit_code": int(exit_code),
        "status": status_of(exit_code, crashed),
        "error": error,
        "figures": _jsonable(figures),
        "judged": _jsonable(judged),
        "seconds": seconds,
        "worker": worker or f"{socket.gethostname()}:{os.getpid()}",
        "finished": time.time(),
    }


def execute(run: Run, joints: bool = False) -> RunResult:
    """Run ``run`` in this process; with ``joints`` the result carries its joint trajectory (if it made one)."""
    from trajectories.errors import LbrError

    from .kinds import get_kind

    t0 = time.perf_counter()
    kind = get_kind(run.kind)
    try:
        out = kind.run(dict(run.options), run.timeout)
    except LbrError as exc:
        return RunResult(record(run, exc.exit_code, str(exc), {}, {}, time.perf_counter() - t0))
    except Exception as exc:  # a bug or an unforeseen input: the row says what, with where it was raised
        where = traceback.extract_tb(exc.__traceback__)[-1]
        error = f"{type(exc).__name__}: {exc} ({os.path.basename(where.filename)}:{where.lineno})"
        return RunResult(record(run, 1, error, {}, {}, time.perf_counter() - t0, crashed=True))
    judged: dict = {}
    if run.judge is not None and kind.judge is not None and out.joints is not None and out.exit_code in (0, 1):
        try:
            judged = kind.judge(out, run.judge)
        except Exception as exc:  # the judge failing is no reason to lose the run's figures
            judged = {"judge_error": f"{type(exc).__name__}: {exc}"}
    rec = record(run, out.exit_code, out.error, out.figures, judged, time.perf_counter() - t0)
    return RunResult(rec, out.joints if joints else None)


def execute_batch(runs: tuple[Run, ...], joints: frozenset[str] = frozenset()) -> list[RunResult]:
    """Several runs in one task (for very short runs); ``joints``: keys of the runs whose trajectories to return."""
    return [execute(r, r.key in joints) for r in runs]
