"""The command message the application sends back: one protobuf object reused every cycle (no allocation beyond
what protobuf needs), filled with the guarded joint position, torque or wrench — or, in FRI 2.7's CARTESIAN_POSE
mode, the pose of the guarded joint position and its E1 instead of joints — the IO writes and the transformations."""

from __future__ import annotations

from typing import Any, Sequence

from .codec import FriCodec
from .constants import COMMAND_MESSAGE_ID, ClientCommandMode

_TORQUE = int(ClientCommandMode.TORQUE)
_WRENCH = int(ClientCommandMode.WRENCH)
_CARTESIAN = int(ClientCommandMode.CARTESIAN_POSE)


class ReplyMessage:
    """The outgoing command message of a session."""

    def __init__(self, codec: FriCodec) -> None:
        self.codec = codec
        out = codec.new_command()
        out.header.messageIdentifier = COMMAND_MESSAGE_ID
        out.header.sequenceCounter = 0
        out.header.reflectedSequenceCounter = 0
        self.message: Any = out
        self._jp = self._torque = self._wrench = self._io = self._pose = self._tr = False  # which fields hold values

    def set_motion(self, mode: int, q: Sequence[float], tau: Sequence[float] | None,
                   wrench: Sequence[float] | None, pose: Sequence[float] | None = None) -> None:  # fmt: skip
        """Joint position [rad], plus the torque [Nm] in TORQUE mode or the wrench [N, Nm] in WRENCH mode; in
        CARTESIAN_POSE mode instead the wire ``pose`` (tx, ty, tz [mm], qw, qx, qy, qz) of q and E1 = q[2] [rad]."""
        cd = self.message.commandData
        if mode == _CARTESIAN:
            if self._jp:
                cd.ClearField("jointPosition")
                self._jp = False
            if self._pose:
                cd.cartesianPose.element[:] = pose
            else:
                cd.cartesianPose.name = ""
                cd.cartesianPose.element.extend(pose)
                cd.redundancyInformation.strategy = 0  # E1
                self._pose = True
            cd.redundancyInformation.value = q[2]
            return
        if self._jp:
            cd.jointPosition.value[:] = q
        else:
            cd.jointPosition.value.extend(q)
            self._jp = True
        if mode == _TORQUE:
            if self._torque:
                cd.jointTorque.value[:] = tau
            else:
                cd.jointTorque.value.extend(tau)
                self._torque = True
        elif mode == _WRENCH:
            if self._wrench:
                cd.cartesianWrenchFeedForward.element[:] = wrench
            else:
                cd.cartesianWrenchFeedForward.element.extend(wrench)
                self._wrench = True

    def header_only(self) -> None:
        """No command data (the monitoring states); IO writes may still be added."""
        if self._jp or self._io or self._pose or self._tr:
            self.message.ClearField("commandData")
            self._jp = self._torque = self._wrench = self._io = self._pose = self._tr = False

    def set_io(self, writes: Sequence[tuple[str, int, float | int]]) -> None:
        """This cycle's IO writes (name, FriIOType, value); none clears the last cycle's."""
        cd = self.message.commandData
        if self._io:
            cd.ClearField("writeIORequest")
            self._io = False
        if writes:
            for name, kind, value in writes:
                io = cd.writeIORequest.add()
                io.name, io.type, io.direction = name, kind, 1
                if kind == 2:
                    io.analogValue = value
                else:
                    io.digitalValue = value
            self._io = True

    def set_transformations(self, values: Sequence[tuple[str, Sequence[float], int, int]]) -> None:
        """This cycle's transformations (name, wire pose (tx, ty, tz [mm], qw, qx, qy, qz), sec, nanosec)."""
        cd = self.message.commandData
        if self._tr:
            cd.ClearField("commandedTransformations")
            self._tr = False
        for name, element, sec, nanosec in values:
            tr = cd.commandedTransformations.add()
            tr.name = name
            tr.element.extend(element)
            tr.timestamp.sec, tr.timestamp.nanosec = sec, nanosec
            self._tr = True

    def datagram(self, sequence: int, reflected: int) -> bytes:
        """The framed datagram with these counters."""
        h = self.message.header
        h.sequenceCounter = sequence
        h.reflectedSequenceCounter = reflected
        return self.codec.frame(self.message.SerializeToString())
