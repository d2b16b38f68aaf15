"""The iiwa 7's robot description: link shapes drawn from the kinematic model, and the URDF that ROS tools read.

No maintained package ships iiwa 7 meshes installable from a package registry, so the arm is drawn with clean
primitives (cylinders and spheres) sized like the real links and placed in the body frames of
:mod:`trajectories.robot`'s model: `lbr view` draws them, and the URDF carries the same frames, joints
(``lbr_A1`` … ``lbr_A7`` as lbr-stack names them, with the limit tables), inertias and shapes, so that RViz and
Foxglove draw what `lbr view` draws and its forward kinematics equal the model's (checked with pinocchio's URDF
parser).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal
from xml.etree import ElementTree as ET

import numpy as np
import pinocchio as pin

from .limits import JointLimits, default_limits
from .robot import Robot
from .trajectory import N_JOINTS

BASE_BODY = 0  # the fixed base (lbr_link_0)
FLANGE_BODY = N_JOINTS + 1  # the flange frame (shapes of the tool)
JOINT_HOUSING = {2: (0.070, 0.16), 4: (0.066, 0.15), 6: (0.058, 0.13)}  # joint: (radius, length) [m]
# Tubes along the upright arm (q = 0): body, z from, z to [m] along the base z, radius [m]
_TUBES = (
    (0, 0.0, 0.1575, 0.090),
    (1, 0.1575, 0.34, 0.068),
    (2, 0.34, 0.54, 0.064),
    (3, 0.54, 0.74, 0.064),
    (4, 0.74, 0.94, 0.058),
    (5, 0.94, 1.14, 0.058),
)


@dataclass(frozen=True)
class Shape:
    """A primitive fixed to one body: a cylinder (centred, axis along its local z) or a sphere [m]."""

    body: int  # 0 base, 1..7 moved by joint A<body>, 8 the flange frame
    kind: Literal["cylinder", "sphere"]
    radius: float  # [m]
    length: float  # [m], cylinders only (0 for spheres)
    placement: tuple[tuple[float, ...], ...]  # 4×4 homogeneous transform in the body frame

    @property
    def matrix(self) -> np.ndarray:
        return np.array(self.placement)


def _tuple(m: np.ndarray) -> tuple[tuple[float, ...], ...]:
    return tuple(tuple(float(v) for v in row) for row in m)


def link_shapes(robot: Robot) -> tuple[Shape, ...]:
    """The arm's primitives: tubes between the joints, housings on A2/A4/A6, the flange and a rod to the TCP."""
    frames0 = robot.link_frames(np.zeros(N_JOINTS))[0]  # body frames at q = 0 (upright arm)
    shapes: list[Shape] = []
    for body, z0, z1, radius in _TUBES:
        upright = np.eye(4)
        upright[2, 3] = 0.5 * (z0 + z1)
        local = upright if body == BASE_BODY else np.linalg.inv(frames0[body - 1]) @ upright
        shapes.append(Shape(body, "cylinder", radius, z1 - z0, _tuple(local)))
    for joint, (radius, length) in JOINT_HOUSING.items():
        shapes.append(Shape(joint, "cylinder", radius, length, _tuple(np.eye(4))))
    d7 = robot.config.flange.d7
    wrist_to_flange = np.eye(4)
    wrist_to_flange[2, 3] = 0.5 * d7
    shapes.append(Shape(N_JOINTS, "cylinder", 0.045, d7, _tuple(wrist_to_flange)))
    tool = np.asarray(robot.config.tool, dtype=float)
    reach = float(np.linalg.norm(tool))
    if reach > 1e-6:  # a thin rod from the flange to the tool point
        z = tool / reach
        x = np.cross(z, [1.0, 0.0, 0.0] if abs(z[0]) < 0.9 else [0.0, 1.0, 0.0])
        x /= np.linalg.norm(x)
        rod = np.eye(4)
        rod[:3, :3] = np.column_stack([x, np.cross(z, x), z])
        rod[:3, 3] = 0.5 * tool
        shapes.append(Shape(FLANGE_BODY, "cylinder", 0.008, reach, _tuple(rod)))
    shapes.append(Shape(FLANGE_BODY, "sphere", 0.012, 0.0, _tuple(np.eye(4))))
    return tuple(shapes)


def link_names(prefix: str = "lbr") -> tuple[str, ...]:
    """TF/URDF frame names: base, the 7 links moved by A1..A7, the flange and the TCP."""
    return (
        f"{prefix}_link_0",
        *(f"{prefix}_link_{i}" for i in range(1, N_JOINTS + 1)),
        f"{prefix}_flange",
        f"{prefix}_tcp",
    )


def joint_names(prefix: str = "lbr") -> tuple[str, ...]:
    """Joint names as lbr-stack's driver and its joint_trajectory_controller expect them."""
    return tuple(f"{prefix}_A{i}" for i in range(1, N_JOINTS + 1))


def _origin(parent: ET.Element, m: np.ndarray) -> None:
    rpy = pin.rpy.matrixToRpy(m[:3, :3])
    ET.SubElement(
        parent,
        "origin",
        xyz=" ".join(f"{v + 0.0:.12g}" for v in m[:3, 3]),
        rpy=" ".join(f"{v + 0.0:.12g}" for v in rpy),
    )


def _visual(link: ET.Element, shape: Shape) -> None:
    visual = ET.SubElement(link, "visual")
    _origin(visual, shape.matrix)
    geometry = ET.SubElement(visual, "geometry")
    if shape.kind == "cylinder":
        ET.SubElement(geometry, "cylinder", radius=f"{shape.radius:.6g}", length=f"{shape.length:.6g}")
    else:
        ET.SubElement(geometry, "sphere", radius=f"{shape.radius:.6g}")
    colour = "lbr_grey" if shape.body in (BASE_BODY, N_JOINTS, FLANGE_BODY) else "lbr_orange"
    ET.SubElement(visual, "material", name=colour)


def urdf(robot: Robot, limits: JointLimits | None = None, prefix: str = "lbr") -> str:
    """The URDF of ``robot`` (flange and tool included): DH body frames, joint limits from ``limits`` (position,
    velocity, torque), lbr_description's inertias as the model holds them, and the primitives of
    :func:`link_shapes` as visuals."""
    lim = default_limits() if limits is None else limits
    model = robot.model
    names = link_names(prefix)
    shapes = link_shapes(robot)
    root = ET.Element("robot", name=f"{prefix}_iiwa7_r800")
    for colour, rgba in (("lbr_orange", "1 0.45 0.05 1"), ("lbr_grey", "0.7 0.7 0.72 1")):
        ET.SubElement(ET.SubElement(root, "material", name=colour), "color", rgba=rgba)
    for body, name in enumerate(names):
        link = ET.SubElement(root, "link", name=name)
        if 1 <= body <= N_JOINTS:
            inertia = model.inertias[body]
            inertial = ET.SubElement(link, "inertial")
            _origin(inertial, pin.SE3(np.eye(3), inertia.lever).homogeneous)
            ET.SubElement(inertial, "mass", value=f"{inertia.mass:.17g}")
            i3 = inertia.inertia
            ET.SubElement(
                inertial,
                "inertia",
                ixx=f"{i3[0, 0]:.17g}",
                ixy=f"{i3[0, 1]:.17g}",
                ixz=f"{i3[0, 2]:.17g}",
                iyy=f"{i3[1, 1]:.17g}",
                iyz=f"{i3[1, 2]:.17g}",
                izz=f"{i3[2, 2]:.17g}",
            )
        for shape in shapes:
            if shape.body == body:
                _visual(link, shape)
    for i, jname in enumerate(joint_names(prefix)):
        joint = ET.SubElement(root, "joint", name=jname, type="revolute")
        ET.SubElement(joint, "parent", link=names[i])
        ET.SubElement(joint, "child", link=names[i + 1])
        _origin(joint, model.jointPlacements[i + 1].homogeneous)
        ET.SubElement(joint, "axis", xyz="0 0 1")
        ET.SubElement(
            joint,
            "limit",
            lower=f"{-lim.position[i]:.17g}",
            upper=f"{lim.position[i]:.17g}",
            velocity=f"{lim.velocity[i]:.17g}",
            effort=f"{lim.torque[i]:.17g}",
        )
    for parent, child, fid in ((names[N_JOINTS], names[-2], robot.flange_id), (names[-2], names[-1], robot.tcp_id)):
        joint = ET.SubElement(root, "joint", name=f"{child}_joint", type="fixed")
        ET.SubElement(joint, "parent", link=parent)
        ET.SubElement(joint, "child", link=child)
        placement = model.frames[fid].placement
        if child == names[-1]:  # the TCP relative to the flange
            placement = model.frames[robot.flange_id].placement.inverse() * placement
        _origin(joint, placement.homogeneous)
    ET.indent(root)
    return '<?xml version="1.0"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


__all__ = ["Shape", "link_shapes", "link_names", "joint_names", "urdf"]
