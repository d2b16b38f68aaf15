"""Length-robust designs: the ramp profile's closed forms, the linear programme's guarantees, the nonlinear check."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planners.antisway import AntiSwayOptions, plan_layout, residual_sway, robust_spec, simulate_path
from planners.pendulum import G, natural_period, simulate
from planners.ramp_profile import RampProfile
from planners.robust_shaping import (
    RobustSpec,
    linear_residual_phasor,
    nonlinear_phasor,
    planar_band,
    robust_profile,
)

L = 0.25  # [m]


def test_ramp_profile_closed_forms_agree_with_numerical_integration():
    rng = np.random.default_rng(3)
    a = np.concatenate([[0.0], rng.uniform(-1, 1, 30), [0.0]])
    a[1:-1] -= a[1:-1].mean()  # ends at rest
    prof = RampProfile(1.0, 0.05, a)
    t = np.linspace(0.0, prof.duration, 20001)
    acc = prof.acceleration(t)
    np.testing.assert_allclose(acc[::500], np.interp(t[::500], np.arange(len(a)) * 0.05, a), atol=1e-12)
    vel = np.concatenate([[0.0], np.cumsum(0.5 * (acc[1:] + acc[:-1]) * np.diff(t))])
    pos = np.concatenate([[0.0], np.cumsum(0.5 * (vel[1:] + vel[:-1]) * np.diff(t))])
    np.testing.assert_allclose(prof.velocity(t), vel, atol=1e-6)
    np.testing.assert_allclose(prof.derivative(t[:-1], 0), pos[:-1], atol=1e-6)
    # the exact Fourier transform of the hat-function acceleration
    w = np.array([3.0, 6.3, 9.0])
    numeric = np.array([np.trapezoid(acc * np.exp(1j * wi * t), t) for wi in w])
    np.testing.assert_allclose(prof.spectrum(w), numeric, atol=1e-6)
    v, amax, j = prof.peaks()
    assert amax == pytest.approx(np.abs(a).max()) and j == pytest.approx(np.abs(np.diff(a)).max() / 0.05)
    assert v == pytest.approx(np.abs(vel).max(), rel=1e-4)


@pytest.mark.heavy
@pytest.mark.parametrize("length, a_max, s", [(0.25, 2.0, 0.35), (0.12, 3.0, 0.6), (0.5, 1.0, 0.1)])
def test_robust_profile_meets_its_bound_over_the_band_and_the_limits(length, a_max, s):
    spec = robust_spec(length, a_max, 0.1, math.radians(0.2), None)
    j = 40.0
    prof, bound = robust_profile(s, spec, a_max, j, math.inf)
    assert bound <= spec.residual
    w = np.linspace(spec.omega_lo, spec.omega_hi, 101)  # denser than the programme's check frequencies
    lin = np.abs(linear_residual_phasor(prof, w))
    assert lin.max() <= 1.1 * spec.residual  # octagon bound exact at the check frequencies, smooth between
    v, a, jj = prof.peaks()
    assert a <= a_max * (1 + 1e-6) and jj <= j * (1 + 1e-6)
    assert prof.position(prof.duration) == pytest.approx(s, abs=1e-12)
    assert abs(prof.velocity(np.array([prof.duration - 1e-9]))[0]) < 1e-6
    assert np.all(
        np.diff(prof.position(np.linspace(0, prof.duration, 500))) >= -1e-4
    )  # backs up < 0.1 mm (speed ≥ 0 at the nodes only)
    # quicker is not possible at this bound (bisection tolerance 1 %)
    from planners.robust_shaping import solve_at_duration

    sol = solve_at_duration(s, 0.97 * prof.duration, spec, a_max, j, math.inf)
    assert sol is None or sol[0] > spec.residual


@pytest.mark.heavy
def test_linear_phasor_matches_the_simulated_linear_pendulum():
    """|Z| is the residual amplitude of θ̈ + ω²θ = −(ω²/g)·ẍ; its phase gives the final state."""
    from scipy.integrate import solve_ivp

    spec = RobustSpec(5.0, 7.0, math.radians(0.5))
    prof, _ = robust_profile(0.3, spec, 1.5, 30.0, math.inf)
    w = 6.1
    sol = solve_ivp(
        lambda t, y: [y[1], -w * w * y[0] - w * w / G * prof.acceleration(np.array(t))[()]],
        (0, prof.duration),
        [0.0, 0.0],
        rtol=1e-11,
        atol=1e-13,
        max_step=prof.step / 4,
    )
    th, thd = sol.y[:, -1]
    z = linear_residual_phasor(prof, np.array([w]))[0]
    assert z == pytest.approx(-np.exp(-1j * w * prof.duration) * (thd / w + 1j * th), abs=1e-7)


@pytest.mark.heavy
def test_nonlinear_correction_reaches_the_budget_where_the_linear_design_does_not():
    """At 3 m/s² on a short string the linear design misses on the nonlinear pendulum; the planner corrects it."""
    length, a_max, s = 0.1, 3.0, 0.45
    budget = math.radians(0.1)
    spec = robust_spec(length, a_max, 0.1, budget, None)
    lin_only, _ = robust_profile(s, spec, a_max, a_max / (0.04 * natural_period(length)), math.inf)
    z_lin, _ = nonlinear_phasor(lin_only, spec.omegas)
    assert np.abs(z_lin).max() > budget
    plan = plan_layout(
        np.array([[0.0, 0.0], [s, 0.0]]), length, a_max, 0.45, 0.005, AntiSwayOptions(robust_budget=budget)
    )
    seg = plan.segments[0]
    assert seg.design == "robust" and seg.band_residual <= 1.1 * budget < 0.5 * np.abs(z_lin).max()
    amp, _ = planar_band(seg.profile, length * np.array([0.9, 0.95, 1.0, 1.05, 1.1]), step=0.001)
    assert amp.max() <= 1.15 * budget


@pytest.mark.heavy
def test_max_sway_is_a_constraint_of_the_default_design():
    pts = np.array([[0.4, -0.3], [0.62, -0.3], [0.62, 0.05]])
    free = plan_layout(pts, L, 2.0, 0.45, 0.005, AntiSwayOptions())
    limit = math.radians(3.0)
    bounded = plan_layout(pts, L, 2.0, 0.45, 0.005, AntiSwayOptions(max_sway=limit))
    for length in (0.9 * L, L, 1.1 * L):
        run_free = simulate_path(free.t, free.position, length, free.stop_time)
        run = simulate_path(bounded.t, bounded.position, length, bounded.stop_time)
        assert run_free.theta.max() > 1.5 * limit
        assert run.theta.max() <= limit * 1.02
        assert residual_sway(run, bounded.stop_time) <= math.radians(0.3)
    assert bounded.stop_time > free.stop_time  # bounded sway costs time


@pytest.mark.heavy
def test_hat_model_of_the_sampled_path_ends_at_rest():
    """The realised pivot acceleration integrates to zero net velocity (no spurious swing after the move)."""
    from planners.sway_prediction import hat_acceleration

    plan = plan_layout(np.array([[0.0, 0.0], [0.3, 0.0]]), L, 2.0, 0.45, 0.005, AntiSwayOptions(shaper="accel"))
    fn = hat_acceleration(plan.t, plan.position)
    tt = np.linspace(-0.005, plan.t[-1] + 0.005, 40001)
    acc = np.array([fn(x)[0] for x in tt])
    assert abs(np.trapezoid(acc, tt)) < 1e-9
    run = simulate(np.array([0.0, 0.1]), lambda t: np.zeros(3), L)
    assert run.theta.max() == 0.0
