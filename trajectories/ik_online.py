"""Inverse kinematics of one TCP pose at a time, warm-started, for targets that arrive while the robot moves.

A few damped Gauss–Newton steps (pinocchio Jacobian in the world-aligned TCP frame) from a seed — the previous
solution — weighted by the joints' speed limits, each step kept inside the position limits by the box-constrained
least-squares step (:mod:`.boxqp`). The smallest step from the seed resolves the 7th degree of freedom, so
consecutive poses give continuous joints. An unreachable pose gives the closest configuration and says so
(``converged`` False) instead of raising: the caller decides what to do with it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .boxqp import solve_box_qp
from .limits import JointLimits
from .robot import Robot


@dataclass(frozen=True)
class OnlineIkOptions:
    """Tolerances and step sizes of :class:`OnlineIk`."""

    max_iterations: int = 4  # Gauss–Newton steps per call
    position_tolerance: float = 1e-6  # [m]
    rotation_tolerance: float = 1e-5  # [rad]
    damping: float = 1e-6  # DLS damping λ² [-]
    max_step: float = 0.2  # largest weighted joint step per iteration [rad]
    limit_margin: float = 0.01  # stay this far inside the position limits [rad]
    posture_gain: float = 0.01  # share of the way to ``posture`` taken in the null space per call [-]


@dataclass(frozen=True)
class OnlineIkResult:
    """Joint positions [rad] for the pose and the TCP error that remains."""

    q: np.ndarray
    position_error: float  # [m]
    rotation_error: float  # [rad]
    iterations: int
    converged: bool


def fixed_angles_to_matrix(alpha: float, beta: float, gamma: float) -> np.ndarray:
    """Rotation of the fixed-angle form (SimulinkIIWA, KUKA A, B, C): α about Z, β about Y, γ about X of the base
    [rad], i.e. R = Rz(α)·Ry(β)·Rx(γ)."""
    ca, sa, cb, sb, cg, sg = np.cos(alpha), np.sin(alpha), np.cos(beta), np.sin(beta), np.cos(gamma), np.sin(gamma)
    return np.array([
        [ca * cb, ca * sb * sg - sa * cg, ca * sb * cg + sa * sg],
        [sa * cb, sa * sb * sg + ca * cg, sa * sb * cg - ca * sg],
        [-sb, cb * sg, cb * cg],
    ])  # fmt: skip


def quaternion_to_matrix(w: float, x: float, y: float, z: float) -> np.ndarray:
    """Rotation of the quaternion (w, x, y, z), normalised; ValueError for a zero quaternion."""
    n = (w * w + x * x + y * y + z * z) ** 0.5
    if not n > 1e-9:
        raise ValueError("the quaternion has zero length")
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip


class OnlineIk:
    """Warm-started IK of single TCP poses of ``robot`` inside ``limits`` (not thread-safe: owns pinocchio data)."""

    def __init__(self, robot: Robot, limits: JointLimits, options: OnlineIkOptions = OnlineIkOptions()) -> None:
        self.robot = robot
        self.options = options
        self._model = robot.model
        self._data = robot.model.createData()
        self._fid = robot.tcp_id
        self._hi = limits.position - options.limit_margin  # [rad]
        self._lo = -self._hi
        self._w = limits.velocity / limits.velocity.max()  # joint step weights: slow joints move less
        self._jac = np.zeros((6, 7))

    def _kinematics(self, q: np.ndarray, position: np.ndarray, rotation: np.ndarray) -> np.ndarray:
        """One pass at ``q``: the joint Jacobians and frame placements (kept in the data), and the pose error."""
        pin.computeJointJacobians(self._model, self._data, q)  # includes the forward kinematics
        pin.updateFramePlacements(self._model, self._data)
        m = self._data.oMf[self._fid]
        err = np.empty(6)
        err[:3] = position - m.translation
        err[3:] = pin.log3(rotation @ m.rotation.T)
        return err

    def _frame_jacobian(self) -> np.ndarray:
        """The TCP Jacobian of the last :meth:`_kinematics` pass."""
        return pin.getFrameJacobian(self._model, self._data, self._fid, pin.LOCAL_WORLD_ALIGNED)

    def solve(self, seed: np.ndarray, position: np.ndarray, rotation: np.ndarray,
              posture: np.ndarray | None = None, lock: tuple[int, float] | None = None) -> OnlineIkResult:  # fmt: skip
        """Joints reaching the TCP ``position`` [m] and ``rotation`` (3×3) in the base frame, from ``seed`` [rad].

        With ``posture`` [rad] the redundancy is pulled toward it in the null space (``posture_gain`` per call), so a
        source going round in circles does not let the elbow drift. ``lock`` = (joint index, value [rad]) fixes one
        joint instead (KUKA's redundancy E1: the A3 angle); the other six then reach the pose, no posture pull."""
        o = self.options
        lo, hi, w = self._lo, self._hi, self._w
        if lock is not None:  # a box of zero width and zero step weight for the locked joint
            j, value = lock
            lo, hi, w = lo.copy(), hi.copy(), w.copy()
            lo[j] = hi[j] = float(value)
            w[j] = 0.0
            posture = None
        q = np.clip(np.asarray(seed, dtype=float), lo, hi)
        err = self._kinematics(q, position, rotation)
        it = 0
        while it < o.max_iterations and not _small(err, o):
            it += 1
            jac = self._frame_jacobian()
            jw = jac * w  # step in weighted joints z: dq = w·z
            dz = jw.T @ np.linalg.solve(jw @ jw.T + o.damping * np.eye(6), err)
            dq = w * dz
            peak = np.abs(dq).max()
            if peak > o.max_step:
                dq *= o.max_step / peak
            if np.any(q + dq > hi) or np.any(q + dq < lo):
                # the least-squares step inside the box: min |J·dq − err|² + λ|dq|²
                h = jac.T @ jac + o.damping * np.eye(7)
                dq = solve_box_qp(h, jac.T @ err, np.maximum(lo - q, -o.max_step),
                                  np.minimum(hi - q, o.max_step)).x  # fmt: skip
            q = np.clip(q + dq, lo, hi)
            err = self._kinematics(q, position, rotation)
        if posture is not None and o.posture_gain > 0:  # first order: leaves the TCP where it is
            jw = self._frame_jacobian() * w
            pull = o.posture_gain * (np.asarray(posture) - q) / w
            pull -= jw.T @ np.linalg.solve(jw @ jw.T + o.damping * np.eye(6), jw @ pull)
            q = np.clip(q + w * pull, lo, hi)
            err = self._kinematics(q, position, rotation)
        return OnlineIkResult(q, float(np.linalg.norm(err[:3])), float(np.linalg.norm(err[3:])), it, _small(err, o))

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """The TCP Jacobian (6×7, world-aligned: linear [m/s] then angular [rad/s] per [rad/s]) at ``q``."""
        pin.computeJointJacobians(self._model, self._data, np.asarray(q, dtype=float))
        return pin.getFrameJacobian(self._model, self._data, self._fid, pin.LOCAL_WORLD_ALIGNED)

    def tcp(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The TCP position [m] and rotation (3×3) at ``q`` [rad]."""
        pin.framesForwardKinematics(self._model, self._data, np.asarray(q, dtype=float))
        m = self._data.oMf[self._fid]
        return m.translation.copy(), m.rotation.copy()


def _small(err: np.ndarray, o: OnlineIkOptions) -> bool:
    return bool(np.linalg.norm(err[:3]) <= o.position_tolerance and np.linalg.norm(err[3:]) <= o.rotation_tolerance)
