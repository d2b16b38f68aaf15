"""A pure-Python client for KUKA's Fast Robot Interface (FRI 1.15 and 2.7), shaped like KUKA's client SDK.

Write a client by subclassing :class:`LBRClient` and run it with :class:`ClientApplication`::

    from lbrcli.fri import ClientApplication, LBRClient

    class Sine(LBRClient):
        def command(self, state):
            q = list(state.ipo_joint_position)
            q[3] += 0.04 * math.sin(...)
            self.robot_command.set_joint_position(q)

    with ClientApplication(Sine(), robot="192.170.10.2", port=30200) as app:
        result = app.run()

FRI 2.7: ``LBRCommand.set_cartesian_pose`` in CARTESIAN_POSE mode, :class:`TransformationClient` for the frames a
robot application requests (docs/guides/fri-2.7-cartesian.md). The application owns the loop: transport, counters, the per-cycle guard, the braking stop and the observers
(log, figures). The simulator is in :mod:`lbrcli.fri.sim`.
"""

from .application import ClientApplication
from .braking import BrakingStop
from .client import LBRClient
from .codec import FriCodec, detect_version
from .command import LBRCommand
from .cycle import Cycle, Observer
from .constants import (
    DEFAULT_PORT,
    ClientCommandMode,
    ConnectionQuality,
    ControlMode,
    DriveState,
    OperationMode,
    OverlayType,
    Phase,
    SafetyState,
    SessionState,
)
from .errors import FriCommandError, FriDecodeError, FriError, FriStateError, FriTimeout, StopSession
from .guard import CommandGuard
from .log import ExecutionLog, LogObserver
from .logwriter import LogProcess
from .messages import FriVersion
from .observers import SessionFigures
from .outcome import EndReason, Outcome, SessionResult
from .players import OnlineMove, TrajectoryPlayer
from .signals import interrupts_brake
from .state import LBRState
from .transformation import TransformationClient

__all__ = [
    "BrakingStop",
    "ClientApplication",
    "ClientCommandMode",
    "CommandGuard",
    "ConnectionQuality",
    "ControlMode",
    "Cycle",
    "DEFAULT_PORT",
    "DriveState",
    "EndReason",
    "ExecutionLog",
    "FriCodec",
    "FriCommandError",
    "FriDecodeError",
    "FriError",
    "FriStateError",
    "FriTimeout",
    "FriVersion",
    "LBRClient",
    "LBRCommand",
    "LBRState",
    "LogObserver",
    "LogProcess",
    "Observer",
    "OnlineMove",
    "OperationMode",
    "Outcome",
    "OverlayType",
    "Phase",
    "SafetyState",
    "SessionFigures",
    "SessionResult",
    "SessionState",
    "StopSession",
    "TrajectoryPlayer",
    "TransformationClient",
    "detect_version",
    "interrupts_brake",
]
