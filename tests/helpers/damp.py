"""Damping runs as the control-damp tests judge them: unshaped joint moves written as a CSV, the log read back as
columns, the largest sway some natural periods after the last move."""

from __future__ import annotations

import csv
import math
import numpy as np
from planners.pendulum import natural_period


from tests.helpers.cli import Q_START

DT = 0.005  # [s] the moves' row spacing
THESIS = Q_START  # [rad] flange along base +x
Q0 = np.array([0.0, 0.6, 0.0, -1.4, 0.0, 1.14, 0.0])  # [rad] flange pointing down: the ball hangs below the TCP


def min_jerk_profile(n: int) -> np.ndarray:
    s = np.linspace(0.0, 1.0, n)
    return 10 * s**3 - 15 * s**4 + 6 * s**5


def write_moves(path, moves=((np.array([0.3, 0, 0, 0, 0, 0, 0]), 1.0), (np.array([0, 0.12, 0, 0.15, 0, 0, 0]), 0.9)),
                 hold: float = 0.4, q0: np.ndarray = Q0, dt: float = DT) -> float:  # fmt: skip
    """Unshaped joint moves (Δq [rad], duration [s]) with holds, rows every ``dt`` [s]; returns the time the last
    move ends [s]."""
    DT = dt  # noqa: N806
    q = np.array(q0, dtype=float)
    rows = [np.repeat(q[None], int(hold / DT), axis=0)]
    for dq, dur in moves:
        seg = q + min_jerk_profile(int(round(dur / DT)))[:, None] * dq
        rows.append(seg)
        q = seg[-1]
        end = sum(len(r) for r in rows) * DT
        rows.append(np.repeat(q[None], int(hold / DT), axis=0))
    q_all = np.vstack(rows)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t", *(f"q{j}" for j in range(1, 8))])
        for k, r in enumerate(q_all):
            w.writerow([f"{k * DT:.6f}", *(f"{v:.10f}" for v in r)])
    return end


def read_log(path) -> dict[str, np.ndarray]:
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    data = np.array([[float(x) if x else math.nan for x in r] for r in rows[1:]])
    return {n: data[:, i] for i, n in enumerate(rows[0])}


def sway_after(log: dict, move_end: float, periods: float, true_length: float, column: str = "ball_theta") -> float:
    t, phase = log["t"], log["phase"]
    t0 = t[np.flatnonzero(phase == 2)[0]]  # the first row
    m = (t >= t0 + move_end + periods * natural_period(true_length)) & (phase >= 2)
    assert m.sum() > 20
    return float(np.degrees(np.abs(log[column][m]).max()))
