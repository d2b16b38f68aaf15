"""The KUKA LBR iiwa 7 R800 as a pinocchio model built from the thesis's DH table.

Kinematics follow the standard DH parameters of thesis Table 2.1 (T_i = Rz(q)·Tz(d)·Tx(a)·Rx(α)), with the
last offset d7 set by the media flange. Link inertias are those of lbr_description's iiwa7 (expressed in the
URDF link frames, all rpy = 0) moved into the DH body frames, so dynamics (inverse dynamics, gravity) work.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np
import pinocchio as pin

from .errors import SettingError
from .trajectory import N_JOINTS

# (d [m], a [m], alpha [rad]) for links 1..6; d7 comes from the flange.
DH_TABLE: tuple[tuple[float, float, float], ...] = (
    (0.340, 0.0, -math.pi / 2),
    (0.0, 0.0, math.pi / 2),
    (0.400, 0.0, math.pi / 2),
    (0.0, 0.0, -math.pi / 2),
    (0.400, 0.0, -math.pi / 2),
    (0.0, 0.0, math.pi / 2),
)


class Flange(str, Enum):
    """Media flange options and their d7 [m]."""

    TOUCH_ELECTRIC = "touch-electric"
    STANDARD = "standard"
    TOUCH_PNEUMATIC = "touch-pneumatic"

    @property
    def d7(self) -> float:
        return {"touch-electric": 0.152, "standard": 0.126, "touch-pneumatic": 0.187}[self.value]


# lbr_description iiwa7: joint origins (xyz [m], parent URDF link frame, all rpy = 0) and link inertias.
_URDF_JOINT_XYZ = (
    (0.0, 0.0, 0.1475),
    (0.0, -0.0105, 0.1925),
    (0.0, 0.0105, 0.2075),
    (0.0, 0.0105, 0.1925),
    (0.0, -0.0105, 0.2075),
    (0.0, -0.0707, 0.1925),
    (0.0, 0.0707, 0.091),
)
# mass [kg], COM [m], (ixx, iyy, izz, ixy, ixz, iyz) [kg m^2] about the COM, links 1..7
_URDF_INERTIA = (
    (3.394011, (0.0, -0.034819, 0.123299), (0.021383, 0.020403, 0.007563, 0.0, 0.0, 0.003797)),
    (4.031991, (0.0, 0.039793, 0.086944), (0.031697, 0.030080, 0.009666, 0.0, 0.0, 0.005889)),
    (3.394011, (0.0, 0.034819, 0.123299), (0.021383, 0.020403, 0.007563, 0.0, 0.0, -0.003797)),
    (4.031989, (0.0, -0.039793, 0.086944), (0.031695, 0.030079, 0.009665, 0.0, 0.0, -0.005889)),
    (1.529239, (0.0, -0.029824, 0.076267), (0.008485, 0.007136, 0.003848, 0.0, 0.0, 0.002806)),
    (2.403626, (0.0, 0.071020, 0.004950), (0.007067, 0.006804, 0.004629, 0.0, 0.0, 0.000311)),
    (0.259474, (3e-6, -2e-6, 0.013782), (0.000171, 0.000171, 0.000299, 0.0, 0.0, 0.0)),
)

TCP_FRAME = "tcp"
FLANGE_FRAME = "flange"


def dh_transform(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    """Standard DH homogeneous transform Rz(θ)·Tz(d)·Tx(a)·Rx(α) (4×4)."""
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array(
        [
            [ct, -st * ca, st * sa, a * ct],
            [st, ct * ca, -ct * sa, a * st],
            [0.0, sa, ca, d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def dh_table(flange: Flange = Flange.TOUCH_ELECTRIC) -> tuple[tuple[float, float, float], ...]:
    """All seven (d, a, alpha) rows for a flange."""
    return DH_TABLE + ((flange.d7, 0.0, 0.0),)


def _build_model(flange: Flange, tool: np.ndarray) -> pin.Model:
    model = pin.Model()
    model.name = "iiwa7"
    rows = dh_table(flange)
    parent = 0
    placement = pin.SE3.Identity()
    for i in range(N_JOINTS):
        jid = model.addJoint(parent, pin.JointModelRZ(), placement, f"A{i + 1}")
        d, a, alpha = rows[i]
        placement = pin.SE3(dh_transform(0.0, d, a, alpha))
        parent = jid
    # Inertias: URDF link frame i sits at the URDF joint origin with base orientation at q = 0; find its pose
    # in the DH body frame i at q = 0 (a constant transform, both being fixed to the same body).
    data = model.createData()
    pin.forwardKinematics(model, data, np.zeros(N_JOINTS))
    urdf_pos = np.cumsum(np.array(_URDF_JOINT_XYZ), axis=0)
    for i, (mass, com, (ixx, iyy, izz, ixy, ixz, iyz)) in enumerate(_URDF_INERTIA):
        inertia_urdf = pin.Inertia(mass, np.array(com), np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]))
        urdf_frame = pin.SE3(np.eye(3), urdf_pos[i])
        body_from_urdf = data.oMi[i + 1].inverse() * urdf_frame
        model.appendBodyToJoint(i + 1, body_from_urdf.act(inertia_urdf), pin.SE3.Identity())
    flange_placement = pin.SE3(dh_transform(0.0, *rows[N_JOINTS - 1]))
    model.addFrame(pin.Frame(FLANGE_FRAME, N_JOINTS, 0, flange_placement, pin.FrameType.OP_FRAME))
    tcp = flange_placement * pin.SE3(np.eye(3), np.asarray(tool, dtype=float))
    model.addFrame(pin.Frame(TCP_FRAME, N_JOINTS, 0, tcp, pin.FrameType.OP_FRAME))
    return model


@dataclass(frozen=True)
class RobotConfig:
    """Which iiwa 7: media flange and a tool offset [m] in the flange frame. Picklable."""

    flange: Flange = Flange.TOUCH_ELECTRIC
    tool: tuple[float, float, float] = (0.0, 0.0, 0.0)  # [m], in the flange frame


class Robot:
    """Pinocchio model and data of the iiwa 7 with a TCP frame (flange + tool).

    Not thread-safe (it owns one pinocchio Data); create one per thread or process.
    """

    def __init__(self, config: RobotConfig = RobotConfig()) -> None:
        self.config = config
        self.model = _build_model(config.flange, np.array(config.tool))
        self.data = self.model.createData()
        self.tcp_id = self.model.getFrameId(TCP_FRAME)
        self.flange_id = self.model.getFrameId(FLANGE_FRAME)

    def fk(self, q: np.ndarray) -> pin.SE3:
        """TCP pose in the base frame for joint positions q [rad]."""
        pin.framesForwardKinematics(self.model, self.data, np.asarray(q, dtype=float))
        return self.data.oMf[self.tcp_id].copy()

    def fk_path(self, q: np.ndarray, frame: str = TCP_FRAME) -> tuple[np.ndarray, np.ndarray]:
        """Positions (n, 3) [m] and rotation matrices (n, 3, 3) of a frame (TCP by default, or ``FLANGE_FRAME``)
        along a path q (n, 7) [rad]."""
        q = np.asarray(q, dtype=float)
        pos = np.empty((len(q), 3))
        rot = np.empty((len(q), 3, 3))
        model, data = self.model, self.data
        fid = self.tcp_id if frame == TCP_FRAME else self.model.getFrameId(frame)
        for k in range(len(q)):
            pin.framesForwardKinematics(model, data, q[k])
            m = data.oMf[fid]
            pos[k] = m.translation
            rot[k] = m.rotation
        return pos, rot

    def link_frames(self, q: np.ndarray) -> np.ndarray:
        """World poses (n, 9, 4, 4) of the joint frames A1..A7, the flange and the TCP along a path q (n, 7) [rad].

        The model's own placements composed for all samples at once (every joint is a revolute joint about its
        local z): the same poses as ``pin.forwardKinematics`` sample by sample, in one vectorised pass.
        """
        q = np.atleast_2d(np.asarray(q, dtype=float))
        n = len(q)
        model = self.model
        out = np.zeros((n, N_JOINTS + 2, 4, 4))
        out[:, :, 3, 3] = 1.0
        rot = np.broadcast_to(np.eye(3), (n, 3, 3))
        pos = np.zeros((n, 3))

        def place(placement: pin.SE3) -> tuple[np.ndarray, np.ndarray]:  # (rot, pos) · placement
            r, t = placement.rotation, placement.translation  # elementwise: small-matrix GEMMs are slow here
            rr = rot[:, :, 0, None] * r[0] + rot[:, :, 1, None] * r[1] + rot[:, :, 2, None] * r[2]
            return rr, pos + rot[:, :, 0] * t[0] + rot[:, :, 1] * t[1] + rot[:, :, 2] * t[2]

        for i in range(N_JOINTS):
            a, pos = place(model.jointPlacements[i + 1])
            c, s = np.cos(q[:, i])[:, None], np.sin(q[:, i])[:, None]
            rot = np.stack([a[:, :, 0] * c + a[:, :, 1] * s, a[:, :, 1] * c - a[:, :, 0] * s, a[:, :, 2]], axis=2)
            out[:, i, :3, :3], out[:, i, :3, 3] = rot, pos
        for k, fid in ((N_JOINTS, self.flange_id), (N_JOINTS + 1, self.tcp_id)):
            out[:, k, :3, :3], out[:, k, :3, 3] = place(model.frames[fid].placement)
        return out

    def inverse_dynamics(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """Joint torques [Nm] for q [rad], v [rad/s], a [rad/s^2] (RNEA, gravity along −z of the base)."""
        return pin.rnea(self.model, self.data, q, v, a).copy()


MAX_TOOL_OFFSET = 2.0  # [m] a tool (string attachment) this far from the flange is a typo


def parse_tool(text: str | tuple | None) -> tuple[float, float, float]:
    """Parse a tool offset ``x,y,z`` [m] (a tuple of three numbers is taken as it is); each within ±2 m
    (SettingError ``RobotConfig.tool``)."""
    if text is None or (isinstance(text, str) and text.strip() == ""):
        return (0.0, 0.0, 0.0)
    parts = text.split(",") if isinstance(text, str) else list(text)
    try:
        vals = tuple(float(p) for p in parts)
    except (TypeError, ValueError):
        raise SettingError("RobotConfig", "tool", f"expected x,y,z in metres, got {text!r}") from None
    if len(vals) != 3 or not all(math.isfinite(v) and abs(v) <= MAX_TOOL_OFFSET for v in vals):
        raise SettingError(
            "RobotConfig", "tool", f"expected three numbers x,y,z within ±{MAX_TOOL_OFFSET:g} m, got {text!r}"
        )
    return vals  # type: ignore[return-value]


def parse_flange(text: str | Flange) -> Flange:
    try:
        return Flange(text)
    except ValueError:
        names = ", ".join(f.value for f in Flange)
        raise SettingError("RobotConfig", "flange", f"unknown flange {text!r} (one of {names})") from None
