"""The shared driven spherical pendulum against closed-form physics."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planners.pendulum import G, SampledAcceleration, direction_from_angles, natural_period, rk4_step, simulate


def test_small_constant_acceleration_matches_the_linear_solution():
    # θ(t) = (a/g)(cos ωt − 1) for a small step in pivot acceleration (thesis eq. 4.5)
    a, length = 0.02, 0.25
    w = math.sqrt(G / length)
    t = np.linspace(0.0, 2.0, 201)
    run = simulate(t, lambda tt: np.array([a, 0.0, 0.0]), length)
    np.testing.assert_allclose(run.theta_x, a / G * (np.cos(w * t) - 1), atol=2e-6)
    np.testing.assert_allclose(run.theta_y, 0.0, atol=1e-12)


def test_free_swing_conserves_energy_and_has_the_large_amplitude_period():
    length, th0 = 0.3, math.radians(40)
    from scipy.special import ellipk

    period = 4 * math.sqrt(length / G) * ellipk(math.sin(th0 / 2) ** 2)
    t = np.linspace(0.0, period, 401)
    run = simulate(t, lambda tt: np.zeros(3), length, s0=direction_from_angles(th0, 0.0))
    e = run.energy_per_mass()
    assert np.ptp(e) < 1e-8
    assert run.theta_x[-1] == pytest.approx(th0, abs=1e-6)
    assert period > natural_period(length)


def test_tension_at_rest_is_g_and_rises_with_upward_acceleration():
    run = simulate(np.array([0.0, 0.5]), lambda tt: np.array([0.0, 0.0, 2.0]), 0.25)
    assert run.tension == pytest.approx(G + 2.0, rel=1e-9)


def test_sampled_acceleration_is_exact_on_a_quadratic_path():
    h = 0.005
    t = np.arange(0, 1.0, h)
    pos = np.column_stack([0.5 * 1.5 * t**2, -0.5 * 0.7 * t**2, np.zeros_like(t)])
    acc = SampledAcceleration(t, pos)
    np.testing.assert_allclose(acc.samples()[1:-1], np.tile([1.5, -0.7, 0.0], (len(t) - 2, 1)), atol=1e-9)
    assert acc(0.3333) == pytest.approx([1.5, -0.7, 0.0], abs=1e-9)
    assert np.all(acc(2.0) == 0.0)  # rest after the path


def test_rk4_step_agrees_with_solve_ivp():
    length, h = 0.2, 0.001
    s, v = direction_from_angles(0.3, -0.2), np.zeros(3)
    acc = lambda tt: np.array([math.sin(3 * tt), 0.5, 0.0])  # noqa: E731
    for k in range(500):
        s, v = rk4_step(s, v, acc(k * h), acc((k + 1) * h), h, length)
    ref = simulate(np.array([0.0, 0.5]), acc, length, s0=direction_from_angles(0.3, -0.2))
    # the linear interpolation of the input inside a step costs O(h²) only
    np.testing.assert_allclose(s, ref.s[-1], atol=1e-6)
