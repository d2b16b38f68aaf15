"""One time line for files on different clocks: a plan and its prediction start at their first row, an execution
log at its first FRI message, a video's track at its first frame.

- The first execution log is the reference. Plan-clock files (joint and task trajectories, predictions) are placed
  where the log commanded the plan's first row (its ``phase``/``row`` columns).
- A track is placed by matching its θ to the reference ball (the log's simulated ball, else the prediction) by
  cross-correlation, as `lbr compare` estimates the lag.
- ``--offset FILE=SECONDS`` places a file by hand. The time line then starts at 0 at the earliest sample.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .inputs import JOINT, LOG, OBSTACLES, TRACK, InputFile

PHASE_TRAJECTORY = 2  # lbrcli.fri.constants.Phase.TRAJECTORY (the log's rows of the file)


@dataclass(frozen=True)
class Alignment:
    """Offsets [s] that put each file's time on the view's time line, how each was found, and the span."""

    offsets: dict[str, float]  # path → view time − file time [s]
    how: dict[str, str]  # path → how the offset was found
    duration: float  # [s], the time line runs from 0 to this


def _times(f: InputFile) -> np.ndarray | None:
    for series in (*f.arms, *f.balls):
        return series.t
    return f.pivot_t


def _plan_start(log: InputFile, plan: InputFile | None) -> tuple[float, str] | None:
    """Log time [s] of the plan's t = 0: where the log commanded its first row."""
    st = log.state
    rows = np.flatnonzero((st.phase == PHASE_TRAJECTORY) & (st.row >= 0))
    if rows.size == 0:
        return None
    k = int(rows[0])
    row = int(st.row[k])
    t_row = 0.0
    if row > 0 and plan is not None and row < len(plan.arms[0].t):
        t_row = float(plan.arms[0].t[row])
    return float(st.t[k]) - t_row, f"its row {row} at {log.name}'s t = {st.t[k]:.3f} s"


def _given(path: str, given: dict[str, float]) -> float | None:
    for key in (path, Path(path).name, str(Path(path).resolve())):
        if key in given:
            return given[key]
    return None


def align(files: list[InputFile], given: dict[str, float] | None = None) -> Alignment:
    """Offsets of every file (see the module doc); ``given`` maps a path or file name to its offset [s]."""
    from trajectories.errors import LbrError

    from tracking.compare import estimate_lag

    given = dict(given or {})
    offsets: dict[str, float] = {}
    how: dict[str, str] = {}
    logs = [f for f in files if f.kind == LOG]
    plan = next((f for f in files if f.kind == JOINT), None)
    reference = logs[0] if logs else None
    plan_offset, plan_how = 0.0, "plan clock (t = 0 at the first row)"
    if reference is not None:
        start = _plan_start(reference, plan)
        if start is not None:
            plan_offset, plan_how = start[0], f"plan clock placed at {start[1]}"
        else:
            plan_how = f"plan clock from 0 ({reference.name} commanded no plan row)"
    for f in files:
        if f.kind == OBSTACLES:
            continue
        if f.kind == LOG:
            offsets[f.path] = 0.0
            how[f.path] = "reference clock" if f is reference else "its own clock (from 0)"
        elif f.plan_clock:
            offsets[f.path], how[f.path] = plan_offset, plan_how
    ref_ball = next((b for f in logs for b in f.balls), None)
    if ref_ball is None:
        ref_ball = next((b for f in files if f.kind != TRACK for b in f.balls), None)
    for f in files:
        if f.kind != TRACK:
            continue
        offsets[f.path], how[f.path] = 0.0, "its own clock (from 0): nothing to match its θ with"
        if ref_ball is None:
            continue
        ref_offset = offsets[ref_ball.source]
        ball = f.balls[0]
        try:
            est = estimate_lag(ref_ball.t, ref_ball.planar, ball.t, ball.planar)
        except (LbrError, ValueError) as exc:
            how[f.path] = f"its own clock (from 0): θ not matched ({exc})"
            continue
        if math.isfinite(est.lag_s):
            offsets[f.path] = ref_offset - est.lag_s
            how[f.path] = (
                f"θ matched to {Path(ref_ball.source).name} (lag {est.lag_s:+.3f} s, score {est.correlation:.3f})"
            )
    for f in files:
        value = _given(f.path, given)
        if value is not None and f.kind != OBSTACLES:
            offsets[f.path], how[f.path] = float(value), "given by hand (offset)"
    spans = [
        (offsets[f.path] + t[0], offsets[f.path] + t[-1])
        for f in files
        if f.kind != OBSTACLES and (t := _times(f)) is not None and len(t)
    ]
    if not spans:
        return Alignment({}, {}, 0.0)
    first = min(s[0] for s in spans)
    return Alignment({p: v - first for p, v in offsets.items()}, how, max(s[1] for s in spans) - first)
