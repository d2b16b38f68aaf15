"""The damper's correction tables: the Jacobian maps move the TCP as asked, the bounds leave the limits intact."""

from __future__ import annotations

import numpy as np

from planners.feedback.correction import correction_plan
from trajectories.limits import default_limits
from trajectories.robot import Robot

DT = 0.005


def _path(n: int = 400) -> np.ndarray:
    q0 = np.array([0.0, 0.6, 0.0, -1.4, 0.0, 1.14, 0.0])
    s = np.linspace(0, 1, n)
    s = 10 * s**3 - 15 * s**4 + 6 * s**5
    dq = np.array([0.6, 0.2, 0.0, 0.3, 0.0, -0.1, 0.0])
    return q0 + s[:, None] * dq


def test_maps_move_the_tcp_horizontally_only():
    robot, lim = Robot(), default_limits()
    q = _path()
    plan = correction_plan(robot, q, lim, DT)
    for k in (0, 150, 399):
        for d in (np.array([0.004, 0.0]), np.array([0.0, -0.003]), np.array([0.002, 0.002])):
            a, b = robot.fk(q[k]), robot.fk(q[k] + plan.maps[k] @ d)
            moved = b.translation - a.translation
            assert np.allclose(moved[:2], d, atol=6e-5)
            assert abs(moved[2]) < 6e-5
            assert np.allclose(a.rotation, b.rotation, atol=1e-4)


def test_bounds_keep_the_joints_within_their_limits():
    robot, lim = Robot(), default_limits()
    q = _path(300)  # a fast move: little headroom mid-way
    plan = correction_plan(robot, q, lim, DT, share=0.95)
    spread = np.abs(plan.maps).sum(axis=2)
    vel = np.zeros_like(q)
    vel[:-1] = np.abs(np.diff(q, axis=0)) / DT
    acc = np.zeros_like(q)
    acc[1:-1] = np.abs(np.diff(q, 2, axis=0)) / DT**2
    assert np.all(vel + spread * plan.bounds[:, [0]] <= 0.95 * lim.velocity + 1e-9)
    assert np.all(acc + spread * plan.bounds[:, [2]] <= 0.95 * lim.acceleration + 1e-9)
    assert np.all(plan.bounds[:, 1] == -plan.bounds[:, 2])
    assert plan.bounds[:, 2].min() < plan.bounds[:, 2].max()  # the headroom varies along the move
    assert 0 < plan.travel <= 0.08
    # the planned TCP acceleration is the second difference of the TCP path
    pos, _ = robot.fk_path(q)
    assert np.allclose(plan.planned_accel[1:-1], np.diff(pos[:, :2], 2, axis=0) / DT**2)
