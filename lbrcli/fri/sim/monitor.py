"""The monitoring message the simulated controller sends: built once, its values updated every cycle."""

from __future__ import annotations

import time

import numpy as np

from ..codec import FriCodec
from ..constants import (
    MONITORING_MESSAGE_ID,
    N_JOINTS,
    ConnectionQuality,
    DriveState,
    SafetyState,
    SessionState,
)
from .config import OPERATION_MODES, SimConfig
from .io import IoBank

_U32 = 0xFFFFFFFF


def _pose7(pose, out) -> None:
    """SE3 [m] → FRI quaternion transformation (tx, ty, tz [mm], qw, qx, qy, qz) into a repeated double."""
    import pinocchio as pin

    x, y, z, w = pin.Quaternion(pose.rotation).coeffs().tolist()
    t = pose.translation
    out[:] = [t[0] * 1e3, t[1] * 1e3, t[2] * 1e3, w, x, y, z]


class MonitoringWriter:
    """One FRIMonitoringMessage object (``mon``) with the application's IO configuration (``io``)."""

    def __init__(self, codec: FriCodec, cfg: SimConfig, client_mode: int, overlay: int, control: int) -> None:
        self.codec = codec
        self.cfg = cfg
        self._nprng = np.random.default_rng(cfg.seed)
        self._v27 = codec.framed
        self._ipo_posed = np.full(N_JOINTS, np.nan)  # the ipo position whose Cartesian pose is in the message
        m = self.codec.new_monitoring()
        m.header.messageIdentifier = MONITORING_MESSAGE_ID
        m.header.sequenceCounter = 0
        m.header.reflectedSequenceCounter = 0
        ri = m.robotInfo
        ri.numberOfJoints = N_JOINTS
        ri.safetyState = SafetyState.NORMAL_OPERATION
        ri.driveState.extend([DriveState.ACTIVE] * N_JOINTS)
        ri.operationMode = OPERATION_MODES[cfg.operation_mode]
        ri.controlMode = control
        ci = m.connectionInfo
        ci.sessionState = SessionState.MONITORING_WAIT
        ci.quality = ConnectionQuality.POOR
        ci.sendPeriod = cfg.period_ms
        ci.receiveMultiplier = cfg.receive_multiplier
        md = m.monitorData
        zeros = [0.0] * N_JOINTS
        for f in (md.measuredJointPosition, md.measuredTorque, md.commandedTorque, md.externalTorque):
            f.value.extend(zeros)
        self._v_msr_q, self._v_msr_tau = md.measuredJointPosition.value, md.measuredTorque.value
        self._v_cmd_tau, self._v_ext_tau = md.commandedTorque.value, md.externalTorque.value
        fields = md.DESCRIPTOR.fields_by_name
        self._v_cmd_q = None
        if "commandedJointPosition" in fields:
            md.commandedJointPosition.value.extend(zeros)
            self._v_cmd_q = md.commandedJointPosition.value
        self._ts = md.timestamp
        self._t0_ns: int | None = None
        self._period_ns = int(cfg.period_ms) * 1_000_000
        self._ts.sec = 0
        self._ts.nanosec = 0
        ipo = m.ipoData
        ipo.clientCommandMode = client_mode
        ipo.overlayType = overlay
        ipo.trackingPerformance = 0.0
        ipo.jointPosition.value.extend(zeros)
        self._v_ipo_q = ipo.jointPosition.value
        if self._v27:  # FRI 2.x: Cartesian poses, redundancy (E1 = the A3 angle, as the SDK documents), force
            e1 = self.codec.msgs.enums["RedundancyStrategy"]["E1"]
            for pose in (md.measuredCartesianPose, ipo.cartesianPose):
                pose.name = ""
                pose.element.extend([0.0] * 7)
            for red in (md.measuredRedundancyInformation, ipo.redundancyInformation):
                red.strategy, red.value = e1, 0.0
            md.externalForce.element.extend([0.0] * 6)
        self.io = IoBank(md, self.codec.msgs.enums, cfg.io)
        self.mon = m

    def fill(
        self,
        seq: int,
        reflect: int,
        state: SessionState,
        quality: ConnectionQuality,
        arm,
        ipo_q: np.ndarray,
        command: np.ndarray,
        tracking: float,
        pose,
    ) -> bytes:
        """The encoded message of cycle ``seq``: the arm's measured state and torques, the ipo position, the
        command in force [rad], the tracking performance, the measured TCP ``pose`` (pinocchio SE3)."""
        m = self.mon
        m.header.sequenceCounter = seq & _U32
        m.header.reflectedSequenceCounter = reflect
        m.connectionInfo.sessionState = state
        m.connectionInfo.quality = quality
        self._v_msr_q[:] = arm.q.tolist()
        self._v_ipo_q[:] = ipo_q.tolist()
        if self._v_cmd_q is not None:
            self._v_cmd_q[:] = command.tolist()
        tau = arm.tau
        self._v_cmd_tau[:] = tau.tolist()
        if self.cfg.torque_noise > 0.0:
            tau = tau + self._nprng.normal(0.0, self.cfg.torque_noise, N_JOINTS)
        self._v_msr_tau[:] = tau.tolist()
        self._v_ext_tau[:] = arm.tau_ext.tolist()
        m.ipoData.trackingPerformance = tracking
        if self._v27:
            md, ipo = m.monitorData, m.ipoData
            _pose7(pose, md.measuredCartesianPose.element)
            md.measuredRedundancyInformation.value = float(arm.q[2])
            if arm.has_external_force:
                md.externalForce.element[:] = arm.external_force_tcp().tolist()
            if not np.array_equal(self._ipo_posed, ipo_q):
                self._ipo_posed[:] = ipo_q
                _pose7(arm.tcp_pose(ipo_q), ipo.cartesianPose.element)
                ipo.redundancyInformation.value = float(ipo_q[2])
        # the controller's real-time clock: its cycle instants (wall clock at the first message + seq × period), not
        # this process's scheduling jitter
        if self._t0_ns is None:
            self._t0_ns = time.time_ns() - seq * self._period_ns
        ns = self._t0_ns + seq * self._period_ns
        self._ts.sec = (ns // 1_000_000_000) & _U32
        self._ts.nanosec = ns % 1_000_000_000
        return self.codec.encode(m)
