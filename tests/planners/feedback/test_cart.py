"""The jerk-driven cart (planners.feedback.cart): whatever is asked, it stays within its bounds."""

from __future__ import annotations

import numpy as np
import pytest

from planners.feedback import Cart
from planners.rail import CartLimits

LIMITS = CartLimits(travel=0.3, velocity=0.8, acceleration=3.5, jerk=30.0)


def test_wild_requests_never_leave_the_bounds():
    rng = np.random.default_rng(0)
    cart = Cart(LIMITS, 1e-3)
    xs, vs, accs = [], [], []
    for k in range(20000):
        jerk = rng.choice([-1e4, 1e4, 0.0]) if k % 500 < 250 else 1e4  # bang-bang, then pushing one way
        cart.step(jerk)
        xs.append(cart.x), vs.append(cart.v), accs.append(cart.a)
    a = np.array(accs)
    assert np.max(np.abs(xs)) <= LIMITS.travel + 1e-3
    assert np.max(np.abs(vs)) <= LIMITS.velocity * 1.01
    assert np.max(np.abs(a)) <= LIMITS.acceleration + 1e-9
    assert np.max(np.abs(np.diff(a))) / 1e-3 <= LIMITS.jerk + 1e-6
    assert cart.trimmed > 0


def test_a_reachable_request_is_followed_exactly():
    cart = Cart(LIMITS, 1e-3)
    for _ in range(100):
        cart.step(10.0)
    assert cart.trimmed == 0 and cart.a == pytest.approx(1.0) and cart.v == pytest.approx(0.05, rel=1e-3)
    assert cart.x == pytest.approx(10.0 * 0.1**3 / 6, rel=1e-3)


def test_tracking_an_acceleration_and_back_to_rest():
    cart = Cart(LIMITS, 1e-3)
    for _ in range(300):
        cart.track(2.0, 0.02)
    assert cart.a == pytest.approx(2.0, abs=0.05)
    for _ in range(6000):
        cart.track(-4.0 * cart.x - 3.0 * cart.v, 0.03)
    assert abs(cart.x) < 5e-3 and abs(cart.v) < 5e-3
