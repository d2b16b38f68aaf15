"""Online IK of single poses: converges from a nearby seed, gives continuous joints along a streamed path, stays
inside the position limits, and says when a pose is out of reach instead of raising."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from trajectories.ik_online import OnlineIk, OnlineIkOptions, fixed_angles_to_matrix, quaternion_to_matrix


@pytest.fixture(scope="module")
def ik(robot, limits):
    return OnlineIk(robot, limits)


def test_fixed_angles_and_quaternions_are_the_documented_rotations():
    rng = np.random.default_rng(0)
    for a, b, c in rng.uniform(-3, 3, (20, 3)):
        assert np.allclose(fixed_angles_to_matrix(a, b, c), Rotation.from_euler("ZYX", [a, b, c]).as_matrix())
        # R = Rz(α)·Ry(β)·Rx(γ): fixed axes X, Y, Z applied in that order
        assert np.allclose(fixed_angles_to_matrix(a, b, c), Rotation.from_euler("xyz", [c, b, a]).as_matrix())
    for quat in rng.normal(size=(20, 4)):
        assert np.allclose(quaternion_to_matrix(*quat), Rotation.from_quat(quat, scalar_first=True).as_matrix())
    with pytest.raises(ValueError, match="zero"):
        quaternion_to_matrix(0, 0, 0, 0)


def test_poses_near_the_seed_are_solved_to_the_tolerance(ik, robot, limits, q_start):
    rng = np.random.default_rng(1)
    for _ in range(200):
        q_true = np.clip(q_start + rng.normal(0, 0.3, 7), -limits.position + 0.05, limits.position - 0.05)
        m = robot.fk(q_true)
        res = ik.solve(q_true + rng.normal(0, 0.02, 7), m.translation, m.rotation)
        assert res.converged and res.position_error <= 1e-6 and res.rotation_error <= 1e-5
        got = robot.fk(res.q)
        assert np.linalg.norm(got.translation - m.translation) <= 1e-6
        assert res.iterations <= 4


@pytest.mark.heavy
@pytest.mark.parametrize("posture, drift", [(True, 0.01), (False, 0.5)])
def test_a_streamed_tcp_circle_gives_continuous_joints(ik, robot, posture, drift):
    """A 10 cm circle at 1 kHz, each pose seeded with the previous solution: joints change smoothly (no flips of
    the redundancy) and every pose is reached; the posture pull brings the elbow back after the full circle."""
    q_start = np.array([0, 0.5, 0, -1.2, 0, 0.8, 0.0])  # away from the wrist singularity (A6 ≈ 0)
    m0 = robot.fk(q_start)
    q = q_start.copy()
    steps = []
    for k in range(2000):
        phi = 2 * np.pi * k / 2000
        p = m0.translation + 0.1 * np.array([np.cos(phi) - 1, np.sin(phi), 0])
        res = ik.solve(q, p, m0.rotation, posture=q_start if posture else None)
        assert res.converged
        steps.append(np.abs(res.q - q).max())
        q = res.q
    assert max(steps) < 2e-3  # [rad] per 1 ms sample: ≈ 0.3 m/s of TCP speed, continuous
    assert np.abs(q - q_start).max() < drift  # back (near) where it started after the full circle
    if not posture:
        assert np.abs(q - q_start).max() > 0.05  # without the pull the redundancy drifts: the pull is what helps


def test_an_unreachable_pose_gives_the_closest_configuration_within_the_limits(ik, robot, limits, q_start):
    target = np.array([1.5, 0.0, 0.4])  # 1.5 m away: the arm reaches ≈ 0.8 m
    q = q_start.copy()
    for _ in range(30):  # the follower refines over several cycles
        res = ik.solve(q, target, np.eye(3))
        q = res.q
    assert not res.converged and 0.5 < res.position_error < 1.0
    assert np.all(np.abs(res.q) <= limits.position - ik.options.limit_margin + 1e-12)
    reach = np.linalg.norm(robot.fk(res.q).translation - np.array([0, 0, 0.34]))
    assert reach > 0.7  # stretched toward it


def test_a_pose_beyond_a_joint_limit_keeps_the_joint_inside(robot, limits, q_start):
    ik = OnlineIk(robot, limits, OnlineIkOptions(max_iterations=50))
    q_far = q_start.copy()
    q_far[6] = limits.position[6] + 0.3  # A7 beyond its limit: the flange's rotation needs it
    m = robot.fk(q_far)
    res = ik.solve(q_start, m.translation, m.rotation)
    assert np.all(np.abs(res.q) <= limits.position - 0.01 + 1e-12)
    if not res.converged:  # the other branch (A7 − 2π) may be out too: then the closest is kept, not an exception
        assert res.rotation_error > 1e-5
