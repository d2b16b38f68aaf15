"""End to end: the follower in lock step with a controller unlike our simulator (:class:`BurstController`: it holds
missing commands or extrapolates them, applies late replies as they are, in bursts) — every command we send, decoded
from its datagram, keeps the velocity, acceleration and jerk limits as the next step after the history the
controller had executed when it sent the message answered, or, where it applied our replies one after the other,
late, when it applied it (the held state after a step of its own beyond the limits:
:func:`~lbrcli.fri.testing.holding.reply_ratios`). Tolerance: 1e-6 of each limit (rounding of ruckig at the limit).
On the previous code these reached 5× the velocity, ~1,000× the acceleration and ~90,000× the jerk limit; where
replies queued, 57–264× the acceleration limit all along the late stretch."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from tests.helpers.fri_session import Q0, preamble, run, sent_positions

from lbrcli.bridge.testing import LockStepSource, follow_in_lock_step
from lbrcli.fri.testing import CA, Cycle
from lbrcli.fri import Outcome, TrajectoryPlayer
from lbrcli.fri.motion import COAST_MAX
from lbrcli.fri.testing.holding import (
    AROUND_CHANGE,
    BurstController,
    command_ratios,
    executed_ratios,
    late_bursts,
    over_limits,
)
from trajectories.limits import default_limits

TOL = 1 + 1e-6


def _within(run, lim) -> tuple[float, float, float]:
    v, a, j = command_ratios(run.controller, lim)
    assert v <= TOL and a <= TOL and j <= TOL, (v, a, j)
    return v, a, j


def _within_but_at_changes(run, lim, late: dict[int, int]) -> int:
    """Every reply the controller applied keeps the limits as the robot executed it but those answering the messages
    around a change of lateness (:func:`~lbrcli.fri.testing.holding.over_limits`); how many of those broke one. The
    core before the fix: 1,394–1,400 replies over the limits, all along a constant lateness of 1–5 periods."""
    over, stray = over_limits(run.controller, lim, late)
    assert not stray, [(s, row.round(2)) for s, row in stray[:5]]
    return len(over)


@pytest.mark.parametrize("hold", [True, False])
def test_30_lost_monitoring_messages_our_next_commands_start_from_what_the_controller_held(hold):
    """30 monitoring messages lost mid-motion (the wave at 0.47 rad/s): a controller that held the robot or one that
    extrapolated; the motion goes on to the end without a stop (the previous code: 89,149× the jerk limit after a
    hold)."""
    lim = default_limits()
    ctl = functools.partial(BurstController, hold=hold)
    run = follow_in_lock_step(LockStepSource(1000.0, True, seed=0), lim, controller=ctl,
                              at={1200: Cycle(state=CA, seq_jump=30)})  # fmt: skip
    _within(run, lim)
    m = run.follower.executed
    assert run.t[-1] > 2.9 and not m.braking and m.extrapolated_cycles == 30
    assert (m.rebased_cycles == 1) == hold  # (the extrapolation foresaw where the extrapolating one went)


@pytest.mark.parametrize("hold", [True, False])
def test_late_bursts_of_replies_keep_every_command_within_the_limits_of_what_was_executed(hold):
    """Bursts of 2–20 periods late replies, applied as they are (older ones dropped when a newer is in): whether the
    session follows on (extrapolating controller) or ends with a braking stop (one that holds: it stood still while
    our path went on), each command keeps every limit against the executed history — but the few around a change of
    lateness, which no client can foresee (the old core: 136–171 over, all along each burst)."""
    lim = default_limits()
    ctl = functools.partial(BurstController, hold=hold, late=late_bursts(0))
    run = follow_in_lock_step(LockStepSource(1000.0, True, seed=0), lim, controller=ctl)
    _within_but_at_changes(run, lim, late_bursts(0))
    m = run.follower.executed
    assert m.rebased_cycles > 0 and m.coast_cycles > 0
    assert m.braking or run.t[-1] > 2.9


@pytest.mark.parametrize("hold, lateness, version, noise", [(True, 1, "1.15", 0.0), (False, 2, "1.15", 0.0),
                                                         (False, 5, "2.7", 1e-5)])  # fmt: skip
def test_replies_late_for_1400_cycles_in_a_row_are_followed_to_the_end_within_the_limits(hold, lateness, version,
                                                                                        noise):  # fmt: skip
    """Every reply 1–5 periods late for 1.4 s (a machine too busy to answer in time, or a link that buffers), applied
    by the controller in order: each message reports the position of our reply after the one the previous message
    reflected, exactly (FRI 1.15's commanded position) or measured with 10 µrad of noise (FRI 2.7). The core keeps its
    own history (the old one re-based on each message: every next command jumped from those in flight, 57–264× the
    acceleration limit as executed); the session goes on to the end, every command within the limits as the robot
    executed it but at the stretch's start and end."""
    lim = default_limits()
    late = {11 + i: lateness for i in range(600, 2000)}
    ctl = functools.partial(BurstController, hold=hold, late=late, noise=noise)
    run = follow_in_lock_step(LockStepSource(1000.0, True, seed=0), lim, controller=ctl, version=version)
    assert _within_but_at_changes(run, lim, late) <= 2 * (AROUND_CHANGE[1] - AROUND_CHANGE[0] + lateness)
    m = run.follower.executed
    assert run.t[-1] > 2.9 and not m.braking
    assert m.rebased_cycles <= lateness + 2 and m.coast_cycles <= 2 * COAST_MAX  # (the old core: > 1,000 re-bases;
    # here: the messages of the entry, while the controller held or bridged)


@pytest.mark.parametrize("hold, lateness", [(False, 1), (True, 3)])
def test_late_replies_carried_forward_by_the_controller_do_not_feed_back(hold, lateness):
    """A controller that carries a late reply forward by its lateness at our commands' velocity (as `lbr sim` does),
    every reply 1–3 periods late for 1.4 s: the message reports our command carried forward, the core recognises it
    as ours (no re-base). The old core re-based on it; the next command jumped by the carry, the controller carried the
    jump forward — a loop that diverged within 20 ms (4,756× the velocity limit as executed, the session lost at
    0.63 s). Executed velocity and acceleration within the limits away from the stretch's ends; jerk within
    1 + 2 × lateness of it (the carry adds lateness × our commands' fourth difference)."""
    lim = default_limits()
    late = {11 + i: lateness for i in range(600, 2000)}
    ctl = functools.partial(BurstController, hold=hold, late=late, carry=True)
    run = follow_in_lock_step(LockStepSource(1000.0, True, seed=0), lim, controller=ctl)
    v, a, j = executed_ratios(run.controller, lim, late)
    assert run.t[-1] > 2.9 and v <= TOL and a <= TOL and j <= 1 + 2 * lateness, (run.t[-1], v, a, j)


@pytest.mark.parametrize("version", ["1.15", "2.7"])
def test_measured_positions_with_10_urad_of_noise_neither_refuse_the_start_nor_break_a_limit(version):
    """Measured positions with 10 µrad of noise (σ; the ipo and FRI 1.15's commanded positions exact): the old core
    judged the COMMANDING_WAIT mirror of the ipo position from the measured one — noise of 10 µrad in one 1 ms period
    is 10 rad/s², over the acceleration limit — and refused the session at its 9th message. The whole 3 s motion runs,
    every command within the limits of what the controller executed."""
    lim = default_limits()
    ctl = functools.partial(BurstController, hold=False, noise=1e-5, seed=3)
    run = follow_in_lock_step(LockStepSource(1000.0, True, seed=0), lim, controller=ctl, version=version)
    assert len(run.t) and run.t[-1] > 2.9 and not run.follower.executed.braking
    _within(run, lim)


def _over_the_jerk_limit(dt: float = 5e-3, moves: int = 4) -> np.ndarray:
    """(n, 7) [rad] rows ``dt`` apart from Q0: rest-to-rest moves, back and forth, whose acceleration reaches 0.13–0.6
    of each joint's limit along ramps at 1.6× its jerk limit (a file's jerk is not enforced: ``lbr check`` notes it)."""
    lim = default_limits()
    share = np.array([0.3, 0.45, 0.25, 0.6, 0.13, 0.2, 0.2])
    top, slope = share * lim.acceleration, 1.6 * lim.jerk  # [rad/s²], [rad/s³]
    ramp = int(np.ceil(np.max(top / slope) / dt))
    up = np.minimum(np.arange(1, ramp + 1)[:, None] * dt * slope, top)  # (the ramp to the top, then held)
    lobe = np.vstack([up, np.repeat(top[None], 20, 0), up[::-1]])
    acc = np.vstack([np.zeros((20, 7))] + [s * np.vstack([lobe, -lobe]) for s in (1, -1) * (moves // 2)]
                    + [np.zeros((40, 7))])  # fmt: skip
    q = np.empty((len(acc) + 1, 7))
    q[0] = q[1] = Q0
    for k in range(1, len(acc)):
        q[k + 1] = 2.0 * q[k] - q[k - 1] + acc[k] * dt * dt
    return q


@pytest.mark.parametrize("row, periods, carry", [(40, 4, False), (110, 4, True), (150, 4, False), (200, 2, False)])
def test_a_late_burst_at_5_ms_in_a_file_beyond_the_jerk_limit_is_followed_back_onto_its_rows(row, periods, carry):
    """A file at 5 ms whose own jerk is 1.6× the limit (not enforced for files), the replies to ``periods`` messages
    from ``row`` late (the client stalled for that long; the controller extrapolates, or carries the late replies
    forward as `lbr sim` does): the core's offset back onto the rows ends, the file is sent to its last row exactly,
    every command within the velocity and acceleration limits of what was executed. The core before held the sum of
    rows and offset to the jerk limit the rows themselves break: each clamp bent the path against the offset's plan
    and re-planned it from there; the offset grew to 0.05 rad and the session ended with a braking stop (13 of 24
    stall positions 10 rows apart along this file; now none — with 8 periods, 7 of 12: see the note on the band)."""
    lim = default_limits()
    traj = _over_the_jerk_limit()
    start = len(preamble())
    late = {start + row + i: periods - i for i in range(periods)}
    script = preamble(send_period=5) + [Cycle(state=CA, send_period=5)] * (len(traj) + 40)
    seen = []
    res, ctl, _, err = run(script, TrajectoryPlayer(traj, lim, period_s=5e-3), controller_type=BurstController,
                           on_cycle=lambda i, app: seen.append(app), tolerate_unanswered=10**6, hold=False, late=late,
                           carry=carry)  # fmt: skip
    assert err is None and res.outcome is Outcome.COMPLETED, res.detail
    m = seen[-1]._motion
    assert m.rebased_cycles > 0 and m.rejoin.done and m.rejoin_cycles > 0
    sent = sent_positions(ctl)
    np.testing.assert_array_equal(sent[len(traj) - 1], traj[-1])
    v, a, _ = command_ratios(ctl, lim, 5e-3)
    assert v <= TOL and a <= TOL, (v, a)
