"""Conversions between rotation matrices and unit quaternions (w, x, y, z) for task trajectories."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation


def quaternions_from_matrices(rot: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotations → (n, 4) quaternions (w, x, y, z), sign kept continuous along the path."""
    quat = Rotation.from_matrix(rot).as_quat(scalar_first=True)
    if len(quat) and quat[0, 0] < 0:
        quat[0] = -quat[0]
    for k in range(1, len(quat)):
        if np.dot(quat[k], quat[k - 1]) < 0:
            quat[k] = -quat[k]
    return quat


def matrices_from_quaternions(quat: np.ndarray) -> np.ndarray:
    """(n, 4) quaternions (w, x, y, z) → (n, 3, 3) rotation matrices."""
    return Rotation.from_quat(np.asarray(quat, dtype=float), scalar_first=True).as_matrix()
