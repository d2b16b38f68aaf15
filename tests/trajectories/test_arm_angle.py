import numpy as np
import pytest

from trajectories.arm_angle import BRANCHES, ArmGeometry, arm_angle, branch_of, inverse
from trajectories.robot import Flange, Robot, RobotConfig


@pytest.mark.parametrize("config", [RobotConfig(), RobotConfig(flange=Flange.STANDARD, tool=(0.01, -0.02, 0.1))])
def test_round_trip_through_arm_angle_and_branch(config, limits):
    robot = Robot(config)
    geometry = ArmGeometry.of(robot)
    rng = np.random.default_rng(4)
    q = rng.uniform(-1.0, 1.0, (400, 7)) * limits.position
    pos, rot = robot.fk_path(q)
    back, reach = inverse(geometry, rot, pos, arm_angle(geometry, q), branch_of(q))
    assert reach.all()
    assert np.abs(back - q).max() < 1e-9


def test_every_arm_angle_and_branch_reaches_the_pose(robot, limits):
    geometry = ArmGeometry.of(robot)
    rng = np.random.default_rng(5)
    q = rng.uniform(-1.0, 1.0, (300, 7)) * limits.position
    pos, rot = robot.fk_path(q)
    psi = rng.uniform(-np.pi, np.pi, 300)
    branch = BRANCHES[rng.integers(8, size=300)]
    other, reach = inverse(geometry, rot, pos, psi, branch)
    assert reach.all()
    p2, r2 = robot.fk_path(other)
    assert np.abs(p2 - pos).max() < 1e-12 and np.abs(r2 - rot).max() < 1e-12
    assert (branch_of(other) == branch).all()
    # the arm angle asked for is the one the configuration has (away from a straight elbow, where it is undefined)
    bent = np.abs(np.sin(other[:, 3])) > 0.05
    diff = np.angle(np.exp(1j * (arm_angle(geometry, other) - psi)))
    assert np.abs(diff[bent]).max() < 1e-9


def test_a_pose_beyond_the_arm_is_flagged(robot):
    geometry = ArmGeometry.of(robot)
    far = np.array([1.2, 0.0, 0.4])  # [m] farther than shoulder + both segments + flange allow
    _, reach = inverse(geometry, np.diag([1.0, -1.0, -1.0]), far, np.zeros(3), BRANCHES[:3])
    assert not reach.any()
