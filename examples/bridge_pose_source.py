"""Drive the robot with TCP-pose targets from another program: the bridge (a TargetFollower on a UDP inbox) runs the
FRI session; a source thread draws a 5 cm circle at 100 Hz with BridgeClient.send_pose and reads the state back.

    python examples/bridge_pose_source.py [--robot IP] [--duration 8]
Against a running `lbr serve`, only source() is needed: that is what a Simulink or MATLAB model sends.
"""

from __future__ import annotations

import math
import threading
import time

import numpy as np
import pinocchio as pin
from _connect import arguments, run

from lbrcli.bridge import BridgeClient, TargetFollower, UdpTargets
from trajectories.limits import default_limits
from trajectories.robot import Robot

Q_START = (0.0, 0.5, 0.0, -1.2, 0.0, 0.8, 0.0)  # [rad]


# --8<-- [start:source]
def source(port: int, seconds: float, log: list) -> None:
    """Stream a horizontal 5 cm circle (orientation kept) for ``seconds``, then end the session."""
    client = BridgeClient("127.0.0.1", port)
    home = Robot().fk(np.array(Q_START))
    x, y, z, w = pin.Quaternion(home.rotation).coeffs()
    t0 = time.monotonic()
    while (t := time.monotonic() - t0) < seconds:
        phi = 2 * math.pi * min(t / (seconds - 1.0), 1.0)  # one turn, then hold for a second
        p = home.translation + 0.05 * np.array([math.cos(phi) - 1, math.sin(phi), 0.0])
        client.send_pose(p, (w, x, y, z), t=t)
        log.append(p)
        time.sleep(0.01)
    state = client.receive_state()  # the bridge answers every cycle: the commanded TCP, measured joints, ...
    log.append(np.array(state.tcp[:3]) if state else None)
    client.end()
    client.close()
    # --8<-- [end:source]


def main(argv=None):
    args = arguments(__doc__.splitlines()[0], duration_s=30.0).parse_args(argv)
    inbox = UdpTargets(0)  # any free port; `lbr serve` listens on 30300
    follower = TargetFollower(inbox, default_limits(), timeout_s=0.2)
    sent: list = []
    threading.Timer(1.0, source, (inbox.port, 6.0, sent)).start()  # the simulator's start takes about a second
    result = run(follower, args, q0=Q_START)
    inbox.close()
    print(f"{result.outcome.value}: {result.detail}; {follower.pose_targets} poses, "
          f"{follower.poses_unreached} not reached")  # fmt: skip
    return result, follower, sent


if __name__ == "__main__":
    main()
