"""What the application checks in every monitoring message: is it one a real controller could send, and has the
robot side ended the session (safety stop, drives off, POOR quality, leaving COMMANDING_ACTIVE, a period change)."""

from __future__ import annotations

from typing import Any, Sequence

from .constants import ConnectionQuality, DriveState, SafetyState, SessionState
from .outcome import EndReason, Outcome

IDLE, CMD_WAIT, CMD_ACTIVE = 0, 3, 4
_DRIVE_ACTIVE = int(DriveState.ACTIVE)
_POOR = int(ConnectionQuality.POOR)
POSITION_SLACK = 0.05  # [rad] a reported position beyond the limits by more than this is not a real robot's

End = tuple[Outcome, EndReason, str]


def joints_ok(values: Sequence[float], position_limit: Sequence[float]) -> bool:
    """7 finite joint values [rad] within the position limits (plus a small slack)."""
    if len(values) != 7:
        return False
    for j in range(7):
        x = values[j]
        if not (-position_limit[j] - POSITION_SLACK <= x <= position_limit[j] + POSITION_SLACK):  # also NaN, inf
            return False
    return True


def consistent(mon: Any, position_limit: Sequence[float]) -> bool:
    """A message a real controller could have sent: connection info, 7 finite joint values where the state needs
    them, positions near the limits at most."""
    if not mon.HasField("connectionInfo"):
        return False
    state = mon.connectionInfo.sessionState
    if state == IDLE:
        return True
    if not joints_ok(mon.monitorData.measuredJointPosition.value, position_limit):
        return False
    return state < CMD_WAIT or joints_ok(mon.ipoData.jointPosition.value, position_limit)


def robot_side_end(mon: Any, state: int, *, seen_session: bool, commanding: bool, was_active: bool,
                   period_key: tuple[int, int] | None, waited_s: float, commanding_timeout_s: float | None) -> End | None:
    """Why the robot side ended the session with this message (None: it did not). ``waited_s`` [s] since the
    first message, for ``commanding_timeout_s``."""
    ci = mon.connectionInfo
    ri = mon.robotInfo
    if state == IDLE:
        if seen_session:
            return Outcome.STOPPED, EndReason.IDLE, "the robot application closed the FRI session (IDLE)"
        return None
    if commanding or state >= CMD_WAIT:
        if (ci.sendPeriod, ci.receiveMultiplier or 1) != period_key:
            pk = period_key or (0, 1)
            return (Outcome.STOPPED, EndReason.PERIOD_CHANGED, f"the controller changed its period from {pk[0]} ms × "
                    f"{pk[1]} to {ci.sendPeriod} ms × {ci.receiveMultiplier or 1}")  # fmt: skip
        if ri.safetyState != 0:
            return Outcome.STOPPED, EndReason.SAFETY_STOP, f"safety stop ({SafetyState(ri.safetyState).name})"
        drives = ri.driveState
        if drives and min(drives) != _DRIVE_ACTIVE:
            return Outcome.STOPPED, EndReason.DRIVES_OFF, "drives not active"
        if ci.quality == _POOR:
            return Outcome.STOPPED, EndReason.QUALITY_POOR, "connection quality POOR"
        if was_active and state != CMD_ACTIVE:
            return (Outcome.STOPPED, EndReason.LEFT_COMMANDING,
                    f"the session left COMMANDING_ACTIVE ({SessionState(state).name})")  # fmt: skip
    elif commanding_timeout_s is not None and waited_s > commanding_timeout_s:
        return (Outcome.STOPPED, EndReason.NO_COMMANDING, f"the robot application did not start commanding within "
                f"{commanding_timeout_s:g} s (session state {SessionState(state).name})")  # fmt: skip
    return None
