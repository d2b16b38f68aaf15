"""An independent forward kinematics of the iiwa 7 from the thesis's Denavit–Hartenberg table (shared/facts/robot.md:
standard DH, T_i = Rz(θ)·Tz(d)·Tx(a)·Rx(α)), plain numpy — a second judge beside the project's pinocchio model."""

from __future__ import annotations

import numpy as np

D = (0.340, 0.0, 0.400, 0.0, 0.400, 0.0, 0.152)  # [m] d1..d7 (Touch Electric media flange)
ALPHA = (-np.pi / 2, np.pi / 2, np.pi / 2, -np.pi / 2, -np.pi / 2, np.pi / 2, 0.0)


def flange(q) -> np.ndarray:
    """4×4 flange pose [m] of the joint angles ``q`` [rad] in the base frame."""
    t = np.eye(4)
    for theta, d, alpha in zip(q, D, ALPHA):
        ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
        t = t @ np.array([[ct, -st * ca, st * sa, 0.0], [st, ct * ca, -ct * sa, 0.0], [0.0, sa, ca, d],
                          [0.0, 0.0, 0.0, 1.0]])  # fmt: skip
    return t


def quaternion_matrix(w: float, x: float, y: float, z: float) -> np.ndarray:
    """Rotation of a unit quaternion (w, x, y, z), written out (no library)."""
    n = np.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])  # fmt: skip


def pose_error(q, wire) -> tuple[float, float]:
    """(position error [m], rotation angle error [rad]) of the DH flange at ``q`` against a wire pose (tx, ty, tz
    [mm], qw, qx, qy, qz)."""
    t = flange(q)
    dp = np.linalg.norm(t[:3, 3] - np.asarray(wire[:3]) * 1e-3)
    r = quaternion_matrix(*wire[3:]).T @ t[:3, :3]
    angle = np.arccos(np.clip((np.trace(r) - 1.0) / 2.0, -1.0, 1.0))
    return float(dp), float(angle)
