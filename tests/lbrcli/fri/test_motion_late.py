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

import pytest

from lbrcli.bridge.testing import LockStepSource, follow_in_lock_step
from lbrcli.fri.testing import CA, Cycle
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
