"""The bridge tests' judge: the commands within a share of the limits while following, the full limits braking."""

from __future__ import annotations

import numpy as np
from lbrcli.fri.log import PHASE_BRAKE
from trajectories.limits import default_limits


LIM = default_limits()


# -- the bridge on the simulator ----------------------------------------------------------------------------------
PERIOD_S = 0.004  # [s] the embedded simulator's send period in these real-time tests; the bridge's 1 ms behaviour is
# tested in lock step (test_bridge_timeline.py). The simulator keeps its period's grid but waits for each reply
# (--sim-lockstep): on a machine busy with other work its connection-quality rule would otherwise drop the session
# for late replies — a timing question, which the benchmarks answer


def limit_ratios(tab, dt=PERIOD_S, following_only=False) -> tuple[float, float, float]:
    """Largest step / velocity limit, second difference / acceleration limit, third / jerk limit of the commands the
    bridge sent in COMMANDING_ACTIVE (with ``following_only`` before the braking stop). The commands, not what the
    simulator executed: on a loaded machine some replies reach it late, and what it makes of those (it holds, then
    takes the late one) is its own, not the bridge's. A client that fell behind answers the newest message and skips
    the ones before it (the log has a row per message answered): a step then spans as many periods as the controller's
    sequence counter moved, and the differences of higher order are judged only over consecutive messages. A step
    after a reply the controller did not get in time (the next message reflects an older reply) is not judged: the
    controller bridged that period, and the safety core holds the next command to what it executed, not to the
    command we sent before (the core's tests judge that in lock step: test_motion_late.py, test_rejoin.py)."""
    keep = tab.column("state") == 4
    if following_only:
        keep &= np.cumsum(tab.column("phase") == PHASE_BRAKE) == 0
    q = np.column_stack([tab.column(f"cmd_q{j}") for j in range(1, 8)])[keep]
    gap = np.diff(tab.column("seq")[keep])  # [periods] between the messages of consecutive rows
    # the controller had our previous reply when it sent the next message
    taken = tab.column("reflected_seq")[keep][1:] == tab.column("client_seq")[keep][:-1]
    assert taken.mean() >= 0.5 if len(taken) else True, f"only {taken.mean():.0%} of the steps could be judged"
    out = []
    for k, lim in ((1, LIM.velocity), (2, LIM.acceleration), (3, LIM.jerk)):
        d = np.diff(q, k, axis=0)
        if k == 1:
            d = (d / np.maximum(gap, 1)[:, None])[taken]
        else:  # only where the k steps are one period each
            whole = np.convolve(gap != 1, np.ones(k), "valid") == 0
            d = d[whole]
        out.append(float((np.abs(d) / dt**k / lim).max()) if len(d) else 0.0)
    return tuple(out)


def judge_following(tab, f: dict, scale: float = 0.5) -> None:
    """The commands within ``scale`` of the limits while following and within the full limits in the braking stop;
    after replies that reached the controller late (a busy machine) the safety core's clamps may use the full
    limits, and after a command the controller bridged what we send next suits what it executed, not the commands
    we sent: the acceleration and jerk are then judged in lock step instead (test_timeline.py, test_motion.py)."""
    v, a, j = limit_ratios(tab, following_only=True)
    clean = f["lost_replies"] == 0 and f["clamped_cycles"] == 0
    step = f["largest_clamp_rad"] / (PERIOD_S * float(np.min(LIM.velocity)))  # a clamp's share of one step
    assert v <= scale + step + 1e-6 and (a <= (scale if clean else 1.0) + 1e-6 or f["lost_replies"]), (v, a, f)
    assert j <= scale + 1e-6 or not clean, (j, f)
    v, a, j = limit_ratios(tab)
    assert v <= scale + step + 1e-6 and (a <= 1.0 + 1e-6 or f["lost_replies"]) and (j <= 1.0 + 1e-6 or not clean), (
        v,
        a,
        j,
        f,
    )
