"""ExecutedMotion: the history the guard judges against, continued over lost messages as the controller does."""

from __future__ import annotations

import numpy as np
import pytest

from lbrcli.fri.motion import ExecutedMotion
from trajectories.limits import default_limits

ACTIVE, POSITION = 4, 1


@pytest.mark.parametrize("lost_after, lost", [(1, 1), (3, 2), (10, 1), (25, 4)])
def test_a_braking_stop_interrupted_by_lost_messages_goes_on_within_the_limits(lost_after, lost):
    lim, dt = default_limits(), 0.001
    m = ExecutedMotion(lim, dt, 1e9, 1e9, hold_cycles=2, q=(0.0,) * 7)
    v = 0.8 * lim.velocity  # [rad/s] cruising at 80 % of every joint's limit
    sent = [np.zeros(7)]
    for k in range(1, 400):  # accelerate within the limits, then cruise
        speed = np.minimum(v, 0.5 * lim.acceleration * k * dt)
        q = tuple(sent[-1] + speed * dt)
        cmd, *_, why = m.next_command(q, ACTIVE, POSITION, q, None, None)
        assert why is None
        m.sent(cmd, ACTIVE)
        sent.append(np.array(cmd))
    m.begin_braking()
    for k in range(400):
        if k == lost_after:  # the controller's messages were lost: it extrapolated our last commands
            m.extrapolate(lost)
            for _ in range(lost):  # at the last commands' velocity
                sent.append(2 * sent[-1] - sent[-2])
            assert np.allclose(m.prev, sent[-1])
        cmd, *_, why = m.next_command(sent[-1], ACTIVE, POSITION, sent[-1], None, None)  # the brake replaces it
        assert why is None
        m.sent(cmd, ACTIVE)
        sent.append(np.array(cmd))
        if m.brake.done:
            break
    assert m.brake.done
    q = np.array(sent)
    assert np.all(np.abs(np.diff(q, axis=0)) / dt <= lim.velocity * (1 + 1e-9))
    assert np.all(np.abs(np.diff(q, 2, axis=0)) / dt**2 <= lim.acceleration * (1 + 1e-6))
    assert np.allclose(q[-1], q[-2], atol=1e-12)  # at rest
