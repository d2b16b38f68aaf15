"""The client that only watches (thesis LBRMonitor, KUKA's default client): it never commands motion, and the flange
position it can add to each log row by forward kinematics."""

from __future__ import annotations

from typing import Callable

import numpy as np

from .client import LBRClient
from .constants import Phase
from .state import LBRState

FLANGE_COLUMNS = ("flange_x", "flange_y", "flange_z")  # [m] the flange's position in the base frame


class Watcher(LBRClient):
    """Header-only answers in the monitoring states; holds the ipo position if the robot application starts
    commanding (KUKA's default client)."""

    def command(self, state: LBRState):
        self.phase = Phase.MIRROR
        return super().command(state)


def flange_position(robot) -> Callable[[LBRState], tuple[float, float, float]]:
    """The flange's position [m] (base frame) at the measured joints of a state, by ``robot``'s (trajectories.robot
    .Robot) forward kinematics — the values of :data:`FLANGE_COLUMNS`."""
    import pinocchio as pin

    from trajectories.robot import FLANGE_FRAME

    fid = robot.model.getFrameId(FLANGE_FRAME)
    mdl, data = robot.model, robot.data
    qbuf = np.zeros(7)

    def position(state: LBRState) -> tuple[float, float, float]:
        qbuf[:] = state.message.monitorData.measuredJointPosition.value
        pin.framesForwardKinematics(mdl, data, qbuf)
        p = data.oMf[fid].translation
        return (p[0], p[1], p[2])

    return position
