"""The robot description against the model: pinocchio's own URDF parser reads the URDF back to the same forward
kinematics, mass matrix and limits; the vectorised body frames equal pinocchio's forward kinematics."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest

from trajectories.description import joint_names, link_names, link_shapes, urdf
from trajectories.limits import default_limits
from trajectories.robot import Flange, Robot, RobotConfig

CONFIGS = [
    RobotConfig(),
    RobotConfig(Flange.STANDARD, (0.0, 0.0, 0.1)),
    RobotConfig(Flange.TOUCH_PNEUMATIC, (0.03, -0.02, 0.07)),
]


@pytest.mark.parametrize("config", CONFIGS, ids=["touch-electric", "standard+tool", "pneumatic+offset-tool"])
def test_urdf_read_by_pinocchio_has_the_models_kinematics_dynamics_and_limits(config):
    robot = Robot(config)
    lim = default_limits()
    model = pin.buildModelFromXML(urdf(robot, lim, prefix="lbr"))
    data = model.createData()
    assert [model.names[i] for i in range(1, 8)] == list(joint_names("lbr"))
    np.testing.assert_allclose(model.upperPositionLimit, lim.position, rtol=1e-9)
    np.testing.assert_allclose(model.velocityLimit, lim.velocity, rtol=1e-9)
    np.testing.assert_allclose(model.effortLimit, lim.torque, rtol=1e-9)
    tcp = model.getFrameId("lbr_tcp")
    flange = model.getFrameId("lbr_flange")
    for q in np.random.default_rng(3).uniform(-2.0, 2.0, (20, 7)):
        pin.framesForwardKinematics(model, data, q)
        pin.framesForwardKinematics(robot.model, robot.data, q)
        np.testing.assert_allclose(data.oMf[tcp].homogeneous, robot.data.oMf[robot.tcp_id].homogeneous, atol=1e-10)
        np.testing.assert_allclose(
            data.oMf[flange].homogeneous, robot.data.oMf[robot.flange_id].homogeneous, atol=1e-10
        )
        np.testing.assert_allclose(pin.crba(model, data, q), pin.crba(robot.model, robot.data, q), atol=1e-8)


def test_every_link_has_its_shapes_and_the_shapes_follow_the_upright_arm():
    robot = Robot()
    root = ET.fromstring(urdf(robot))
    links = {link.get("name"): link for link in root.iter("link")}
    assert list(links) == list(link_names("lbr"))
    assert all(len(links[name].findall("visual")) >= 1 for name in link_names("lbr")[:-1])
    frames = robot.link_frames(np.zeros(7))[0]
    tubes = [s for s in link_shapes(robot) if s.kind == "cylinder" and 1 <= s.body <= 5 and s.length > 0.17]
    for shape in tubes:  # upright (q = 0): every tube stands on the base's z axis, vertical
        world = frames[shape.body - 1] @ shape.matrix
        np.testing.assert_allclose(world[:2, 3], 0.0, atol=1e-12)
        assert abs(world[2, 2]) == pytest.approx(1.0)


def test_link_frames_equal_pinocchio_forward_kinematics():
    robot = Robot(RobotConfig(tool=(0.01, 0.02, 0.1)))
    q = np.random.default_rng(0).uniform(-2.5, 2.5, (200, 7))
    frames = robot.link_frames(q)
    for k in range(0, 200, 13):
        pin.framesForwardKinematics(robot.model, robot.data, q[k])
        for i in range(7):
            np.testing.assert_allclose(frames[k, i], robot.data.oMi[i + 1].homogeneous, atol=1e-14)
        np.testing.assert_allclose(frames[k, 7], robot.data.oMf[robot.flange_id].homogeneous, atol=1e-14)
        np.testing.assert_allclose(frames[k, 8], robot.data.oMf[robot.tcp_id].homogeneous, atol=1e-14)
