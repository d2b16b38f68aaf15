"""End to end: the follower in lock step with a controller unlike our simulator (:class:`BurstController`: it holds
missing commands or extrapolates them, applies late replies as they are, in bursts) — every command we send, decoded
from its datagram, keeps the velocity, acceleration and jerk limits as the next step after the history the
controller had executed when it sent the message answered (the held state after a step of its own beyond the limits:
:func:`~lbrcli.fri.testing.holding.command_ratios`). Tolerance: 1e-6 of each limit (rounding of ruckig at the limit).
On the previous code these reached 5× the velocity, ~1,000× the acceleration and ~90,000× the jerk limit."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from lbrcli.bridge.testing import LockStepSource, follow_in_lock_step
from lbrcli.fri.testing import CA, Cycle
from lbrcli.fri.motion import COAST_MAX
from lbrcli.fri.testing.holding import BurstController, command_ratios
from trajectories.limits import default_limits

TOL = 1 + 1e-6


def _bursts(seed: int, start: int = 600, end: int = 2800) -> dict[int, int]:
    """Script index (after the 11-cycle preamble) → lateness: bursts of 5–60 replies each 2–20 periods late."""
    rng = np.random.default_rng(seed)
    late, k = {}, start
    while k < end:
        lateness, n = int(rng.integers(2, 21)), int(rng.integers(5, 60))
        late.update({11 + i: lateness for i in range(k, k + n)})
        k += n + int(rng.integers(100, 400))
    return late


def _within(run, lim) -> tuple[float, float, float]:
    v, a, j = command_ratios(run.controller, lim)
    assert v <= TOL and a <= TOL and j <= TOL, (v, a, j)
    return v, a, j


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
    our path went on), each command keeps every limit against the executed history."""
    lim = default_limits()
    ctl = functools.partial(BurstController, hold=hold, late=_bursts(0))
    run = follow_in_lock_step(LockStepSource(1000.0, True, seed=0), lim, controller=ctl)
    _within(run, lim)
    m = run.follower.executed
    assert m.rebased_cycles > 0 and m.coast_cycles > 0
    assert m.braking or run.t[-1] > 2.9


@pytest.mark.parametrize("hold, lateness", [(True, 1), (False, 2)])
def test_replies_late_for_1400_cycles_in_a_row_are_followed_to_the_end_within_the_limits(hold, lateness):
    """Every reply 1–2 periods late for 1.4 s (a machine too busy to answer in time): the core coasts at most
    ``COAST_MAX`` commands, then the follower re-plans from what the controller executed at each bridge — the session
    goes on to the end, every command within the limits of the executed history (the previous code coasted until
    the motion was 0.05 rad off the path and stopped at 0.7–2.1 s)."""
    lim = default_limits()
    late = {11 + i: lateness for i in range(600, 2000)}
    ctl = functools.partial(BurstController, hold=hold, late=late)
    run = follow_in_lock_step(LockStepSource(1000.0, True, seed=0), lim, controller=ctl)
    _within(run, lim)
    m = run.follower.executed
    assert run.t[-1] > 2.9 and not m.braking
    assert m.rebased_cycles > 1000 and m.coast_cycles <= 2 * COAST_MAX
