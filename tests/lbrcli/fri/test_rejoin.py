"""Rejoin: the offset back onto the client's path after a bridged command decays to zero within the limits."""

from __future__ import annotations

import numpy as np

from lbrcli.fri.rejoin import Rejoin
from trajectories.limits import default_limits


def test_the_offset_of_a_bridged_command_comes_to_rest_at_zero_continuing_its_history_within_the_limits():
    """The offset a bridge leaves (the executed acceleration 0 where the client's path accelerates at 90 % of each
    joint's limit): sampled once per period it continues its own history within the velocity, acceleration and
    jerk limits and ends at zero, at rest."""
    lim, dt = default_limits(), 1e-3
    a = 0.9 * lim.acceleration * np.array([1, -1, 1, -1, 1, -1, 1])  # [rad/s²] the client's path at the bridge
    history = [np.zeros(7), np.zeros(7), -a * dt * dt]  # oldest first: the bridge held the velocity
    r = Rejoin(lim, dt)
    r.start(history[2], history[1], history[0])
    assert not r.done
    e = history + [np.array(r.next())]
    while not r.done:
        e.append(np.array(r.next()))
        assert len(e) < 2000
    e = np.array(e)
    v = np.diff(e, axis=0) / dt
    acc = np.diff(v, axis=0) / dt
    jerk = np.diff(acc, axis=0) / dt
    assert np.all(np.abs(v) <= lim.velocity) and np.all(np.abs(acc[1:]) <= lim.acceleration * (1 + 1e-9))
    assert np.all(np.abs(jerk[1:]) <= lim.jerk * (1 + 1e-6))  # (jerk[0]: the bridge's own step)
    assert np.abs(e[-1]).max() < 1e-12 and np.abs(e[-1] - e[-2]).max() < 1e-7  # (ruckig's last sample)
    assert r.next() == (0.0,) * 7


def test_no_offset_needs_no_rejoin():
    r = Rejoin(default_limits(), 1e-3)
    r.start((0.0,) * 7, (0.0,) * 7, (0.0,) * 7)
    assert r.done and r.next() == (0.0,) * 7 and r.failed == 0
