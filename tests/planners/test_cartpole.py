"""Planar cart–pendulum: energy bookkeeping Ė = −u·m·l·θ̇·cos θ and agreement with the spherical model."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from planners import pendulum
from planners.cartpole import apex_angle, desired_energy, energy, energy_rate, rhs, theta_ddot

L, M = 0.25, 0.0139


def _run(u_of_t, theta0=0.3, duration=6.0):
    sol = solve_ivp(
        lambda t, y: rhs(y, u_of_t(t), L),
        (0, duration),
        [0, 0, theta0, 0.0],
        method="DOP853",
        dense_output=True,
        rtol=1e-11,
        atol=1e-12,
        max_step=0.01,
    )
    t = np.linspace(0, duration, 6001)
    return t, sol.sol(t)


def test_energy_bookkeeping_along_a_driven_run():
    def u_of_t(t):
        return 2.5 * math.sin(5.0 * t) + 1.0 * math.cos(13.0 * t)  # [m/s²] arbitrary pivot input

    t, (x, v, th, om) = _run(u_of_t)
    e = energy(th, om, L, M)
    u = np.array([u_of_t(tk) for tk in t])
    rate = energy_rate(th, om, u, L, M)
    # the energy really changes (the test is not trivial) ...
    assert np.ptp(e) > 0.5 * M * 9.81 * L
    # ... and does so exactly as Ė = −u m l θ̇ cos θ: pointwise derivative and integral
    np.testing.assert_allclose(np.gradient(e, t), rate, atol=2e-3 * np.abs(rate).max())
    integral = np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(t))])
    np.testing.assert_allclose(e - e[0], integral, atol=1e-6)


def test_energy_is_conserved_with_a_pivot_at_constant_speed():
    t, (x, v, th, om) = _run(lambda t: 0.0, theta0=1.5)
    e = energy(th, om, L, M)
    assert np.ptp(e) < 1e-9


@pytest.mark.parametrize("theta,theta_dot,u", [(0.3, 1.0, 2.0), (2.0, -3.0, -4.0), (-1.2, 0.5, 0.7)])
def test_planar_model_is_the_spherical_model_in_the_y_z_plane(theta, theta_dot, u):
    s = np.array([0.0, math.sin(theta), -math.cos(theta)])
    sdot = np.array([0.0, math.cos(theta), math.sin(theta)]) * theta_dot
    sdd = pendulum.rhs(s, sdot, np.array([0.0, u, 0.0]), L)
    e_theta = np.array([0.0, math.cos(theta), math.sin(theta)])  # tangent toward +θ
    # tangential component of s̈ is θ̈
    assert float(np.dot(sdd, e_theta)) == pytest.approx(float(theta_ddot(theta, theta_dot, u, L)), rel=1e-12)


def test_desired_energy_and_apex_angle_are_inverse():
    for deg in (10, 90, 115, 170):
        th = math.radians(deg)
        assert apex_angle(desired_energy(th, L, M), L, M) == pytest.approx(th)
        assert energy(th, 0.0, L, M) == pytest.approx(desired_energy(th, L, M))
    assert apex_angle(10.0, L, M) == pytest.approx(math.pi)
