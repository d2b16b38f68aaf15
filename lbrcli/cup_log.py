"""What an execution log says about the cup-and-ball game: when the simulated ball entered the cup and whether it
stayed (the simulator's ``ball_phase`` column: 0 taut, 1 slack, 2 in the cup)."""

from __future__ import annotations

from pathlib import Path
from typing import Any


def cup_summary(log_path: str | Path) -> dict[str, Any] | None:
    """Log times [s] of the ball's first entry into the cup, of its leaving it again, whether it is in the cup at the
    end, and the entry time after the first trajectory row [s]; None when the log has no ``ball_phase``."""
    import numpy as np

    from trajectories.csvio import read_table

    from .fri.log import LOG_COLUMNS, NAN_COLUMNS, PHASE_TRAJECTORY

    table = read_table(log_path, LOG_COLUMNS, time="increasing", nan_columns=NAN_COLUMNS)
    if not table.has("ball_phase"):
        return None
    t, ball, phase = table.column("t"), table.column("ball_phase"), table.column("phase")
    inside = ball == 2.0
    moving = np.flatnonzero(phase == PHASE_TRAJECTORY)
    t0 = float(t[moving[0]]) if moving.size else None
    first = np.flatnonzero(inside)
    if not first.size:
        return {
            "entered_s": None,
            "entered_after_start_s": None,
            "left_s": [],
            "stayed": False,
            "released": bool(np.any(ball == 1.0)),
            "trajectory_start_s": t0,
        }
    k = int(first[0])
    exits = np.flatnonzero(inside[k:-1] & ~inside[k + 1 :]) + k + 1
    return {
        "entered_s": float(t[k]),
        "entered_after_start_s": float(t[k] - t0) if t0 is not None else None,
        "left_s": [float(t[i]) for i in exits],
        "stayed": bool(inside[-1]),
        "released": True,
        "trajectory_start_s": t0,
    }


def describe(summary: dict[str, Any]) -> str:
    """One line for the execution summary."""
    if summary["entered_s"] is None:
        return "ball: never entered the cup" + ("" if summary["released"] else " (the string never went slack)")
    after = summary["entered_after_start_s"]
    when = f"t = {summary['entered_s']:.3f} s" + (
        f" ({after:.3f} s after the first trajectory row)" if after is not None else ""
    )
    if summary["stayed"]:
        hops = len(summary["left_s"])
        return f"ball: entered the cup at {when} and stayed" + (f" (it hopped above the rim {hops}×)" if hops else "")
    return f"ball: entered the cup at {when} but left it at t = {summary['left_s'][-1]:.3f} s and did not come back"
