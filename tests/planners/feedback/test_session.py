"""The upright session on the fast simulation (planners.feedback.simulate.simulate_session): over the band a lab
meets — rods 20 % off the model, dry friction of 5 % of the gravity torque, encoder noise of 2 counts, a zero
offset, 15 ms of delay — it identifies the rod, balances for the hold without a fall and lowers it to hanging; it
refuses a reversed encoder, ends when no reading comes, and fails honestly when it cannot catch."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planners.feedback.session import SessionOptions
from planners.feedback.simulate import Sensor, simulate_session
from planners.rail import CartLimits
from planners.rigid_pendulum import RigidPendulum

LIM = CartLimits(0.3, 0.8, 3.5, 60.0)
NOMINAL = RigidPendulum(rod_length=0.4)


def _rod(scale: float = 1.0, friction: float = 0.0) -> RigidPendulum:
    r = RigidPendulum(rod_length=0.4 * scale)
    return RigidPendulum(rod_length=0.4 * scale, coulomb=friction * r.mass * r.com * 9.81)


@pytest.mark.heavy
@pytest.mark.parametrize("scale, friction, sensor", [
    (0.8, 0.05, Sensor(noise=2, delay=0.015, offset=-30)), (1.2, 0.05, Sensor(noise=2, delay=0.015, offset=30)),
    (1.0, 0.0, Sensor())])  # fmt: skip
def test_it_balances_for_the_hold_without_a_fall_and_lowers_the_rod(scale, friction, sensor):
    run = simulate_session(_rod(scale, friction), LIM, NOMINAL.equivalent_length, SessionOptions(hold_s=8.0), sensor)
    s = run.session
    assert s.succeeded and s.falls == 0 and s.done, s.figures()
    assert s.rod.equivalent_length == pytest.approx(_rod(scale).equivalent_length, rel=0.02)
    balanced = np.array([p == "balance" for p in run.phase])
    up = np.degrees(np.abs(np.angle(np.exp(1j * (run.phi - np.pi)))))
    assert up[balanced][2000:].max() < 6.0  # the true rod stayed near upright after the catch
    assert abs(math.degrees(run.phi[-1])) < 15.0 and np.all(np.abs(run.x) <= LIM.travel + 1e-9)  # lowered, on the rail


@pytest.mark.heavy
def test_a_push_of_10_degrees_is_recovered():
    run = simulate_session(_rod(), LIM, NOMINAL.equivalent_length, SessionOptions(hold_s=6.0), Sensor(noise=2),
                           pushes=((3.0, math.radians(10)),))  # fmt: skip
    assert run.session.succeeded and run.session.falls == 0


@pytest.mark.heavy
def test_a_reversed_encoder_is_refused_not_guessed():
    run = simulate_session(_rod(), LIM, NOMINAL.equivalent_length, SessionOptions(hold_s=5.0), Sensor(sign=-1))
    s = run.session
    assert not s.succeeded and s.done and "SessionOptions.encoder_sign -1" in s.verdict and s.swing_up_s is None


@pytest.mark.heavy
def test_it_always_ends_and_says_why_it_failed():
    # no reading ever: the wait runs out
    run = simulate_session(_rod(), LIM, NOMINAL.equivalent_length, SessionOptions(wait_s=1.0), Sensor(rate_hz=0.001))
    assert (
        run.session.done
        and not run.session.succeeded
        and "hang still" in run.session.verdict
        or "no reading" in run.session.verdict
    )
    # a cart too weak to swing it up: the swing-up's time runs out, the rod is lowered, the arm parks
    weak = CartLimits(0.3, 0.8, 0.3, 60.0)
    run = simulate_session(_rod(), weak, NOMINAL.equivalent_length, SessionOptions(swing_timeout_s=5.0), Sensor())
    s = run.session
    assert s.done and not s.succeeded and "no catch upright within 5 s" in s.verdict
    assert run.t[-1] < 40.0  # the whole session is bounded


@pytest.mark.heavy
@pytest.mark.parametrize("scale, push, when", [(1.2, 10.0, 6.0), (0.8, -10.0, 7.0)])
def test_with_5_percent_dry_friction_a_push_of_10_degrees_is_recovered_on_the_arms_rail(
    robot, limits, scale, push, when
):
    # the rail's own bounds at its state (as lbr control upright uses them); without the dither both fall once: the
    # stick-slip limit cycle has the cart near an end when the push comes
    from tests.helpers.cli import Q_START
    from planners.rail import build_rail

    rail = build_rail(robot, Q_START, limits, 0.3)
    rod = RigidPendulum(rod_length=0.5 * scale)
    rod = RigidPendulum(rod_length=0.5 * scale, coulomb=0.05 * rod.mass * rod.com * 9.81)
    run = simulate_session(rod, rail.limits, RigidPendulum(rod_length=0.5).equivalent_length, SessionOptions(hold_s=12.0),
                           Sensor(noise=2, delay=0.015, offset=25), pushes=((when, math.radians(push)),),
                           bounds=rail.local_bounds)  # fmt: skip
    s = run.session
    assert s.succeeded and s.falls == 0, s.figures()
    assert np.all(np.abs(run.x) <= rail.limits.travel + 1e-9)


def _default_travel() -> float:
    """``lbr control upright``'s default ``--travel`` [m]."""
    import inspect

    from lbrcli.commands.control import upright

    return float(inspect.signature(upright).parameters["travel"].default)


@pytest.mark.heavy
@pytest.mark.parametrize("travel", [0.3, None])  # None: lbr control upright's default rail
def test_the_bands_last_corner_needs_more_than_a_30_cm_rail_and_the_default_rail_gives_it(robot, limits, travel):
    """The 1.2 × rod with a 20 g tip, 5 % dry friction and 15 ms of delay, knocked by 10°: its recovery runs the cart
    past 0.3 m (on a ±0.3 m rail the governor stops it at the end and the rod falls); the default rail holds it."""
    from tests.helpers.cli import Q_START
    from planners.rail import build_rail

    rail = build_rail(robot, Q_START, limits, travel or _default_travel())
    shape = RigidPendulum(rod_length=0.6, tip_mass=0.02)
    rod = RigidPendulum(rod_length=0.6, tip_mass=0.02, coulomb=0.05 * shape.mass * shape.com * 9.81)
    run = simulate_session(rod, rail.limits, RigidPendulum(rod_length=0.5).equivalent_length, SessionOptions(hold_s=12.0),
                           Sensor(noise=2, delay=0.015, offset=17), pushes=((6.0, math.radians(10.0)),),
                           bounds=rail.local_bounds)  # fmt: skip
    s = run.session
    t_catch = run.t[run.phase.index("balance")]
    after = np.abs(run.x[(run.t > t_catch + 6.0) & (run.t < t_catch + 10.0)]).max()
    assert after > 0.3 - 1e-3  # the knock's recovery needs more than 30 cm of rail
    if travel == 0.3:
        assert s.falls >= 1
    else:
        assert s.succeeded and s.falls == 0, s.figures()
        assert after < 0.95 * rail.limits.travel and np.all(np.abs(run.x) <= rail.limits.travel + 1e-9)
