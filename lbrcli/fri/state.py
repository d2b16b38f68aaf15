"""The robot's state as the controller reported it in the last monitoring message (KUKA's ``LBRState``).

A read-only, typed view over the decoded message: no caller touches protobuf paths. Joint values come back as
tuples of 7 floats [rad] or [Nm]; a value the controller did not send raises :class:`FriStateError`.
"""

from __future__ import annotations

from typing import Any

from .constants import (
    N_JOINTS,
    ClientCommandMode,
    ConnectionQuality,
    ControlMode,
    DriveState,
    OperationMode,
    OverlayType,
    SafetyState,
    SessionState,
)
from .errors import FriStateError
from .messages import FriVersion

_BOOLEAN, _DIGITAL, _ANALOG = 0, 1, 2
_IO_TYPES = {_BOOLEAN: "boolean", _DIGITAL: "digital", _ANALOG: "analog"}


def _joints(values: Any, what: str) -> tuple[float, ...]:
    if len(values) != N_JOINTS:
        raise FriStateError(f"the controller sent no {what} in this message")
    return tuple(values)


class LBRState:
    """View of one monitoring message; the application re-points it at every new message."""

    NUMBER_OF_JOINTS = N_JOINTS

    def __init__(self, message: Any, version: FriVersion | str = FriVersion.V1_15) -> None:
        self.message = message  # the decoded protobuf message (escape hatch; read-only by convention)
        self.version = FriVersion(version)

    # -- session --------------------------------------------------------------------------------------------
    @property
    def session_state(self) -> SessionState:
        return SessionState(self.message.connectionInfo.sessionState)

    @property
    def quality(self) -> ConnectionQuality:
        return ConnectionQuality(self.message.connectionInfo.quality)

    @property
    def sample_time(self) -> float:
        """The controller's send period [s] (KUKA's getSampleTime)."""
        return self.message.connectionInfo.sendPeriod * 1e-3

    @property
    def receive_multiplier(self) -> int:
        """The client answers every k-th message."""
        return self.message.connectionInfo.receiveMultiplier or 1

    @property
    def sequence_counter(self) -> int:
        return self.message.header.sequenceCounter

    @property
    def reflected_sequence_counter(self) -> int:
        """The client's sequence counter the controller last received."""
        return self.message.header.reflectedSequenceCounter

    @property
    def timestamp(self) -> float:
        """Controller time stamp of the message [s] (seconds + nanoseconds)."""
        ts = self.message.monitorData.timestamp
        return ts.sec + ts.nanosec * 1e-9

    @property
    def timestamp_sec(self) -> int:
        return self.message.monitorData.timestamp.sec

    @property
    def timestamp_nanosec(self) -> int:
        return self.message.monitorData.timestamp.nanosec

    # -- robot ----------------------------------------------------------------------------------------------
    @property
    def safety_state(self) -> SafetyState:
        return SafetyState(self.message.robotInfo.safetyState)

    @property
    def operation_mode(self) -> OperationMode:
        return OperationMode(self.message.robotInfo.operationMode)

    @property
    def drive_state(self) -> DriveState:
        """The lowest state of the 7 drives (ACTIVE only when all are)."""
        drives = self.message.robotInfo.driveState
        return DriveState(min(drives)) if drives else DriveState.OFF

    @property
    def control_mode(self) -> ControlMode:
        return ControlMode(self.message.robotInfo.controlMode)

    @property
    def client_command_mode(self) -> ClientCommandMode:
        return ClientCommandMode(self.message.ipoData.clientCommandMode)

    @property
    def overlay_type(self) -> OverlayType:
        return OverlayType(self.message.ipoData.overlayType)

    @property
    def tracking_performance(self) -> float:
        """0..1; 1 when the controller follows the commands exactly (0 outside COMMANDING_ACTIVE)."""
        return self.message.ipoData.trackingPerformance

    # -- joints ---------------------------------------------------------------------------------------------
    @property
    def measured_joint_position(self) -> tuple[float, ...]:
        """[rad]"""
        return _joints(self.message.monitorData.measuredJointPosition.value, "measured joint position")

    @property
    def ipo_joint_position(self) -> tuple[float, ...]:
        """[rad] the robot application's own motion (constant under a PositionHold)."""
        return _joints(self.message.ipoData.jointPosition.value, "ipo joint position")

    @property
    def commanded_joint_position(self) -> tuple[float, ...]:
        """[rad] the command in force (FRI 1.x only)."""
        md = self.message.monitorData
        if "commandedJointPosition" not in md.DESCRIPTOR.fields_by_name:
            raise FriStateError(f"FRI {self.version.value} does not report the commanded joint position")
        return _joints(md.commandedJointPosition.value, "commanded joint position")

    @property
    def measured_torque(self) -> tuple[float, ...]:
        """[Nm]"""
        return _joints(self.message.monitorData.measuredTorque.value, "measured torque")

    @property
    def commanded_torque(self) -> tuple[float, ...]:
        """[Nm]"""
        return _joints(self.message.monitorData.commandedTorque.value, "commanded torque")

    @property
    def external_torque(self) -> tuple[float, ...]:
        """[Nm] estimated external torques."""
        return _joints(self.message.monitorData.externalTorque.value, "external torque")

    # -- FRI 2.x Cartesian data -----------------------------------------------------------------------------
    def _pose(self, holder: Any, field: str, what: str) -> tuple[float, ...]:
        if field not in holder.DESCRIPTOR.fields_by_name:
            raise FriStateError(f"FRI {self.version.value} does not report the {what}")
        e = getattr(holder, field).element
        if len(e) != 7:
            raise FriStateError(f"the controller sent no {what} in this message")
        return (e[0] * 1e-3, e[1] * 1e-3, e[2] * 1e-3, e[3], e[4], e[5], e[6])

    @property
    def measured_cartesian_pose(self) -> tuple[float, ...]:
        """Flange pose x, y, z [m], qw, qx, qy, qz in the base frame (FRI 2.x; the wire carries mm)."""
        return self._pose(self.message.monitorData, "measuredCartesianPose", "measured Cartesian pose")

    @property
    def ipo_cartesian_pose(self) -> tuple[float, ...]:
        """Pose of the application's own motion, x, y, z [m], qw, qx, qy, qz (FRI 2.x)."""
        return self._pose(self.message.ipoData, "cartesianPose", "ipo Cartesian pose")

    @property
    def external_force(self) -> tuple[float, ...]:
        """Estimated external wrench fx, fy, fz [N], tx, ty, tz [Nm] (FRI 2.7)."""
        md = self.message.monitorData
        if "externalForce" not in md.DESCRIPTOR.fields_by_name:
            raise FriStateError(f"FRI {self.version.value} does not report the external force")
        e = md.externalForce.element
        if len(e) != 6:
            raise FriStateError("the controller sent no external force in this message")
        return tuple(e)

    @property
    def measured_redundancy_value(self) -> float:
        """Redundancy parameter of the measured pose (E1 [rad]; FRI 2.x)."""
        md = self.message.monitorData
        if "measuredRedundancyInformation" not in md.DESCRIPTOR.fields_by_name:
            raise FriStateError(f"FRI {self.version.value} does not report redundancy information")
        if not md.HasField("measuredRedundancyInformation"):
            raise FriStateError("the controller sent no redundancy information in this message")
        return md.measuredRedundancyInformation.value

    @property
    def ipo_redundancy_value(self) -> float:
        """E1 [rad] of the application's own motion (FRI 2.x; KUKA's getIpoRedundancyValue)."""
        ipo = self.message.ipoData
        if "redundancyInformation" not in ipo.DESCRIPTOR.fields_by_name:
            raise FriStateError(f"FRI {self.version.value} does not report redundancy information")
        if not ipo.HasField("redundancyInformation"):
            raise FriStateError("the controller sent no ipo redundancy information (no Cartesian overlay active)")
        return ipo.redundancyInformation.value

    @property
    def requested_transformation_ids(self) -> tuple[str, ...]:
        """Names of the frames the robot application asks the client to provide (FRI 2.x; else empty)."""
        if "requestedTransformations" not in self.message.DESCRIPTOR.fields_by_name:
            return ()
        return tuple(t.name for t in self.message.requestedTransformations)

    # -- IO -------------------------------------------------------------------------------------------------
    @property
    def io_names(self) -> tuple[str, ...]:
        """Names of the IO channels in this message (inputs and outputs)."""
        return tuple(io.name for io in self.message.monitorData.readIORequest)

    def _io(self, name: str, kind: int) -> Any:
        for io in self.message.monitorData.readIORequest:
            if io.name == name:
                if io.type != kind:
                    raise FriStateError(f"IO {name} is {_IO_TYPES.get(io.type, '?')}, not {_IO_TYPES[kind]}")
                return io
        raise FriStateError(f"IO {name} is not in the monitoring message (configured in the robot application?)")

    def is_output(self, name: str) -> bool:
        for io in self.message.monitorData.readIORequest:
            if io.name == name:
                return io.direction == 1
        raise FriStateError(f"IO {name} is not in the monitoring message")

    def boolean_io(self, name: str) -> bool:
        return bool(self._io(name, _BOOLEAN).digitalValue)

    def digital_io(self, name: str) -> int:
        return int(self._io(name, _DIGITAL).digitalValue)

    def analog_io(self, name: str) -> float:
        return float(self._io(name, _ANALOG).analogValue)
