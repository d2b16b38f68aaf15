"""IK throughput: a 10 s path at 1 kHz (10,001 poses) with changing orientation, one core: the library default
(every sample sequentially, position limits) and `lbr ik`'s mode (speed limits, coarse pass + vectorised
refinement), with the start given and chosen by the solver."""

from __future__ import annotations

import time

import numpy as np
from trajectories.start_poses import THESIS_START


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    from trajectories.ik import IkOptions, solve_ik_path
    from trajectories.limits import default_limits
    from trajectories.robot import Robot

    robot = Robot()
    limits = default_limits()
    q_start = np.array(THESIS_START)
    n = 2001 if quick else 10001
    t = np.linspace(0.0, (n - 1) * 1e-3, n)
    wave = np.sin(2 * np.pi * 0.2 * t)[:, None] * np.array([0.3, 0.15, 0.1, 0.12, 0.2, 0.15, 0.3])
    pos, rot = robot.fk_path(q_start + wave)
    best = np.inf
    for _ in range(1 if quick else 3):
        t0 = time.perf_counter()
        res = solve_ik_path(robot, pos, rot, q_start, limits)
        best = min(best, time.perf_counter() - t0)
    bounded = IkOptions(nullspace_gain=None, speed_limits=True)
    rows = []
    for label, q0 in (("start given", q_start), ("start chosen", None)):
        fastest = np.inf
        for _ in range(1 if quick else 3):
            t0 = time.perf_counter()
            res_b = solve_ik_path(robot, pos, rot, q0, limits, bounded, times=t)
            fastest = min(fastest, time.perf_counter() - t0)
        rows += [
            (f"lbr ik mode ({label}) throughput", n / fastest, "poses/s"),
            (f"lbr ik mode ({label}) max position error", res_b.max_position_error, "m"),
            (f"lbr ik mode ({label}) peak speed / limit", res_b.velocity_ratio, "-"),
        ]
    return rows + [
        (f"IK {n} poses (1 kHz path) wall time", best, "s"),
        ("IK throughput", n / best, "poses/s"),
        ("IK max position error", res.max_position_error, "m"),
        ("IK max rotation error", res.max_rotation_error, "rad"),
    ]
