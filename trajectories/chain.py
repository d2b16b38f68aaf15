"""Batched kinematics of the iiwa's revolute-z chain in numpy: TCP poses, Jacobians and pose errors of many
configurations at once.

The joint placements and the TCP frame are read from the pinocchio model of a :class:`Robot`, so the batched
results equal pinocchio's (checked in the tests); this is the fast path used to refine a whole joint path in a
few vectorised Newton iterations.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .robot import Robot


@dataclass(frozen=True)
class Chain:
    """Joint placements (parent joint frame → joint frame at q = 0) and the TCP frame of a revolute-z chain."""

    rotations: np.ndarray  # (7, 3, 3)
    translations: np.ndarray  # (7, 3) [m]
    tcp_rotation: np.ndarray  # (3, 3), TCP in the last joint frame
    tcp_translation: np.ndarray  # (3,) [m]

    @classmethod
    def of(cls, robot: Robot) -> "Chain":
        model = robot.model
        placements = [model.jointPlacements[i] for i in range(1, model.njoints)]
        tcp = model.frames[robot.tcp_id].placement
        return cls(
            rotations=np.array([p.rotation for p in placements]),
            translations=np.array([p.translation for p in placements]),
            tcp_rotation=np.array(tcp.rotation),
            tcp_translation=np.array(tcp.translation),
        )

    def kinematics(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """TCP positions (n, 3) [m], rotations (n, 3, 3) and world-aligned Jacobians (n, 6, 7) at q (n, 7) [rad].

        Jacobian rows: linear velocity [m/s] then angular velocity [rad/s] of the TCP, both in the base frame.
        """
        n = len(q)
        rot = np.broadcast_to(np.eye(3), (n, 3, 3))
        pos = np.zeros((n, 3))
        axes = np.empty((n, 7, 3))
        origins = np.empty((n, 7, 3))
        c, s = np.cos(q), np.sin(q)
        for i in range(7):
            pos = pos + rot @ self.translations[i]
            rot = rot @ self.rotations[i]
            axes[:, i] = rot[:, :, 2]
            origins[:, i] = pos
            # rot · Rz(q_i): columns x' = c·x + s·y, y' = −s·x + c·y
            x, y = rot[:, :, 0], rot[:, :, 1]
            ci, si = c[:, i, None], s[:, i, None]
            rot = np.stack([ci * x + si * y, ci * y - si * x, rot[:, :, 2]], axis=2)
        tcp_pos = pos + rot @ self.tcp_translation
        tcp_rot = rot @ self.tcp_rotation
        jac = np.empty((n, 6, 7))
        jac[:, :3] = np.cross(axes, tcp_pos[:, None, :] - origins).transpose(0, 2, 1)
        jac[:, 3:] = axes.transpose(0, 2, 1)
        return tcp_pos, tcp_rot, jac


def rotation_log(rot: np.ndarray) -> np.ndarray:
    """Rotation vectors (n, 3) [rad] of rotation matrices (n, 3, 3) with angles below π − 1e-3."""
    cos = np.clip((np.trace(rot, axis1=1, axis2=2) - 1.0) * 0.5, -1.0, 1.0)
    angle = np.arccos(cos)
    skew = np.stack([rot[:, 2, 1] - rot[:, 1, 2], rot[:, 0, 2] - rot[:, 2, 0], rot[:, 1, 0] - rot[:, 0, 1]], axis=1)
    small = angle < 1e-4
    factor = np.where(small, 0.5 + angle**2 / 12.0, angle / (2.0 * np.sin(np.where(small, 1.0, angle))))
    return skew * factor[:, None]


def pose_errors(
    position: np.ndarray, rotation: np.ndarray, target_position: np.ndarray, target_rotation: np.ndarray
) -> np.ndarray:
    """Errors (n, 6) target − actual in the base frame: position [m] then rotation vector [rad]."""
    err = np.empty((len(position), 6))
    err[:, :3] = target_position - position
    err[:, 3:] = rotation_log(target_rotation @ rotation.transpose(0, 2, 1))
    return err
