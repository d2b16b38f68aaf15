"""Cartesian poses of FRI 2.7: the wire's quaternion transformation ↔ matrices, and the joints of a commanded pose.

On the wire a pose is (tx, ty, tz [mm], qw, qx, qy, qz) — KUKA's ``setCartesianPose`` — and its redundancy is E1,
the angle of A3 [rad]. In Python every pose is in metres: a 4×4 or 3×4 homogeneous matrix, its 12 row-major values
(KUKA's ``setCartesianPoseAsMatrix`` layout), or 7 values (x, y, z [m], qw, qx, qy, qz). ``PoseSolver`` turns a
commanded TCP pose and E1 into joint positions with the warm-started IK of :mod:`trajectories.ik_online` (A3 held at
E1, the other six joints reach the pose), and says when a pose cannot be executed: not reached by the IK from the
last solution (out of reach, or a joint outside its limits) or a jump (a joint would need more than ``jump_cycles``
command periods at its velocity limit). The client and the simulated controller use the same rules.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
import pinocchio as pin

from trajectories.ik_online import OnlineIk, OnlineIkOptions, quaternion_to_matrix
from trajectories.limits import JointLimits
from trajectories.robot import Robot

__all__ = ["E1_JOINT", "PoseSolution", "PoseSolver", "pose_matrix", "pose_to_wire", "wire_to_pose"]

E1_JOINT = 2  # KUKA's redundancy E1 of the LBR is the angle of A3 (index 2) [rad]
"""Index of the joint whose angle [rad] is KUKA's redundancy value E1 of the LBR (A3)."""
JUMP_CYCLES = 10  # a pose whose joints are further than this many periods at the velocity limit is a jump
REACH_POSITION = 1e-4  # [m] IK residual above which a pose counts as unreachable
REACH_ROTATION = 1e-3  # [rad]


def pose_matrix(pose: Sequence[float] | np.ndarray) -> np.ndarray:
    """A 4×4 homogeneous matrix [m] of a pose given as 4×4, 3×4, 12 row-major values or 7 values (x, y, z [m],
    qw, qx, qy, qz); ValueError for any other shape, non-finite values or a rotation that is not one."""
    a = np.asarray(pose, dtype=float)
    if a.shape == (7,):
        out = np.eye(4)
        out[:3, :3] = quaternion_to_matrix(*a[3:])
        out[:3, 3] = a[:3]
    elif a.shape in ((12,), (3, 4), (4, 4)):
        out = np.eye(4)
        out[:3, :] = a.reshape(-1, 4)[:3]
    else:
        raise ValueError(f"a pose is 4×4, 3×4, 12 or 7 values, got shape {a.shape}")
    if not np.all(np.isfinite(out)):
        raise ValueError("the pose has non-finite values")
    r = out[:3, :3]
    if np.abs(r @ r.T - np.eye(3)).max() > 1e-6 or np.linalg.det(r) < 0:
        raise ValueError("the pose's 3×3 part is not a rotation matrix")
    return out


def pose_to_wire(position: np.ndarray, rotation: np.ndarray) -> list[float]:
    """(tx, ty, tz [mm], qw, qx, qy, qz) of a pose: position [m], rotation 3×3 (qw ≥ 0)."""
    x, y, z, w = pin.Quaternion(np.asarray(rotation, dtype=float)).coeffs().tolist()
    if w < 0:
        x, y, z, w = -x, -y, -z, -w
    return [position[0] * 1e3, position[1] * 1e3, position[2] * 1e3, w, x, y, z]


def wire_to_pose(element: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """(position [m], rotation 3×3) of a wire pose (tx, ty, tz [mm], qw, qx, qy, qz); ValueError if malformed."""
    if len(element) != 7:
        raise ValueError(f"a Cartesian pose has 7 values, got {len(element)}")
    e = np.asarray(element, dtype=float)
    if not np.all(np.isfinite(e)):
        raise ValueError("the Cartesian pose has non-finite values")
    return e[:3] * 1e-3, quaternion_to_matrix(*e[3:])


@dataclass(frozen=True)
class PoseSolution:
    """Joints [rad] for a commanded pose, or why there are none (``problem``)."""

    q: np.ndarray
    position_error: float  # [m]
    rotation_error: float  # [rad]
    problem: str | None = None


class PoseSolver:
    """Commanded TCP pose + E1 → joint positions of ``robot`` inside ``limits`` at command period ``period_s`` [s]
    (warm-started from ``seed``: the last solution or the measured joints). Not thread-safe (pinocchio data)."""

    def __init__(self, robot: Robot, limits: JointLimits, period_s: float, jump_cycles: int = JUMP_CYCLES) -> None:
        self.limits = limits
        self.ik = OnlineIk(
            robot,
            limits,
            OnlineIkOptions(max_iterations=12, position_tolerance=1e-10, rotation_tolerance=1e-10, limit_margin=1e-4),
        )
        self.max_jump = np.asarray(limits.velocity, dtype=float) * period_s * jump_cycles  # [rad]

    def solve(self, seed: Sequence[float], position: np.ndarray, rotation: np.ndarray, e1: float) -> PoseSolution:
        """The joints reaching ``position`` [m], ``rotation`` with A3 at ``e1`` [rad] from ``seed`` [rad]."""
        seed = np.asarray(seed, dtype=float)
        lim = float(self.limits.position[E1_JOINT])
        if not (np.isfinite(e1) and abs(e1) <= lim):
            return PoseSolution(seed, np.inf, np.inf, f"redundancy E1 {e1:.4f} rad outside the A3 limit ±{lim:.4f} rad")
        res = self.ik.solve(seed, position, rotation, lock=(E1_JOINT, e1))
        if res.position_error > REACH_POSITION or res.rotation_error > REACH_ROTATION:
            return PoseSolution(res.q, res.position_error, res.rotation_error,
                                f"Cartesian pose unreachable from the last one with E1 {e1:.4f} rad: "
                                f"{res.position_error * 1e3:.2f} mm, {np.degrees(res.rotation_error):.2f}° off "
                                "(out of reach, or a joint at its limit)")  # fmt: skip
        step = np.abs(res.q - seed)
        j = int(np.argmax(step / self.max_jump))
        if step[j] > self.max_jump[j]:
            return PoseSolution(
                res.q,
                res.position_error,
                res.rotation_error,
                f"Cartesian pose jumps: A{j + 1} would move {step[j]:.4f} rad in one command "
                f"(more than {self.max_jump[j]:.4f} rad, {JUMP_CYCLES} periods at its velocity limit)",
            )
        return PoseSolution(res.q, res.position_error, res.rotation_error)

    def tcp(self, q: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
        """The TCP position [m] and rotation of joints ``q`` [rad]."""
        return self.ik.tcp(np.asarray(q, dtype=float))
