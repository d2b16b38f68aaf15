"""Tension condition (thesis 5.9, m ≪ M form) on hand-computed states, against the spherical model."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from planners import pendulum
from planners.cartpole import rhs
from planners.tension import apex_acceleration_to_stay_taut, fixed_pivot_slack_angle, slack_report, tension_margin


@pytest.mark.parametrize(
    "theta_deg,theta_dot,acc_h,acc_v,length,expected",
    [
        (0.0, 0.0, 0.0, 0.0, 0.25, 9.81),  # hanging at rest: T/m = g
        (90.0, 2.0, 0.0, 0.0, 0.25, 1.0),  # horizontal: only the centripetal term l·θ̇² = 0.25·4
        (90.0, 0.0, -3.0, 0.0, 0.25, 3.0),  # horizontal at rest, pivot pulling away at 3 m/s²
        (60.0, 1.0, 3.0, 2.0, 0.5, 0.5 + 11.81 * 0.5 - 3.0 * math.sqrt(3) / 2),
        (115.0, 0.0, 0.0, 0.0, 0.25, 9.81 * math.cos(math.radians(115))),  # apex above 90°: slack (−4.146)
        (115.0, 0.0, -5.0, 0.0, 0.25, 9.81 * math.cos(math.radians(115)) + 5.0 * math.sin(math.radians(115))),
        (-115.0, 0.0, 5.0, 0.0, 0.25, 9.81 * math.cos(math.radians(115)) + 5.0 * math.sin(math.radians(115))),
    ],
)
def test_hand_computed_states(theta_deg, theta_dot, acc_h, acc_v, length, expected):
    m = tension_margin(math.radians(theta_deg), theta_dot, acc_h, acc_v, length)
    assert float(m) == pytest.approx(expected, abs=1e-12)


def test_sign_conventions_match_the_spherical_model():
    rng = np.random.default_rng(4)
    th = rng.uniform(-math.pi, math.pi, 200)
    om = rng.uniform(-8, 8, 200)
    ax, az = rng.uniform(-6, 6, 200), rng.uniform(-6, 6, 200)
    s = np.column_stack([np.zeros_like(th), np.sin(th), -np.cos(th)])
    sdot = np.column_stack([np.zeros_like(th), np.cos(th), np.sin(th)]) * om[:, None]
    acc = np.column_stack([np.zeros_like(th), ax, az])  # pivot along +y (toward +θ) and up
    np.testing.assert_allclose(
        tension_margin(th, om, ax, az, 0.3), pendulum.tension_per_mass(s, sdot, acc, 0.3), atol=1e-12
    )


def test_apex_acceleration_keeps_the_string_just_taut():
    th = math.radians(115)
    a = apex_acceleration_to_stay_taut(th)
    assert a == pytest.approx(-4.5746, abs=1e-3)
    assert float(tension_margin(th, 0.0, a, 0.0, 0.25)) == pytest.approx(0.0, abs=1e-12)
    assert float(tension_margin(th, 0.0, a - 0.1, 0.0, 0.25)) > 0
    assert apex_acceleration_to_stay_taut(math.radians(60)) > 0


def test_free_swing_goes_slack_where_predicted():
    apex = math.radians(115)
    sol = solve_ivp(
        lambda t, y: rhs(y, 0.0, 0.25), (0, 0.4), [0, 0, apex, 0.0], rtol=1e-11, atol=1e-12, dense_output=True
    )
    t = np.linspace(0, 0.4, 40001)
    _, _, th, om = sol.sol(t)
    margin = tension_margin(th, om, 0.0, 0.0, 0.25)
    rep = slack_report(t, margin)
    assert not rep.taut and rep.t_first_slack == 0.0  # at the apex itself
    k = int(np.flatnonzero(margin > 0)[0])  # first taut sample on the way down
    assert math.degrees(th[k]) == pytest.approx(math.degrees(fixed_pivot_slack_angle(apex)), abs=0.05)
    assert math.degrees(fixed_pivot_slack_angle(apex)) == pytest.approx(106.4, abs=0.1)
    assert math.degrees(fixed_pivot_slack_angle(math.pi)) == pytest.approx(131.8, abs=0.05)
    assert fixed_pivot_slack_angle(math.radians(80)) == pytest.approx(math.radians(80))
