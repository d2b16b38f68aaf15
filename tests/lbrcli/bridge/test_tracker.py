"""The reference tracker's hold: at rest it stays without planning; moving, it stops as ruckig plans the stop."""

from __future__ import annotations

import numpy as np

from lbrcli.bridge.tracker import ReferenceTracker
from trajectories.limits import default_limits

LIM = default_limits()
Q0 = np.array([0.1, 0.5, -0.2, -1.2, 0.3, 0.4, -0.1])  # [rad]


def test_hold_at_rest_stays_put_and_counts_the_cycle_on_the_reference() -> None:
    tr = ReferenceTracker(LIM, 1e-3, Q0)
    for _ in range(3):
        q = tr.hold()
    np.testing.assert_array_equal(q, Q0)
    assert not tr.v.any() and not tr.a.any() and tr.on_reference == 3 and tr.intercept_s == 1e-3


def test_hold_while_moving_is_the_planned_stop_at_the_held_position() -> None:
    v = 0.3 * np.asarray(LIM.velocity)  # [rad/s] moving, no acceleration
    a, b = ReferenceTracker(LIM, 1e-3, Q0), ReferenceTracker(LIM, 1e-3, Q0)
    a.reset(Q0, v, np.zeros(7))
    b.reset(Q0, v, np.zeros(7))
    for _ in range(200):  # against the same reference through step: the commanded state at rest where it stopped
        q_hold = a.hold()
        here = b.q.copy()
        q_step = b.step(lambda t: (here, np.zeros(7), np.zeros(7)))
        np.testing.assert_allclose(q_hold, q_step, rtol=0, atol=1e-12)
    assert np.all(np.abs(a.q - Q0) > 0) and not np.abs(a.v).max() > 1e-9  # it went on and came to rest
    assert a.catching_up > 0
