"""Swing-up and balance of the rigid pendulum (planners.feedback.upright) in the FRI-free closed loop."""

from __future__ import annotations

import math

from dataclasses import replace

import numpy as np
import pytest

from planners.feedback.simulate import Sensor, simulate_upright
from planners.feedback.upright import Mode, UprightOptions, balance_gain, damping_limit
from planners.pendulum import G
from planners.rail import build_rail
from planners.rigid_pendulum import RigidPendulum


@pytest.fixture(scope="module")
def rail(robot, limits):
    from tests.helpers.cli import Q_START

    return build_rail(robot, Q_START, limits, 0.3)


def _from_upright_deg(phi):
    return np.degrees(np.abs(np.angle(np.exp(1j * (phi - np.pi)))))


@pytest.mark.heavy
@pytest.mark.parametrize("rod, delay", [(0.3, 0.010), (0.45, 0.005), (0.75, 0.010)])
def test_swings_up_balances_and_survives_a_ten_degree_push(rail, rod, delay):
    push = 9.0
    run = simulate_upright(
        RigidPendulum(rod_length=rod),
        rail.limits,
        14.0,
        bounds=rail.local_bounds,
        sensor=Sensor(delay=delay),
        pushes=((push, math.radians(-10)),),
    )
    up = _from_upright_deg(run.phi)
    first = int(np.argmax(run.mode == Mode.BALANCE))
    assert 0 < run.t[first] < 6.0
    assert run.falls == 0
    after = run.t > push
    assert up[after].max() > 9.0  # the push happened …
    assert up[after].max() < 30.0 and up[-1000:].max() < 2.0  # … and was caught
    assert np.max(np.abs(run.x)) <= 0.3 + 1e-3


def test_parking_brings_the_cart_home_and_to_rest(rail):
    run = simulate_upright(RigidPendulum(rod_length=0.5), rail.limits, 12.0, bounds=rail.local_bounds, park_at=7.0)
    assert run.mode[-1] == Mode.PARK
    assert abs(run.x[-1]) < 2e-3 and abs(run.v[-1]) < 2e-3


def _with_friction(length: float, share: float) -> tuple[RigidPendulum, float]:
    """A uniform rod whose bearing's dry friction is ``share`` of its peak gravity torque, and that friction as μ
    [rad/s²] (what the identification tells the controller)."""
    rod = RigidPendulum(rod_length=length)
    return replace(rod, coulomb=share * rod.mass * rod.com * G), share * G / rod.equivalent_length


def _settled(run, after: float = 8.0) -> tuple[float, float]:
    """(max |angle from upright| [deg], max |cart x| [m]) from ``after`` s past the first catch."""
    first = int(np.argmax(run.mode == Mode.BALANCE))
    late = run.t > run.t[first] + after
    return float(_from_upright_deg(run.phi)[late].max()), float(np.abs(run.x[late]).max())


@pytest.mark.heavy
@pytest.mark.parametrize("length", [0.4, 0.6])
def test_the_dither_keeps_a_rod_with_dry_friction_from_stick_slip(rail, length):
    # 5 % dry friction: without the dither the balance runs a stick-slip limit cycle of ≈ 4.5° and ±0.25 m (below)
    rod, mu = _with_friction(length, 0.05)
    run = simulate_upright(rod, rail.limits, 22.0, bounds=rail.local_bounds, sensor=Sensor(delay=0.010), friction=mu)
    angle, travel = _settled(run)
    assert run.falls == 0 and angle < 1.2 and travel < 0.02, (angle, travel)


@pytest.mark.heavy
def test_without_the_dither_the_same_rod_sticks_and_slips(rail):
    rod, mu = _with_friction(0.4, 0.05)
    run = simulate_upright(rod, rail.limits, 22.0, bounds=rail.local_bounds, sensor=Sensor(delay=0.010), friction=mu,
                           options=UprightOptions(dither_gain=0.0))  # fmt: skip
    angle, travel = _settled(run)
    assert angle > 3.0 and travel > 0.15, (angle, travel)


@pytest.mark.parametrize("length", [0.27, 0.35, 0.46])
def test_the_damping_limit_is_where_the_balance_loses_stability(length):
    from scipy.linalg import expm

    from planners.feedback.lqr import cart_pendulum

    gain = balance_gain(length)
    limit = damping_limit(length, gain)
    a, b = cart_pendulum(length, True)
    closed = a - b @ np.asarray(gain).reshape(1, 5)
    # another judge: the rod's damping closes a loop around the closed loop's θ̈ → θ̇ response; it goes unstable
    # where that response crosses the negative real axis at −1/c
    w = np.logspace(-1, 2, 20000)
    e = np.zeros(5)
    e[4] = 1.0
    g = np.array([np.linalg.solve(1j * x * np.eye(5) - closed, e)[4] for x in w])
    cross = [i for i in range(len(w) - 1) if g[i].imag * g[i + 1].imag < 0 and g[i].real < 0]
    assert cross and limit == pytest.approx(-1.0 / g[cross[-1]].real, rel=0.01)
    # and in time: the linear closed loop decays with 0.9 × the limit and grows with 1.1 × it
    for share, grows in ((0.9, False), (1.1, True)):
        m = closed.copy()
        m[4, 4] -= share * limit
        z = expm(m * 40.0) @ np.array([0.0, 0.0, 0.0, 0.01, 0.0])
        assert (np.abs(z).max() > 0.01) == grows
