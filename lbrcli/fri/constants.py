"""FRI protocol constants shared by the client and the simulator (values from shared/facts/fri.md)."""

from __future__ import annotations

from enum import IntEnum

MONITORING_MESSAGE_ID = 0x245142
COMMAND_MESSAGE_ID = 0x34001
DEFAULT_PORT = 30200
"""The UDP port FRI uses unless the robot application configures another (KUKA's default)."""
MAX_DATAGRAM = 1500  # [bytes], each way
N_JOINTS = 7


class SessionState(IntEnum):
    """The FRI session state the controller reports in every monitoring message."""

    IDLE = 0
    MONITORING_WAIT = 1
    MONITORING_READY = 2
    COMMANDING_WAIT = 3
    COMMANDING_ACTIVE = 4


# The session states as plain ints, for the per-cycle comparisons with a decoded message's field (an IntEnum's
# comparison costs a method call): the one definition every module imports.
STATE_IDLE = int(SessionState.IDLE)
STATE_MONITORING_WAIT = int(SessionState.MONITORING_WAIT)
STATE_MONITORING_READY = int(SessionState.MONITORING_READY)
STATE_COMMANDING_WAIT = int(SessionState.COMMANDING_WAIT)
STATE_COMMANDING_ACTIVE = int(SessionState.COMMANDING_ACTIVE)


class ConnectionQuality(IntEnum):
    """The controller's verdict on the connection (share of timely replies); below GOOD it leaves commanding."""

    POOR = 0
    FAIR = 1
    GOOD = 2
    EXCELLENT = 3


class SafetyState(IntEnum):
    """The robot's safety state; any stop level ends a commanding session."""

    NORMAL_OPERATION = 0
    SAFETY_STOP_LEVEL_0 = 1
    SAFETY_STOP_LEVEL_1 = 2
    SAFETY_STOP_LEVEL_2 = 3


class OperationMode(IntEnum):
    """The robot's operation mode: T1 (flange at most 250 mm/s), T2 or automatic."""

    TEST_MODE_1 = 0
    TEST_MODE_2 = 1
    AUTOMATIC_MODE = 2


class DriveState(IntEnum):
    """The state of the joint drives; commanding needs ACTIVE."""

    OFF = 0
    TRANSITIONING = 1
    ACTIVE = 2


class ControlMode(IntEnum):
    """The controller's control mode under the FRI overlay (position, joint or Cartesian impedance)."""

    POSITION_CONTROLMODE = 0
    CARTESIAN_IMPEDANCE_CONTROLMODE = 1
    JOINT_IMPEDANCE_CONTROLMODE = 2
    NO_CONTROLMODE = 3


class ClientCommandMode(IntEnum):
    """What the client's replies command: joint positions [rad], wrench [N, Nm], torques [Nm] or a Cartesian pose."""

    NO_COMMAND_MODE = 0
    POSITION = 1  # JOINT_POSITION in 2.x
    WRENCH = 2
    TORQUE = 3
    CARTESIAN_POSE = 4  # 2.x only


class OverlayType(IntEnum):
    """The FRI overlay the robot application opened: none, joint or Cartesian."""

    NO_OVERLAY = 0
    JOINT = 1
    CARTESIAN = 2


class Phase(IntEnum):
    """What a cycle's command was (the log's ``phase`` column)."""

    NONE = 0  # not commanding (monitoring states, the mirror in COMMANDING_WAIT)
    MOVE = 1  # jerk-limited move to the start
    TRAJECTORY = 2  # the file's rows
    SETTLE = 3  # holding the last row
    BRAKE = 4  # the application's braking stop (Ctrl-C, a guard refusal, the end of the stream)
    MIRROR = 5  # COMMANDING_ACTIVE without motion (monitor): the ipo position held
    WAIT = 6  # holding the first row until the ball's (pendulum's) sway has decayed
