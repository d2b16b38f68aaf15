"""IK throughput: a 10 s path at 1 kHz (10,001 poses) with changing orientation, one core."""

from __future__ import annotations

import time

import numpy as np


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    from trajectories.ik import solve_ik_path
    from trajectories.limits import default_limits
    from trajectories.robot import Robot

    robot = Robot()
    limits = default_limits()
    q_start = np.array([0, 0.071, 0, -1.3523, 0, 0.1301, 0])
    n = 2001 if quick else 10001
    t = np.linspace(0.0, (n - 1) * 1e-3, n)
    wave = np.sin(2 * np.pi * 0.2 * t)[:, None] * np.array([0.3, 0.15, 0.1, 0.12, 0.2, 0.15, 0.3])
    pos, rot = robot.fk_path(q_start + wave)
    best = np.inf
    for _ in range(1 if quick else 3):
        t0 = time.perf_counter()
        res = solve_ik_path(robot, pos, rot, q_start, limits)
        best = min(best, time.perf_counter() - t0)
    return [
        (f"IK {n} poses (1 kHz path) wall time", best, "s"),
        ("IK throughput", n / best, "poses/s"),
        ("IK max position error", res.max_position_error, "m"),
        ("IK max rotation error", res.max_rotation_error, "rad"),
    ]
