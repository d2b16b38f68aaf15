"""Inverse kinematics of whole paths on pinocchio: warm-started damped least squares.

Each sample starts from a first-order extrapolation of the two previous solutions, so a path sampled at the
FRI rate needs one or two Newton steps per pose. The 7th degree of freedom is resolved by a null-space pull
toward the reference configuration ``q0`` (the minimum-norm step otherwise keeps the previous sample's
configuration), so the arm never flips configuration mid-path. Joint positions are kept inside the limits.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import pinocchio as pin

from .errors import IkError
from .limits import JointLimits
from .robot import Robot


@dataclass(frozen=True)
class IkOptions:
    """Tolerances and gains of the path IK."""

    position_tolerance: float = 1e-9  # [m]
    rotation_tolerance: float = 1e-8  # [rad]
    max_iterations_first: int = 200  # Newton steps for the first pose (from q0)
    max_iterations: int = 30  # Newton steps for each following pose
    damping: float = 1e-9  # DLS damping λ² [-]
    nullspace_gain: float = 0.02  # fraction of the way toward q0 in the null space, per sample [-]
    max_step: float = 0.3  # largest joint step per Newton iteration [rad]
    limit_margin: float = 1e-4  # stay this far inside the position limits [rad]


@dataclass(frozen=True)
class IkResult:
    """Joint path (n, 7) [rad] with the remaining TCP error per sample and iterations used."""

    q: np.ndarray
    position_error: np.ndarray  # [m]
    rotation_error: np.ndarray  # [rad]
    iterations: np.ndarray

    @property
    def max_position_error(self) -> float:
        return float(self.position_error.max()) if len(self.position_error) else 0.0

    @property
    def max_rotation_error(self) -> float:
        return float(self.rotation_error.max()) if len(self.rotation_error) else 0.0


def solve_ik_path(
    robot: Robot,
    positions: np.ndarray,
    rotations: np.ndarray,
    q0: np.ndarray,
    limits: JointLimits,
    options: IkOptions = IkOptions(),
    *,
    times: np.ndarray | None = None,
    progress: Callable[[int], None] | None = None,
) -> IkResult:
    """Solve IK for TCP targets (positions (n, 3) [m], rotations (n, 3, 3)) starting near q0 (7,) [rad].

    Raises IkError naming the first sample whose error stays above tolerance.
    """
    model, data, fid = robot.model, robot.data, robot.tcp_id
    n = len(positions)
    out_q = np.empty((n, 7))
    pos_err = np.empty(n)
    rot_err = np.empty(n)
    iters = np.empty(n, dtype=np.int32)
    upper = limits.position - options.limit_margin
    lower = -upper
    q_ref = np.clip(np.asarray(q0, dtype=float), lower, upper)
    eye7 = np.eye(7)
    damp6 = options.damping * np.eye(6)
    tol_p, tol_r = options.position_tolerance, options.rotation_tolerance
    local = pin.ReferenceFrame.LOCAL
    joint_jacobians, frame_placement, frame_jacobian = (
        pin.computeJointJacobians,
        pin.updateFramePlacement,
        pin.getFrameJacobian,
    )
    log6, jlog6 = pin.log6, pin.Jlog6
    SE3 = pin.SE3

    q = q_ref.copy()
    for k in range(n):
        if k >= 2:
            q = 2.0 * out_q[k - 1] - out_q[k - 2]
        elif k == 1:
            q = out_q[0].copy()
        np.clip(q, lower, upper, out=q)
        target = SE3(rotations[k], positions[k])
        budget = options.max_iterations_first if k == 0 else options.max_iterations
        null_pending = True
        it = 0
        while True:
            joint_jacobians(model, data, q)  # forward kinematics + all joint Jacobians
            dM = target.actInv(frame_placement(model, data, fid))
            err = log6(dM).vector
            ep = np.linalg.norm(dM.translation)
            er = np.linalg.norm(err[3:])
            if (ep <= tol_p and er <= tol_r and not null_pending) or it >= budget:
                break
            Jl = jlog6(dM) @ frame_jacobian(model, data, fid, local)
            pinv = np.linalg.solve(Jl @ Jl.T + damp6, Jl).T  # J^T (J J^T + λ²I)^-1
            dq = -pinv @ err
            if null_pending:
                gain = 1.0 if k == 0 else options.nullspace_gain
                dq += gain * ((eye7 - pinv @ Jl) @ (q_ref - q))
                null_pending = k == 0 and it < 20  # converge the first pose to the q0-closest solution
            step = np.abs(dq).max()
            if step > options.max_step:
                dq *= options.max_step / step
            q = q + dq
            np.clip(q, lower, upper, out=q)
            it += 1
        out_q[k] = q
        pos_err[k] = ep
        rot_err[k] = er
        iters[k] = it
        if ep > max(tol_p, 1e-7) or er > max(tol_r, 1e-6):
            t = float(times[k]) if times is not None else float(k)
            raise IkError(
                f"pose {k} (t = {t:.4f} s) not reached: remaining error {ep * 1e3:.3f} mm, "
                f"{np.degrees(er):.4f} deg (out of reach or beyond the joint limits)",
                index=k,
                t=t,
                position_error=float(ep),
                rotation_error=float(er),
            )
        if progress is not None and k % 500 == 0:
            progress(k)
    return IkResult(q=out_q, position_error=pos_err, rotation_error=rot_err, iterations=iters)
