"""Swing-up and balance of the rigid pendulum (planners.feedback.upright) in the FRI-free closed loop."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planners.feedback.simulate import Sensor, simulate_upright
from planners.feedback.upright import Mode
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
