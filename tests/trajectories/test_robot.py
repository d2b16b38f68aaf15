import numpy as np
import pinocchio as pin
import pytest

from trajectories.robot import Flange, Robot, RobotConfig, dh_table, dh_transform


def dh_fk(q, flange=Flange.TOUCH_ELECTRIC):
    T = np.eye(4)
    for qi, (d, a, alpha) in zip(q, dh_table(flange)):
        T = T @ dh_transform(qi, d, a, alpha)
    return T


@pytest.mark.parametrize("flange", list(Flange))
def test_fk_matches_dh_table_for_random_configurations(flange, limits):
    rng = np.random.default_rng(1)
    robot = Robot(RobotConfig(flange=flange))
    for _ in range(200):
        q = rng.uniform(-limits.position, limits.position)
        M = robot.fk(q)
        T = dh_fk(q, flange)
        assert np.abs(M.translation - T[:3, 3]).max() <= 1e-9
        assert np.abs(M.rotation - T[:3, :3]).max() <= 1e-9


def test_flange_lengths():
    assert Flange.TOUCH_ELECTRIC.d7 == 0.152
    assert Flange.STANDARD.d7 == 0.126
    assert Flange.TOUCH_PNEUMATIC.d7 == pytest.approx(0.187)
    # Upright arm: the flange sits at 0.34 + 0.4 + 0.4 + d7 above the table.
    for flange in Flange:
        z = Robot(RobotConfig(flange=flange)).fk(np.zeros(7)).translation[2]
        assert z == pytest.approx(1.14 + flange.d7, abs=1e-12)


def test_thesis_start_pose_within_1_5_cm_of_thesis_T_start(robot, q_start):
    T_thesis = np.array([[0, 0, 1, 0.585], [0, 1, 0, 0], [-1, 0, 0, 0.801]])
    M = robot.fk(q_start)
    assert np.linalg.norm(M.translation - T_thesis[:, 3]) < 0.015
    # flange z-axis along base +x within ~1 degree (thesis rounding)
    angle = np.degrees(np.arccos(np.clip(M.rotation[:, 2] @ np.array([1.0, 0, 0]), -1, 1)))
    assert angle < 1.5


def test_tool_offset_is_in_the_flange_frame(q_start):
    plain = Robot().fk(q_start)
    tool = Robot(RobotConfig(tool=(0.0, 0.0, 0.1))).fk(q_start)
    # The flange z-axis points along base +x at the start pose: a 0.1 m tool moves the TCP ~0.1 m along +x.
    assert np.allclose(tool.translation - plain.translation, plain.rotation @ np.array([0, 0, 0.1]), atol=1e-12)
    assert (tool.translation - plain.translation)[0] == pytest.approx(0.1, abs=2e-3)


def test_link_inertias_land_where_the_urdf_puts_them(robot):
    """At q = 0 every link's centre of mass in the base frame equals the lbr_description URDF's."""
    from trajectories.robot import _URDF_INERTIA, _URDF_JOINT_XYZ

    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, np.zeros(7))
    origins = np.cumsum(np.array(_URDF_JOINT_XYZ), axis=0)
    for i, (mass, com, _) in enumerate(_URDF_INERTIA):
        inertia = robot.model.inertias[i + 1]
        assert inertia.mass == pytest.approx(mass)
        com_world = data.oMi[i + 1].act(inertia.lever)
        assert np.allclose(com_world, origins[i] + np.array(com), atol=1e-12)
    total = sum(robot.model.inertias[i].mass for i in range(1, 8)) + 4.855658  # + base link
    assert total == pytest.approx(23.9, abs=0.05)


def test_gravity_torque_matches_potential_energy_gradient(robot, q_start):
    """τ_g = ∂V/∂q with V = g·Σ m_i z_com,i (finite differences on the COM heights)."""

    def potential(q):
        data = robot.model.createData()
        pin.forwardKinematics(robot.model, data, q)
        return sum(
            9.81 * robot.model.inertias[i].mass * data.oMi[i].act(robot.model.inertias[i].lever)[2] for i in range(1, 8)
        )

    tau = robot.inverse_dynamics(q_start, np.zeros(7), np.zeros(7))
    eps = 1e-6
    grad = np.array([(potential(q_start + eps * e) - potential(q_start - eps * e)) / (2 * eps) for e in np.eye(7)])
    # pinocchio's default gravity is 9.81 m/s^2
    assert np.allclose(tau, grad, atol=1e-5)
    assert abs(tau[1]) > 5.0  # A2 carries the stretched-out arm
