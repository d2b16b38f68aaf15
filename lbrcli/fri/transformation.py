"""KUKA's ``TransformationClient`` (FRI 2.7): provide the frames the robot application requests.

A Sunrise application can take frames from the FRI client (a camera's object pose, say): the controller then names
them in every monitoring message and the client answers each with their current values. Subclass
:class:`TransformationClient`, override ``provide`` and pass it to the application next to the robot client::

    class Provider(TransformationClient):
        def provide(self):
            for name in self.requested_transformation_ids():
                self.set_transformation(name, pose_of(name))  # 4×4 [m], stamped with the message's time

    ClientApplication(LBRClient(), robot=..., transformation_client=Provider()).run()

``provide`` is called once per monitoring message in every state but IDLE, after the robot client's callback (as
KUKA's ``ClientApplication::step``); values go out with that message's reply. Poses are in metres (the wire carries
millimetres); at most 5 frames per message, names shorter than 64 bytes (KUKA's SDK limits).
"""

from __future__ import annotations

from typing import Any

from .constants import ConnectionQuality
from .errors import FriCommandError

__all__ = ["MAX_TRANSFORMATIONS", "TransformationClient"]

MAX_TRANSFORMATIONS = 5
"""Requested transformations one FRI 2.7 message carries at most (KUKA's SDK: 5)."""


class TransformationClient:
    """Provides requested frames; ``robot_state`` is set by the application before ``provide`` is called."""

    robot_state: Any = None  # LBRState of the current message

    def __init__(self) -> None:
        self.values: list[tuple[str, list[float], int, int]] = []  # this cycle's (name, wire pose, sec, nanosec)

    def provide(self) -> None:
        """Set this cycle's values with ``set_transformation`` (default: none)."""

    def requested_transformation_ids(self) -> tuple[str, ...]:
        """Names of the frames the robot application requests (KUKA's getRequestedTransformationIDs)."""
        return self.robot_state.requested_transformation_ids

    @property
    def timestamp_sec(self) -> int:
        """The current message's controller time stamp, seconds part."""
        return self.robot_state.timestamp_sec

    @property
    def timestamp_nanosec(self) -> int:
        """The current message's controller time stamp, nanoseconds part."""
        return self.robot_state.timestamp_nanosec

    @property
    def sample_time(self) -> float:
        """The controller's send period [s]."""
        return self.robot_state.sample_time

    @property
    def connection_quality(self) -> ConnectionQuality:
        return self.robot_state.quality

    def set_transformation(self, transformation_id: str, pose, timestamp_sec: int | None = None,
                           timestamp_nanosec: int | None = None) -> None:  # fmt: skip
        """The value of frame ``transformation_id``: a 4×4 or 3×4 matrix, 12 row-major values (translation [m]) or
        x, y, z [m], qw, qx, qy, qz; stamped with the time the data was taken (default: this message's time stamp).
        FriCommandError for a malformed pose, a name of 64 bytes or more, or more than 5 frames."""
        from .cartesian import pose_matrix, pose_to_wire

        if len(self.values) >= MAX_TRANSFORMATIONS:
            raise FriCommandError(f"more than {MAX_TRANSFORMATIONS} transformations in one message")
        if not (0 < len(transformation_id.encode()) < 64):
            raise FriCommandError(f"transformation id must be 1..63 bytes, got {transformation_id!r}")
        try:
            m = pose_matrix(pose)
        except ValueError as exc:
            raise FriCommandError(f"transformation {transformation_id}: {exc}") from None
        sec = self.timestamp_sec if timestamp_sec is None else int(timestamp_sec)
        nsec = self.timestamp_nanosec if timestamp_nanosec is None else int(timestamp_nanosec)
        self.values.append((transformation_id, pose_to_wire(m[:3, 3], m[:3, :3]), sec, nsec))
