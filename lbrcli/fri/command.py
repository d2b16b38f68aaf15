"""What the client answers in a cycle (KUKA's ``LBRCommand``): joint position, torque, wrench, Cartesian pose, IO.

The application resets it before each callback and writes what was set into the command message. As in KUKA's
SDK the joint position is always required in the commanding states (also in TORQUE and WRENCH mode); torques are
allowed only in TORQUE mode, a wrench only in WRENCH mode, IO writes only to channels the controller reports as
outputs. In FRI 2.7's CARTESIAN_POSE mode the client sets the TCP pose (and optionally E1) instead of joints; the
application turns it into joints (IK), guards those like any joint command and sends their pose. Values are taken by
reference (no copy); the application checks them in its guard before sending.
"""

from __future__ import annotations

from typing import Any, Sequence

from .constants import ClientCommandMode
from .errors import FriCommandError
from .state import LBRState

_POSITION_MODES = (ClientCommandMode.POSITION, ClientCommandMode.TORQUE, ClientCommandMode.WRENCH)


class LBRCommand:
    """The command of one cycle; set through the methods, read by the application."""

    def __init__(self, state: LBRState) -> None:
        self._state = state
        self.joint_position: Sequence[float] | None = None  # [rad] 7 values
        self.torque: Sequence[float] | None = None  # [Nm] 7 values (TORQUE mode)
        self.wrench: Sequence[float] | None = None  # fx, fy, fz [N], tx, ty, tz [Nm] (WRENCH mode)
        self.cartesian_pose: Any = None  # 4×4 [m] TCP in the base frame (CARTESIAN_POSE mode)
        self.redundancy: float | None = None  # E1 = A3 [rad] with the pose; None: the ipo E1
        self.io_writes: list[tuple[str, int, float | int]] = []  # (name, FriIOType, value)

    def reset(self) -> None:
        self.joint_position = self.torque = self.wrench = self.cartesian_pose = self.redundancy = None
        if self.io_writes:
            self.io_writes.clear()

    def set_joint_position(self, q: Sequence[float]) -> None:
        """Joint position [rad] to command (7 values)."""
        mode = self._state.message.ipoData.clientCommandMode
        if mode not in _POSITION_MODES:
            raise FriCommandError(
                f"joint positions cannot be commanded in client command mode {ClientCommandMode(mode).name}"
            )
        self.joint_position = q

    def set_torque(self, tau: Sequence[float]) -> None:
        """Joint torques [Nm] added by the controller (TORQUE mode only)."""
        if self._state.message.ipoData.clientCommandMode != ClientCommandMode.TORQUE:
            raise FriCommandError("joint torques can be commanded only in client command mode TORQUE")
        self.torque = tau

    def set_wrench(self, wrench: Sequence[float]) -> None:
        """Cartesian wrench fx, fy, fz [N], tx, ty, tz [Nm] (WRENCH mode only)."""
        if self._state.message.ipoData.clientCommandMode != ClientCommandMode.WRENCH:
            raise FriCommandError("a Cartesian wrench can be commanded only in client command mode WRENCH")
        self.wrench = wrench

    def set_cartesian_pose(self, pose, redundancy: float | None = None) -> None:
        """TCP pose in the base frame to command (CARTESIAN_POSE mode only, FRI 2.7): a 4×4 or 3×4 matrix, its 12
        row-major values (translation [m]) or x, y, z [m], qw, qx, qy, qz; ``redundancy`` E1 = the A3 angle [rad]
        (None: the controller's ipo E1). FriCommandError in another mode or for a malformed pose."""
        if self._state.message.ipoData.clientCommandMode != ClientCommandMode.CARTESIAN_POSE:
            raise FriCommandError("a Cartesian pose can be commanded only in client command mode CARTESIAN_POSE")
        from .cartesian import pose_matrix  # (pinocchio only for clients that use it)

        try:
            self.cartesian_pose = pose_matrix(pose)
        except ValueError as exc:
            raise FriCommandError(f"Cartesian pose: {exc}") from None
        self.redundancy = None if redundancy is None else float(redundancy)

    def _write(self, name: str, kind: int, value: float | int) -> None:
        if not self._state.is_output(name):
            raise FriCommandError(f"IO {name} is an input; only outputs can be written")
        self._state._io(name, kind)  # type check (FriStateError if it is another type)
        self.io_writes.append((name, kind, value))

    def set_boolean_io(self, name: str, value: bool) -> None:
        self._write(name, 0, 1 if value else 0)

    def set_digital_io(self, name: str, value: int) -> None:
        if value < 0:
            raise FriCommandError(f"IO {name}: digital values are unsigned, got {value}")
        self._write(name, 1, int(value))

    def set_analog_io(self, name: str, value: float) -> None:
        self._write(name, 2, float(value))
