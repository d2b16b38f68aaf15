"""The move to a start with a ball on the string: residual sway unshaped / joint-shaped / TCP-shaped (ZVD), judged by
the independent spline + DOP853 pendulum (planners.sway_judge), and the per-cycle cost of the shaped move.

`python benchmarks/run_all.py moves` (random rest-to-rest moves of up to ±0.5 rad per joint around the thesis-like
home, at 20 % of the limits, 5 ms commands, strings 0.25 / 0.6 / 1.0 m).
"""

from __future__ import annotations

import time

import numpy as np

from lbrcli.fri.moves import OnlineMove, ShapedMove
from planners.pendulum import natural_period
from planners.shapers import make_shaper
from planners.sway_judge import judge_sway
from trajectories.limits import default_limits
from trajectories.robot import Robot

HOME = np.array([0.0, 0.6, 0.0, -1.4, 0.0, 1.14, 0.0])
DT = 0.005  # [s]


def _play(move, a, b) -> tuple[np.ndarray, list[float]]:
    move.start(a, b)
    out, cost = [tuple(a)], []
    while not move.done:
        t0 = time.perf_counter()
        out.append(move.next())
        cost.append(time.perf_counter() - t0)
    return np.array(out), cost


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    lim, robot = default_limits(), Robot()
    rng = np.random.default_rng(11)
    per_length = 2 if quick else 6
    plain, joint, tcp, costs, ratios = [], [], [], [], []
    for length in (0.25, 0.6, 1.0):
        sh = make_shaper("zvd", natural_period(length))
        for _ in range(per_length):
            a, b = HOME + rng.uniform(-0.5, 0.5, 7), HOME + rng.uniform(-0.5, 0.5, 7)
            for store, move in ((plain, OnlineMove(lim, DT, 0.2)), (joint, ShapedMove(lim, DT, 0.2, sh.amplitudes, sh.times)),
                                (tcp, ShapedMove(lim, DT, 0.2, sh.amplitudes, sh.times, robot=robot))):  # fmt: skip
                q, cost = _play(move, a, b)
                store.append(judge_sway(robot.fk_path(q)[0], DT, length, len(q) * DT)[0])
                if store is tcp:
                    costs += cost
                    ratios.append(max((np.abs(np.diff(q, k, axis=0)) / DT**k / lm).max()
                                      for k, lm in ((1, lim.velocity), (2, lim.acceleration), (3, lim.jerk))))  # fmt: skip
    us = np.array(costs) * 1e6
    return [
        ("moves judged", float(len(tcp)), ""),
        ("residual sway unshaped, median", float(np.median(plain)), "deg"),
        ("residual sway unshaped, max", float(np.max(plain)), "deg"),
        ("residual sway joint-shaped ZVD, max", float(np.max(joint)), "deg"),
        ("residual sway TCP-shaped ZVD (lbr), median", float(np.median(tcp)), "deg"),
        ("residual sway TCP-shaped ZVD (lbr), max", float(np.max(tcp)), "deg"),
        ("largest velocity/acceleration/jerk ratio of the shaped moves", float(max(ratios)), "of the limits"),
        ("shaped move per cycle, p50", float(np.percentile(us, 50)), "us"),
        ("shaped move per cycle, p99", float(np.percentile(us, 99)), "us"),
    ]


if __name__ == "__main__":
    for name, value, unit in run():
        print(f"{name:<60} {value:>10.4g} {unit}")
