"""Joint paths that start and end at rest when the task path does: the self-motion brought to rest with the task,
accelerations kept inside the limits by moving along the self-motion — judged by `lbr check`'s own check and
pinocchio's FK, on paths whose redundancy was still moving at the end or whose accelerations were above the limit."""

import numpy as np
import pytest

from trajectories.check import check_trajectory
from trajectories.errors import IkError
from trajectories.ik import IkOptions, PathSolver, solve_ik_path
from trajectories.ik_paths import build_rest_suite, cartesian_path, drawing_path, verify_joint_path
from trajectories.robot import Robot
from trajectories.trajectory import JointTrajectory

BOUNDED = IkOptions(nullspace_gain=None, speed_limits=True)


def _solve(path, limits, options=BOUNDED):
    robot = Robot(path.config)
    return robot, solve_ik_path(robot, path.position, path.rotation, None, limits, options, times=path.t)


@pytest.mark.heavy
def test_a_yawing_line_ends_at_rest_and_passes_the_check(limits):
    """A suite line at 1 ms (flange turning 90° about the vertical, rest to rest) on which the null-space pull
    toward the start still moved the elbow at the last sample (refused by the check): now the file passes the
    check and the path is exact."""
    path = cartesian_path("line", 0.001, center=(0.4, -0.2, 0.5), size=0.2, plane="yz", timing="smooth",
                          yaw_deg=90, duration=8.0)  # fmt: skip
    robot, res = _solve(path, limits)
    before = _solve(path, limits, IkOptions(nullspace_gain=None, speed_limits=True, rest_at_ends=False))[1]
    report = check_trajectory(JointTrajectory(t=path.t, q=res.q), limits)
    assert res.task_at_rest == (True, True) and res.at_rest == (True, True)
    assert report.ok, [v.describe() for v in report.failing]
    assert verify_joint_path(robot, path, res.q, limits).ok(1e-6, 1e-5, acceleration=True)
    # the same solve without bringing the redundancy to rest: the elbow still moves at the end
    assert not check_trajectory(JointTrajectory(t=path.t, q=before.q), limits).ok
    assert before.at_rest[1] is False


def test_a_path_moving_at_its_ends_is_reported_not_at_rest(limits):
    path = drawing_path("moving", "loops", 0.005, 4.0, (0.5, 0.0, 0.15), "table", 0.36, rest=False)
    _, res = _solve(path, limits)
    assert res.task_at_rest == (False, False) and res.at_rest == (False, False)
    assert {v.note for v in check_trajectory(JointTrajectory(t=path.t, q=res.q), limits).violations
            if v.quantity == "rest"} == {"start", "end"}  # fmt: skip


@pytest.mark.heavy
def test_accelerations_above_the_limit_are_lowered_along_the_self_motion(limits):
    """An FK-built path near the shoulder and wrist singularities (its witness within 0.8 of every limit) on which
    the local solution reached 2.3× the acceleration limit: moved along the self-motion it passes the check."""
    from trajectories.ik_smooth import lower_accelerations

    path = next(p for p in build_rest_suite(limits, quick=False) if p.name == "rest-joint-c0-5ms")
    robot = Robot(path.config)
    raw = IkOptions(nullspace_gain=None, speed_limits=True, rest_at_ends=False)
    q = solve_ik_path(robot, path.position, path.rotation, None, limits, raw, times=path.t).q
    solver = PathSolver(robot, path.position, path.rotation, limits, raw, path.t)
    assert solver.rates(q)[1] > 1.5
    lowered = lower_accelerations(solver, q)
    check = verify_joint_path(robot, path, lowered, limits)
    assert check.ok(1e-6, 1e-5, acceleration=True), check
    assert check_trajectory(JointTrajectory(t=path.t, q=lowered), limits).ok


@pytest.mark.heavy
def test_a4_acceleration_set_by_the_poses_refuses_a_rest_to_rest_path(limits):
    """A rose drawn with an offset pen whose wrist distance changes faster than A4 may accelerate: A4 is set by
    the pose, so no arm angle helps; the refusal names the first sample, judged by the closed form's A4."""
    from trajectories.arm_angle import BRANCHES, ArmGeometry, inverse

    path = next(p for p in build_rest_suite(limits, quick=False) if p.name == "rose-table-offsetpen-5ms")
    with pytest.raises(IkError) as exc:
        _solve(path, limits)
    err = exc.value
    assert (err.reason, err.joint, err.kind) == ("acceleration limit", 3, "path")
    q, _ = inverse(ArmGeometry.of(Robot(path.config)), path.rotation, path.position, 0.4, BRANCHES[0])
    acc = np.abs(np.diff(q[:, 3], 2)) / path.dt**2
    assert acc[err.index - 2] > limits.acceleration[3] and (acc[: err.index - 2] <= limits.acceleration[3]).all()
