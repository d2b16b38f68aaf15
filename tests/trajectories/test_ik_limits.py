"""The path IK inside the joint limits: constrained steps, speed bounds, start choice and honest errors."""

from dataclasses import replace

import numpy as np
import pytest

from trajectories.errors import IkError
from trajectories.ik import IkOptions, solve_ik_path
from trajectories.ik_paths import build_suite, issue_circle, random_joint_path, verify_joint_path
from tests.helpers.cli import Q_START

BOUNDED = IkOptions(nullspace_gain=None, speed_limits=True)
THESIS = Q_START


def _solve(robot, limits, path, q0=None, options=BOUNDED):
    return solve_ik_path(robot, path.position, path.rotation, q0, limits, options, times=path.t)


@pytest.mark.heavy
def test_joint_held_at_its_limit_is_named_as_a_fact_of_the_path_from_q0(robot, limits):
    # the flange turns 170° about its own axis (A7 alone), but this robot's A7 stops at ±120°: the path from q0
    # runs into A7's limit, although other arm angles reach the pose inside the limits (not a fact of the pose)
    from trajectories.arm_angle import BRANCHES, ArmGeometry, inverse

    dt = 0.005
    t = np.arange(0.0, 2.0 + dt / 2, dt)
    q = np.tile([0.0, 0.6, 0.0, -1.2, 0.0, 0.9, 0.0], (len(t), 1))
    q[:, 6] = np.radians(170) * np.sin(np.pi * t / 4) ** 2
    pos, rot = robot.fk_path(q)
    narrow = replace(limits, position=np.r_[limits.position[:6], np.radians(120.0)])
    with pytest.raises(IkError) as exc:
        solve_ik_path(robot, pos, rot, q[0], narrow, BOUNDED, times=t)
    err = exc.value
    assert err.reason == "position limit" and err.joint == 6 and abs(err.needed) > np.radians(120)
    assert err.kind == "start" and "ran into A7's position limit" in str(err) and t[err.index] > 1.0
    assert "the pose itself is reachable" in str(err) and "without solve_ik_path.q0" in str(err)
    # a judge of its own: the closed form on a 0.05° grid of arm angles × 8 branches finds the pose inside the limits
    psi = np.radians(np.arange(-180.0, 180.0, 0.05))
    k = err.index
    c, _ = inverse(ArmGeometry.of(robot), rot[k], pos[k], psi[None, :], BRANCHES[:, None, :])
    assert (np.abs(c) <= narrow.position - 1e-4).all(axis=-1).any()
    # within the real limits it is followed to the end
    res = solve_ik_path(robot, pos, rot, q[0], limits, BOUNDED, times=t)
    assert res.max_position_error < 1e-6 and res.velocity_ratio <= 1.0


def test_issue_circle_solved_from_a_start_chosen_for_the_whole_path(robot, limits):
    path = issue_circle(0.001)  # at 5 ms: tests/lbrcli/commands/test_kinematics_ik.py
    res = _solve(robot, limits, path)
    check = verify_joint_path(robot, path, res.q, limits)
    assert check.position_error <= 1e-6 and check.rotation_error <= 1e-5
    assert check.velocity_ratio <= 1.0 and check.position_ratio < 1.0
    assert res.start.startswith("auto") and res.candidates
    assert abs(res.velocity_ratio - check.velocity_ratio) < 1e-6


@pytest.mark.heavy
def test_suite_subset_solved_inside_the_speed_limits(robot, limits):
    # FK-built paths at 5 ms: random, through the wrist singularity, brushing A2/A7 limits; the solver picks the start
    suite = {p.name: p for p in build_suite(robot, limits) if p.dt == 0.005}
    for name in ("joint-c2-v0.9-5ms", "singular-wrist-0-5ms", "limit-A7-5ms"):
        path = suite[name]
        res = _solve(robot, limits, path)
        check = verify_joint_path(robot, path, res.q, limits)
        assert check.ok(), (name, check)


def test_path_faster_than_the_limits_exits_naming_joint_and_speed(robot, limits):
    rng = np.random.default_rng(5)
    dt = 0.005
    q = random_joint_path(rng, limits, dt, 2.0, THESIS + 0.3, np.full(7, 0.3), 0.5)
    t = np.arange(len(q)) * dt
    q[:, 0] = 0.4 * np.sin(2 * np.pi * 1.5 * t)  # A1 peaks at 3.8 rad/s, limit 1.71 rad/s
    pos, rot = robot.fk_path(q)
    with pytest.raises(IkError) as exc:
        solve_ik_path(robot, pos, rot, q[0], limits, BOUNDED, times=t)
    err = exc.value
    assert err.reason == "velocity limit" and err.needed > limits.velocity[err.joint]
    assert f"A{err.joint + 1}" in str(err) and "rad/s" in str(err)
    # without speed bounds the same path is followed exactly (and breaks the limit)
    res = solve_ik_path(robot, pos, rot, q[0], limits, IkOptions(nullspace_gain=None), times=t)
    assert res.max_position_error < 1e-6 and res.velocity_ratio > 1.5


def test_out_of_reach_says_by_how_much(robot, limits):
    M = robot.fk(THESIS)
    pos = np.tile(M.translation, (30, 1))
    pos[20:, 0] += 1.0  # 1 m further out from pose 20 on: beyond reach
    rot = np.tile(M.rotation, (30, 1, 1))
    with pytest.raises(IkError) as exc:
        solve_ik_path(robot, pos, rot, THESIS, limits, BOUNDED, times=np.arange(30) * 0.1)
    assert exc.value.reason == "out of reach" and exc.value.index == 20
    assert "out of reach by" in str(exc.value) and " mm" in str(exc.value)


@pytest.mark.heavy
def test_null_space_pull_is_per_second_not_per_sample(robot, limits):
    # The same continuous path sampled at 1 and 5 ms, solved from a start whose elbow differs from the path's:
    # the redundancy relaxes toward q0 at the same pace, so both joint paths agree at common times.
    def paths(options):
        out = []
        for dt in (0.001, 0.005):
            q = random_joint_path(np.random.default_rng(7), limits, dt, 2.0, THESIS + 0.2, np.full(7, 0.5), 0.5)
            t = np.arange(len(q)) * dt
            pos, rot = robot.fk_path(q)
            q0 = q[0] + np.array([0.0, 0.0, 0.6, 0.0, 0.0, 0.0, 0.0])  # pull target off the path's elbow
            out.append(solve_ik_path(robot, pos, rot, q0, limits, options, times=t).q)
        return np.abs(out[0][::5] - out[1]).max()

    assert paths(IkOptions(nullspace_gain=None, nullspace_rate=2.0)) < 1e-3
    assert paths(IkOptions(nullspace_gain=0.002)) > 1e-2  # a per-sample gain pulls 5× harder at 1 ms


def test_newton_steps_pinned_by_the_box_stop_early(robot, limits):
    """A target the joints cannot reach inside their box: the Newton loop ends once the box-bound steps stop
    reducing the error, well before its budget, and reports the remaining error (above the tolerance)."""
    from trajectories.ik import IkOptions, PathSolver

    q = np.array([0.0, 0.5, 0.0, -1.2, 0.0, 0.9, 0.0])
    pos, rot = robot.fk_path(q[None])
    far = pos + np.array([0.05, 0.0, 0.0])  # 5 cm away, with every joint allowed only ±0.01 rad
    solver = PathSolver(robot, far, rot, limits, IkOptions(nullspace_gain=None))
    out, ep, er, steps = solver.track(0, q, q - 0.01, q + 0.01, q, 0.0, 200)
    assert steps < 20
    assert ep > 0.01 and np.all(np.abs(out - q) <= 0.01 + 1e-12)
    # a reachable target inside a wide box still converges
    near = pos + np.array([0.002, 0.0, 0.0])
    solver = PathSolver(robot, near, rot, limits, IkOptions(nullspace_gain=None))
    out, ep, er, steps = solver.track(0, q, q - 0.5, q + 0.5, q, 0.0, 200)
    assert ep <= 1e-9 and er <= 1e-8
