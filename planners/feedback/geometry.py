"""Can a sensor measure the sway a move makes? The pendulum module's rod swings about its bearing axis — the flange's
z axis — so it measures the sway across that axis, and only where the axis is horizontal."""

from __future__ import annotations

import math

import numpy as np


def module_axis_error(robot, q: np.ndarray, base_axis: int, stride: int = 10) -> tuple[int, float]:
    """(row, angle [rad]) of the row of ``q`` (n, 7) [rad] where the TCP's z axis (the module's bearing) is farthest
    from the base axis ``base_axis`` (0 x, 1 y) — either direction — sampled every ``stride`` rows and at the last."""
    q = np.asarray(q, dtype=float)
    rows = list(range(0, len(q), max(1, stride)))
    if rows[-1] != len(q) - 1:
        rows.append(len(q) - 1)
    worst, worst_row = 0.0, 0
    for k in rows:
        z = robot.fk(q[k]).rotation[:, 2]
        angle = math.acos(min(1.0, abs(float(z[base_axis]))))
        if angle > worst:
            worst, worst_row = angle, k
    return worst_row, worst
