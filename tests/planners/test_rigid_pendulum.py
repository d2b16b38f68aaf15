"""The rigid pendulum model (planners.rigid_pendulum): geometry, free swing, energy and the pivot's push."""

from __future__ import annotations

import math

import pytest

from planners.pendulum import G
from planners.rigid_pendulum import RigidPendulum, rk4_step, swing_energy, wrap_angle


def test_uniform_rod_has_two_thirds_of_its_length_as_equivalent_length():
    p = RigidPendulum(rod_length=0.6, rod_mass=0.2)
    assert p.com == pytest.approx(0.3) and p.inertia == pytest.approx(0.2 * 0.36 / 3)
    assert p.equivalent_length == pytest.approx(0.4)
    assert p.natural_period == pytest.approx(2 * math.pi * math.sqrt(0.4 / G))
    tip = RigidPendulum(rod_length=0.6, rod_mass=0.0, tip_mass=1.0)
    assert tip.equivalent_length == pytest.approx(0.6)  # a point mass: the ball's length


@pytest.mark.parametrize("bad", [dict(rod_length=0.0), dict(rod_mass=0.0, tip_mass=0.0), dict(viscous=-1.0)])
def test_bad_parameters_are_refused(bad):
    with pytest.raises(ValueError):
        RigidPendulum(**bad).validate()


def test_free_swing_keeps_its_energy_and_period():
    p = RigidPendulum(rod_length=0.5, viscous=0.0, coulomb=0.0)
    l = p.equivalent_length
    phi, omega, h = 0.05, 0.0, 1e-3
    e0 = swing_energy(phi, omega, l)
    crossings = []
    for k in range(3000):
        prev = phi
        phi, omega = rk4_step(p, phi, omega, (0.0, 0.0), (0.0, 0.0), h)
        if prev > 0 >= phi:
            crossings.append(k * h)
    assert swing_energy(phi, omega, l) == pytest.approx(e0, rel=1e-8)
    assert crossings[1] - crossings[0] == pytest.approx(p.natural_period, rel=2e-3)


def test_pivot_acceleration_swings_the_rod_backwards_and_friction_drains_it():
    p = RigidPendulum(rod_length=0.5)
    phi, omega = 0.0, 0.0
    for _ in range(100):  # 0.1 s at 2 m/s² toward +e
        phi, omega = rk4_step(p, phi, omega, (2.0, 0.0), (2.0, 0.0), 1e-3)
    assert phi < -0.01 and omega < 0
    # an upward pivot acceleration is heavier gravity: a faster swing
    assert abs(p.angular_acceleration(0.1, 0.0, 0.0, 5.0)) > abs(p.angular_acceleration(0.1, 0.0, 0.0, 0.0))
    e0 = swing_energy(1.0, 0.0, p.equivalent_length)
    phi, omega = 1.0, 0.0
    for _ in range(5000):
        phi, omega = rk4_step(p, phi, omega, (0.0, 0.0), (0.0, 0.0), 1e-3)
    assert swing_energy(phi, omega, p.equivalent_length) < e0 - 0.01


def test_wrap_angle():
    assert wrap_angle(math.pi) == pytest.approx(math.pi)
    assert wrap_angle(-math.pi) == pytest.approx(math.pi)
    assert wrap_angle(3 * math.pi / 2) == pytest.approx(-math.pi / 2)
    assert wrap_angle(0.3 - 4 * math.pi) == pytest.approx(0.3)
