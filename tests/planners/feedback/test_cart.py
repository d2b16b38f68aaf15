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


def _curved_rail_bounds(x: float, v: float, a: float) -> tuple[float, float, float, float, float]:
    """Bounds like a curved rail's (Rail.local_bounds): the joints' jerk q'·j + 3·q''·v·a + q'''·v³ within ±100, so the
    cart's jerk interval shifts with v·a (here q''/q' = −30 /m)."""
    rest = -90.0 * v * a
    return 0.8, -3.5, 3.5, -100.0 - rest, 100.0 - rest


def test_a_state_outside_the_bounds_is_brought_back_not_run_away():
    # a cart whose state was set from outside its governor (coasted onto another part of the rail), its acceleration
    # above the interval while moving: there the rail's jerk interval lies wholly above 0, and following it drove the
    # acceleration up without end (to 1e150 m/s² within 60 cycles, the balance observer after it)
    cart = Cart(LIMITS, 1e-3, bounds=_curved_rail_bounds)
    cart.v, cart.a = 0.7, 4.5
    accs = []
    for _ in range(400):
        cart.track(6.0, 0.02)  # (the controller asks for more still)
        accs.append(cart.a)
    a = np.array(accs)
    assert np.all(np.isfinite(a)) and a.max() <= 4.5 + 1e-9
    assert a[-1] <= 3.5 + 1e-9  # back inside its interval
    out = a > 3.5
    jerk = np.abs(np.diff(np.r_[4.5, a])) / 1e-3
    assert np.max(jerk[out]) <= LIMITS.jerk + 1e-6  # back at the constant jerk bound ...
    assert np.max(jerk) <= 100.0 + 90.0 * 0.8 * 4.5  # ... then within the rail's interval
