"""Closed-form inverse kinematics of the iiwa by arm angle.

The iiwa is an S-R-S arm: axes 1–3 meet at the shoulder S, axes 5–7 at the wrist W. For a flange pose the
wrist is fixed, the elbow E lies on a circle about the line S–W, and its place on the circle — the arm angle
ψ [rad], measured from the vertical plane through S–W — is the one redundant degree of freedom. With the
signs of A2, A4 and A6 (the shoulder, elbow and wrist branches) the seven joint angles follow in closed form
from (pose, ψ). Every joint limit of the iiwa is below π, so the atan2 values are the joint angles themselves.

Vectorised over any leading shape: poses (..., 3, 3) / (..., 3) broadcast against ψ (...).
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import product

import numpy as np

from .robot import Robot

BRANCHES = np.array(list(product((1.0, -1.0), repeat=3)))  # (8, 3): signs of A2, A4, A6


@dataclass(frozen=True)
class ArmGeometry:
    """Segment lengths of the S-R-S chain and the TCP in the flange frame."""

    base_shoulder: float  # [m] d1
    shoulder_elbow: float  # [m] d3
    elbow_wrist: float  # [m] d5
    wrist_flange: float  # [m] d7
    tool: np.ndarray  # (3,) [m], TCP in the flange frame (no rotation)

    @classmethod
    def of(cls, robot: Robot) -> "ArmGeometry":
        from .robot import DH_TABLE

        return cls(
            base_shoulder=DH_TABLE[0][0],
            shoulder_elbow=DH_TABLE[2][0],
            elbow_wrist=DH_TABLE[4][0],
            wrist_flange=robot.config.flange.d7,
            tool=np.asarray(robot.config.tool, dtype=float),
        )


def _rz_rx(q: np.ndarray, sin_alpha: float) -> np.ndarray:
    """Rz(q)·Rx(α) for α = ±π/2 (sin α = ±1), shape (..., 3, 3)."""
    c, s = np.cos(q), np.sin(q)
    z = np.zeros_like(q)
    return np.stack(
        [
            np.stack([c, z, s * sin_alpha], -1),
            np.stack([s, z, -c * sin_alpha], -1),
            np.stack([z, np.full_like(q, sin_alpha), z], -1),
        ],
        -2,
    )


def _reference(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Axes (v, w) of the elbow circle's plane for S–W directions u (..., 3): v is the base vertical projected
    normal to u (the base x axis when u is vertical) — ψ = 0 —, w = u × v."""
    v = np.array([0.0, 0.0, 1.0]) - u * u[..., 2:3]
    flat = np.linalg.norm(v, axis=-1) < 1e-9
    if flat.any():
        v = np.where(flat[..., None], np.array([1.0, 0.0, 0.0]) - u * u[..., 0:1], v)
    v = v / np.linalg.norm(v, axis=-1, keepdims=True)
    return v, np.cross(u, v)


def _mt_v(m: np.ndarray, v: np.ndarray) -> np.ndarray:
    """mᵀ·v for stacks of 3×3 matrices and 3-vectors."""
    return np.einsum("...ji,...j->...i", m, v)


def inverse(
    geometry: ArmGeometry, rotation: np.ndarray, position: np.ndarray, psi: np.ndarray, branch: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Joint angles (..., 7) [rad] putting the TCP at (rotation, position) with arm angle ``psi`` [rad] and
    branch signs ``branch`` (..., 3) of A2, A4, A6; and whether the wrist is within the arm's reach (...)."""
    rotation = np.asarray(rotation, dtype=float)
    flange = np.asarray(position, dtype=float) - np.einsum("...ij,j->...i", rotation, geometry.tool)
    d1, d3, d5, d7 = geometry.base_shoulder, geometry.shoulder_elbow, geometry.elbow_wrist, geometry.wrist_flange
    psi = np.asarray(psi, dtype=float)
    branch = np.asarray(branch, dtype=float)
    shape = np.broadcast_shapes(rotation.shape[:-2], flange.shape[:-1], psi.shape, branch.shape[:-1])
    rotation = np.broadcast_to(rotation, shape + (3, 3))
    flange = np.broadcast_to(flange, shape + (3,))
    psi = np.broadcast_to(psi, shape)
    g2, g4, g6 = (np.broadcast_to(branch[..., i], shape) for i in range(3))

    wrist = flange - d7 * rotation[..., :, 2]
    sw = wrist - np.array([0.0, 0.0, d1])
    length = np.linalg.norm(sw, axis=-1)
    u = sw / np.maximum(length, 1e-12)[..., None]
    cos_b = (d3 * d3 + length * length - d5 * d5) / (2.0 * d3 * np.maximum(length, 1e-12))
    reach = (cos_b >= -1.0) & (cos_b <= 1.0) & (length > 1e-9)
    cos_b = np.clip(cos_b, -1.0, 1.0)
    sin_b = np.sqrt(1.0 - cos_b * cos_b)
    v, w = _reference(u)
    elbow_dir = cos_b[..., None] * u + sin_b[..., None] * (np.cos(psi)[..., None] * v + np.sin(psi)[..., None] * w)
    elbow = np.array([0.0, 0.0, d1]) + d3 * elbow_dir
    # shoulder: z2 = elbow direction = (c1 s2, s1 s2, c2)
    q2 = g2 * np.arccos(np.clip(elbow_dir[..., 2], -1.0, 1.0))
    q1 = np.arctan2(g2 * elbow_dir[..., 1], g2 * elbow_dir[..., 0])
    r02 = _rz_rx(q1, -1.0) @ _rz_rx(q2, 1.0)
    # elbow axis z3 normal to the arm's plane (the plane of u and the elbow's radial direction; defined by ψ
    # even for a straight arm); its sign picks the elbow branch
    z3 = np.sin(psi)[..., None] * v - np.cos(psi)[..., None] * w
    z3_2 = _mt_v(r02, z3)  # (s3, −c3, 0)
    q3 = np.arctan2(z3_2[..., 0], -z3_2[..., 1])
    r03 = r02 @ _rz_rx(q3, 1.0)
    ew_3 = _mt_v(r03, wrist - elbow) / d5  # (−s4, c4, 0)
    q4 = np.arctan2(-ew_3[..., 0], ew_3[..., 1])
    # the other elbow branch: z3 reversed → A3 + π, −A4
    flip4 = np.sign(q4) != g4
    q3 = np.where(flip4, np.where(q3 > 0, q3 - np.pi, q3 + np.pi), q3)
    q4 = np.where(flip4, -q4, q4)
    r04 = _rz_rx(q1, -1.0) @ _rz_rx(q2, 1.0) @ _rz_rx(q3, 1.0) @ _rz_rx(q4, -1.0)
    # wrist: z7 in frame 4 = (c5 s6, s5 s6, c6)
    z7_4 = _mt_v(r04, rotation[..., :, 2])
    q6 = g6 * np.arccos(np.clip(z7_4[..., 2], -1.0, 1.0))
    q5 = np.arctan2(g6 * z7_4[..., 1], g6 * z7_4[..., 0])
    r06 = r04 @ _rz_rx(q5, -1.0) @ _rz_rx(q6, 1.0)
    x7_6 = _mt_v(r06, rotation[..., :, 0])  # (c7, s7, 0)
    q7 = np.arctan2(x7_6[..., 1], x7_6[..., 0])
    return np.stack([q1, q2, q3, q4, q5, q6, q7], axis=-1), reach


def arm_angle(geometry: ArmGeometry, q: np.ndarray) -> np.ndarray:
    """Arm angle ψ [rad] of joint configurations q (..., 7): where the elbow sits on its circle about S–W."""
    q = np.asarray(q, dtype=float)
    d1, d3, d5 = geometry.base_shoulder, geometry.shoulder_elbow, geometry.elbow_wrist
    r02 = _rz_rx(q[..., 0], -1.0) @ _rz_rx(q[..., 1], 1.0)
    elbow_dir = r02[..., :, 2]
    r04 = r02 @ _rz_rx(q[..., 2], 1.0) @ _rz_rx(q[..., 3], -1.0)
    wrist = np.array([0.0, 0.0, d1]) + d3 * elbow_dir + d5 * r04[..., :, 2]
    sw = wrist - np.array([0.0, 0.0, d1])
    v, w = _reference(sw / np.linalg.norm(sw, axis=-1, keepdims=True))
    return np.arctan2(np.einsum("...i,...i", elbow_dir, w), np.einsum("...i,...i", elbow_dir, v))


def branch_of(q: np.ndarray) -> np.ndarray:
    """Branch signs (..., 3) of A2, A4, A6 (+1 at exactly 0)."""
    q = np.asarray(q, dtype=float)
    return np.where(q[..., [1, 3, 5]] < 0.0, -1.0, 1.0)
