import numpy as np
import pinocchio as pin

from trajectories.chain import Chain, pose_errors, rotation_log
from trajectories.robot import Flange, Robot, RobotConfig


def test_batched_kinematics_equal_pinocchio_with_a_tool():
    robot = Robot(RobotConfig(flange=Flange.STANDARD, tool=(0.02, -0.01, 0.12)))
    q = np.random.default_rng(0).uniform(-2.5, 2.5, (20, 7))
    pos, rot, jac = Chain.of(robot).kinematics(q)
    for k in range(len(q)):
        M = robot.fk(q[k])
        J = pin.computeFrameJacobian(robot.model, robot.data, q[k], robot.tcp_id, pin.LOCAL_WORLD_ALIGNED)
        assert np.abs(M.translation - pos[k]).max() < 1e-12
        assert np.abs(M.rotation - rot[k]).max() < 1e-12
        assert np.abs(J - jac[k]).max() < 1e-12


def test_rotation_log_equals_pinocchio_log3_small_and_large():
    rng = np.random.default_rng(1)
    unit = rng.normal(size=(50, 3))
    unit /= np.linalg.norm(unit, axis=1)[:, None]
    vecs = unit * np.r_[rng.uniform(0, 1e-6, 25), rng.uniform(0.1, 3.1, 25)][:, None]  # angles below π
    rots = np.array([pin.exp3(v) for v in vecs])
    assert np.abs(rotation_log(rots) - vecs).max() < 1e-12


def test_pose_errors_are_zero_on_target_and_linear_nearby():
    robot = Robot()
    q = np.random.default_rng(2).uniform(-1, 1, (5, 7))
    chain = Chain.of(robot)
    pos, rot, jac = chain.kinematics(q)
    assert np.abs(pose_errors(pos, rot, pos, rot)).max() == 0.0
    dq = np.random.default_rng(3).normal(size=(5, 7)) * 1e-6
    pos2, rot2, _ = chain.kinematics(q + dq)
    err = pose_errors(pos, rot, pos2, rot2)  # target − actual ≈ J dq
    assert np.abs(err - np.einsum("nij,nj->ni", jac, dq)).max() < 1e-10
