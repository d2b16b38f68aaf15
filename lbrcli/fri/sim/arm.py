"""The simulated arm: the iiwa's rigid-body dynamics (pinocchio) under the controller's three control laws.

- Position control (``follow``): the stiff position controller makes the links follow the interpolator's
  trajectory exactly; the motors then deliver the inverse dynamics minus any external push.
- Joint impedance (``joint_impedance``): τ_m = g(q) + K (q_set − q) − D q̇ + τ_cmd.
- Cartesian impedance (``cartesian_impedance``): τ_m = g(q) + Jᵀ (K_x e_x + F_cmd) + N K_n (q_set − q) − D q̇,
  with e_x the TCP pose error to the pose of q_set (translation [m] and rotation vector [rad]; isotropic
  stiffness k_t [N/m], k_r [Nm/rad]) and N = I − Jᵀ (J Jᵀ)⁻¹ J the projector onto the null space (holds the elbow).

The links obey M(q) q̈ + C(q, q̇) q̇ + g(q) = τ_m + τ_ext (τ_ext: the environment's push). The impedance laws are
integrated with a linearly implicit Euler step (stiffness and damping taken at the end of the step, so the step is
stable for any stiffness), in sub-steps of at most 1 ms. Damping: joint impedance D = 2 ζ √(K M_ii) per joint;
Cartesian D = Jᵀ D_x J + N D_n Nᵀ with D_x = 2 ζ √(k Λ_ii) per base axis (Λ the operational-space mass) and
D_n = 2 ζ √(K_n M_ii). A joint reaching its position limit stops there (a hard stop).

Torques reported: measured = τ_m (what the joint torque sensors read, no friction modelled); external = τ_ext.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from ..constants import N_JOINTS

_MAX_SUBSTEP = 1e-3  # [s]


class Arm:
    """State q [rad], v [rad/s], a [rad/s²] and motor torque tau [Nm] of the simulated LBR."""

    def __init__(
        self, robot, position_limit: np.ndarray, q0: np.ndarray, external_torque: np.ndarray, external_force: np.ndarray
    ) -> None:
        self.model, self.data, self.tcp_id = robot.model, robot.data, robot.tcp_id
        self.qmax = np.asarray(position_limit, dtype=float)  # [rad]
        self.q = np.array(q0, dtype=float)
        self.v = np.zeros(N_JOINTS)
        self.a = np.zeros(N_JOINTS)
        self.tau = pin.computeGeneralizedGravity(self.model, self.data, self.q).copy()  # motor torque [Nm]
        self._ext_joint = np.asarray(external_torque, dtype=float)
        self._ext_force = np.asarray(external_force, dtype=float)  # [N, Nm] at the TCP, base-frame axes
        self.has_external_force = bool(np.any(self._ext_force))
        self.tau_ext = self._ext_joint.copy()  # [Nm]
        self._eye = np.eye(N_JOINTS)
        self._set_q = np.full(N_JOINTS, np.nan)  # cache of the Cartesian set-point's joint position
        self._set_pose = pin.SE3.Identity()

    # -- kinematics ------------------------------------------------------------------------------------------
    def tcp_pose(self, q: np.ndarray | None = None) -> pin.SE3:
        """TCP pose in the base frame [m] at q (default: the measured position); a reference into the data."""
        pin.framesForwardKinematics(self.model, self.data, self.q if q is None else q)
        return self.data.oMf[self.tcp_id]

    def _update_external(self) -> None:
        if self.has_external_force:
            J = pin.computeFrameJacobian(self.model, self.data, self.q, self.tcp_id, pin.LOCAL_WORLD_ALIGNED)
            np.add(self._ext_joint, J.T @ self._ext_force, out=self.tau_ext)

    def external_force_tcp(self) -> np.ndarray:
        """The external wrench [N, Nm] in the TCP frame (what FRI 2.7's externalForce reports)."""
        if not self.has_external_force:
            return np.zeros(6)
        R = self.tcp_pose().rotation
        return np.concatenate([R.T @ self._ext_force[:3], R.T @ self._ext_force[3:]])

    # -- position control ------------------------------------------------------------------------------------
    def follow(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> None:
        """The links follow (q, v, a) exactly; the motors deliver the inverse dynamics minus the push."""
        self.q[:] = q
        self.v[:] = v
        self.a[:] = a
        self._update_external()
        np.subtract(pin.rnea(self.model, self.data, self.q, self.v, self.a), self.tau_ext, out=self.tau)

    # -- impedance control -----------------------------------------------------------------------------------
    def joint_impedance(self, q_set: np.ndarray, tau_cmd: np.ndarray, stiffness: float, zeta: float, dt: float) -> None:
        """Advance dt [s] under joint impedance around q_set [rad] plus the commanded torque [Nm]."""
        n = max(1, math.ceil(dt / _MAX_SUBSTEP - 1e-9))
        h = dt / n
        K = float(stiffness)
        v0 = self.v.copy()
        for _ in range(n):
            M = pin.crba(self.model, self.data, self.q)
            D = 2.0 * zeta * np.sqrt(K * np.diagonal(M))
            g = pin.computeGeneralizedGravity(self.model, self.data, self.q)
            tau = g + K * (q_set - self.q) - D * self.v + tau_cmd
            self._integrate(M, tau, np.diag(h * D + (h * h) * K), h, K * self.v)
        self.a[:] = (self.v - v0) / dt

    def cartesian_impedance(
        self,
        q_set: np.ndarray,
        wrench_tcp: np.ndarray,
        stiffness: tuple[float, float],
        nullspace_stiffness: float,
        zeta: float,
        dt: float,
    ) -> None:
        """Advance dt [s] under Cartesian impedance around the TCP pose of q_set plus the commanded wrench
        (force [N] along the TCP's x, y, z; moments [Nm] about its x, y, z). The stiffness is isotropic
        (translation, rotation), so the same along the TCP's axes as along the base's."""
        model, data = self.model, self.data
        if not np.array_equal(q_set, self._set_q):
            self._set_q[:] = q_set
            self._set_pose = self.tcp_pose(q_set).copy()
        Rs, ps = self._set_pose.rotation, self._set_pose.translation
        kt, kr = stiffness
        kdiag = np.array([kt, kt, kt, kr, kr, kr])
        kn = nullspace_stiffness
        n = max(1, math.ceil(dt / _MAX_SUBSTEP - 1e-9))
        h = dt / n
        v0 = self.v.copy()
        for _ in range(n):
            J = pin.computeFrameJacobian(model, data, self.q, self.tcp_id, pin.LOCAL_WORLD_ALIGNED)
            oMf = data.oMf[self.tcp_id]  # updated by computeFrameJacobian
            R, p = oMf.rotation, oMf.translation
            F = kdiag * np.concatenate([ps - p, pin.log3(Rs @ R.T)])  # spring wrench, base axes
            F[:3] += R @ wrench_tcp[:3]
            F[3:] += R @ wrench_tcp[3:]
            M = pin.crba(model, data, self.q)
            N = self._eye - J.T @ np.linalg.solve(J @ J.T, J)  # null-space projector
            Kq = (J.T * kdiag) @ J + kn * N
            # damping: ζ per base axis with the operational-space mass Λ, ζ per joint in the null space
            lam_diag = np.diagonal(np.linalg.inv(J @ np.linalg.solve(M, J.T)))
            dx = 2.0 * zeta * np.sqrt(kdiag * np.maximum(lam_diag, 0.0))
            D = (J.T * dx) @ J + (N * (2.0 * zeta * np.sqrt(kn * np.diagonal(M)))) @ N.T
            g = pin.computeGeneralizedGravity(model, data, self.q)
            tau = g + J.T @ F + N @ (kn * (q_set - self.q)) - D @ self.v
            self._integrate(M, tau, h * D + h * h * Kq, h, Kq @ self.v)
        self.a[:] = (self.v - v0) / dt

    def _integrate(self, M: np.ndarray, tau_m: np.ndarray, implicit: np.ndarray, h: float, kv: np.ndarray) -> None:
        """One linearly implicit Euler step of h [s] with motor torque tau_m [Nm]:
        (M + h D + h² K) Δv = h (τ_m + τ_ext − C q̇ − g − h K q̇); then the position limits (hard stops)."""
        model, data = self.model, self.data
        self._update_external()
        nle = pin.nonLinearEffects(model, data, self.q, self.v)  # C q̇ + g
        self.tau[:] = tau_m
        dv = np.linalg.solve(M + implicit, h * (tau_m + self.tau_ext - nle - h * kv))
        self.v += dv
        self.q += h * self.v
        over = np.abs(self.q) > self.qmax
        if over.any():
            np.clip(self.q, -self.qmax, self.qmax, out=self.q)
            self.v[over] = 0.0
