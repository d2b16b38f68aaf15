"""The string model (one-sided string, cup, contact): closed forms, its two integrators against each other, and the
independent penalty-force judge on cases it was not tuned on (other lengths, cups, restitutions, release heights)."""

import dataclasses
import math

import numpy as np
import pytest

from planners.catch_outcome import outcome
from planners.pendulum import G, SampledAcceleration, simulate
from planners.string_model import (
    RESTING,
    SLACK,
    TAUT,
    Ball,
    Cup,
    StringModel,
    contact_velocity,
    cup_gap,
    in_cup,
    retension_velocity,
)
from planners.string_penalty import judge
from planners.string_sim import PivotMotion, simulate_string
from planners.string_stepper import StringStepper, step_path

NO_DRAG = Ball(drag_coefficient=0.0)
P0 = np.array([0.5, 0.0, 0.8])


def fixed_pivot(duration, h=0.005):
    t = np.arange(0.0, duration, h)
    return t, np.tile(P0, (len(t), 1))


def apex_rate(theta_apex, length):
    """ṡ [1/s] at the bottom of a free swing whose energy reaches θ_apex (toward +y)."""
    return math.sqrt(2 * G * (1 - math.cos(theta_apex)) / length)


@pytest.mark.heavy
def test_taut_motion_is_the_spherical_pendulum():
    """A driven swing that stays taut: identical to planners.pendulum (the same equations), drag off."""
    t = np.arange(0.0, 2.0, 0.005)
    pos = np.column_stack([0.5 + 0.04 * np.sin(3 * t) * (1 - np.cos(t)), 0.1 * np.sin(2.2 * t) ** 3, 0.8 + 0 * t])
    model = StringModel(0.3, ball=NO_DRAG, cup=None)
    until = t <= 1.8  # (the path stops dead at its end: judged before)
    run = simulate_string(model, PivotMotion(t, pos), 1.8, t[until])
    ref = simulate(t[until], SampledAcceleration(t, pos), 0.3, max_step=0.005)
    assert not run.events and np.all(run.phase == TAUT)
    assert np.abs(run.string_direction - ref.s).max() < 1e-7
    assert np.nanmax(np.abs(run.tension - ref.tension)) < 1e-5


@pytest.mark.heavy
@pytest.mark.parametrize("length,apex_deg", [(0.2, 140.0), (0.33, 165.0)])
def test_free_swing_goes_slack_where_the_tension_vanishes_and_flies_a_parabola(length, apex_deg):
    t, pos = fixed_pivot(1.2)
    model = StringModel(length, ball=NO_DRAG, cup=None)
    run = simulate_string(
        model,
        PivotMotion(t, pos),
        1.2,
        np.arange(0, 1.2, 0.001),
        sdot0=np.array([0.0, apex_rate(math.radians(apex_deg), length), 0.0]),
    )
    release = run.of_kind("slack")[0]
    cos_s = 2.0 / 3.0 * math.cos(math.radians(apex_deg))
    assert release.info["theta_deg"] == pytest.approx(math.degrees(math.acos(cos_s)), abs=1e-5)
    assert release.info["speed_m_s"] == pytest.approx(math.sqrt(-G * length * cos_s), rel=1e-6)
    # the flight: a parabola from the release point until the string tightens again
    ts = release.t
    tight = run.of_kind("retension")[0].t
    k0 = int(np.searchsorted(run.t, ts)) + 1
    b0 = run.position[k0 - 1] + run.velocity[k0 - 1] * (run.t[k0 - 1] - run.t[k0 - 1])
    flight = (run.t > ts) & (run.t < tight)
    dt_ = run.t[flight] - run.t[k0 - 1]
    expect = b0 + run.velocity[k0 - 1] * dt_[:, None] + 0.5 * np.array([0, 0, -G]) * dt_[:, None] ** 2
    assert np.abs(run.position[flight] - expect).max() < 1e-6
    assert np.all(run.phase[flight] == SLACK)
    d = np.linalg.norm(run.position[flight] - run.pivot[flight], axis=1)
    assert d.max() < length  # slack: nearer than the string's length


def test_the_string_tightens_with_the_jerk_its_coefficient_asks_for():
    s = (0.0, 0.6, -0.8)
    v = (0.3, 1.2, 0.4)  # radial part 1.2·0.6 − 0.4·0.8 = 0.4 m/s outward
    inelastic = retension_velocity(s, v, 0.0)
    elastic = retension_velocity(s, v, 1.0)
    assert np.dot(inelastic, s) == pytest.approx(0.0, abs=1e-12)
    assert np.dot(elastic, s) == pytest.approx(-0.4)
    assert np.allclose(np.array(v) - np.dot(v, s) * np.array(s), np.array(inelastic) - 0.0)  # tangential kept
    assert retension_velocity(s, (0.0, -0.6, 0.8), 0.0) == (0.0, -0.6, 0.8)  # moving inward: nothing happens


def test_cup_geometry_distances_and_normals():
    cup = Cup(inner_radius=0.03, depth=0.04, rim_height=0.05, wall=0.004)
    up = (0.0, 0.0, 1.0)
    d, n, seg = cup_gap((0.0, 0.0, 0.08), up, cup)  # above the opening on the axis: nearest is the rim's inner edge
    assert d == pytest.approx(math.hypot(0.03, 0.03)) and seg in (2, 3)
    d, n, seg = cup_gap((0.0, 0.0, 0.03), up, cup)  # inside, above the bottom
    assert d == pytest.approx(0.02) and seg == 4 and n == pytest.approx((0, 0, 1))
    d, n, seg = cup_gap((0.05, 0.0, 0.03), up, cup)  # beside the outer wall
    assert d == pytest.approx(0.05 - 0.034) and seg == 1 and n == pytest.approx((1, 0, 0))
    d, n, _ = cup_gap((0.0, 0.045, 0.07), up, cup)  # above the outer corner of the rim
    assert d == pytest.approx(math.hypot(0.045 - 0.034, 0.02))
    assert n == pytest.approx((0.0, 0.011 / d, 0.02 / d))
    d, _, _ = cup_gap((0.032, 0.0, 0.02), up, cup)  # inside the wall itself
    assert d < 0
    d, n, seg = cup_gap((0.0, 0.0, -0.02), up, cup)  # below the bottom
    assert d == pytest.approx(0.02) and seg == 0 and n == pytest.approx((0, 0, -1))
    tilted = (0.0, math.sin(0.3), math.cos(0.3))  # the section turns with the axis
    p = tuple(0.03 * np.array(tilted))
    assert cup_gap(p, tilted, cup)[0] == pytest.approx(0.02)
    assert in_cup((0.0, 0.01, 0.03), up, cup) and not in_cup((0.0, 0.01, 0.06), up, cup)


def test_impact_keeps_the_restitution_and_limits_friction():
    n = (0.0, 0.0, 1.0)
    out = contact_velocity((0.2, 0.0, -1.0), n, 0.5, 0.1)
    assert out[2] == pytest.approx(0.5)
    assert out[0] == pytest.approx(0.2 - 0.1 * 1.5 * 1.0)  # Coulomb: at most μ(1 + e)|v_n|
    assert contact_velocity((0.05, 0.0, -1.0), n, 0.5, 1.0)[0] == pytest.approx(0.0)  # sticks


def _drop(model, height, lateral=0.0, v=(0.0, 0.0, 0.0)):
    """A stepper with the ball flying above a resting cup (string slack)."""
    st = StringStepper(model, tuple(P0), (0.0, 0.0, 1.0))
    st.phase = SLACK
    st.b = (P0[0], P0[1] + lateral, P0[2] + height)
    st.v = v
    return st


@pytest.mark.parametrize("e", [0.3, 0.6])
def test_a_ball_dropped_into_the_cup_bounces_with_its_restitution_and_comes_to_rest(e):
    model = StringModel(0.25, ball=NO_DRAG, restitution=e)
    t, pos = fixed_pivot(2.0, 0.001)
    st, _ = step_path(model, PivotMotion(t, pos), 1.9, state=_drop(model, 0.12))
    hits = [ev for ev in st.events if ev.kind == "contact"]
    v_in = math.sqrt(2 * G * (0.12 - model.cup.bottom_height - model.ball.radius))
    assert hits[0].info["normal_speed_m_s"] == pytest.approx(v_in, rel=1e-3)
    assert hits[1].info["normal_speed_m_s"] == pytest.approx(e * v_in, rel=1e-3)
    o = outcome(st.events, st.resting, st.inside)
    assert o.caught and st.phase == RESTING and o.margin == pytest.approx(model.cup.inner_radius - model.ball.radius)


def test_a_ball_beside_the_rim_is_not_caught_and_says_how_far_out():
    model = StringModel(0.25, ball=NO_DRAG)
    t, pos = fixed_pivot(1.0, 0.001)
    st, _ = step_path(model, PivotMotion(t, pos), 0.9, state=_drop(model, 0.12, lateral=0.06))
    o = outcome(st.events, st.resting, st.inside)
    assert not o.caught and o.margin == pytest.approx(0.02 - 0.06, abs=1e-6)
    assert "40 mm outside the rim" in o.failure


@pytest.mark.parametrize("lateral", [0.0, 0.06])
def test_a_search_stops_stepping_a_ball_at_its_miss_and_reaches_the_same_verdict(lateral):
    model = StringModel(0.25, ball=NO_DRAG)
    t, pos = fixed_pivot(1.5, 0.001)
    full, _ = step_path(model, PivotMotion(t, pos), 1.4, state=_drop(model, 0.12, lateral=lateral))
    short, _ = step_path(model, PivotMotion(t, pos), 1.4, state=_drop(model, 0.12, lateral=lateral), until_missed=True)
    verdicts = [outcome(st.events, st.resting, st.inside) for st in (full, short)]
    assert verdicts[0].caught == verdicts[1].caught == (lateral == 0.0)
    assert verdicts[0].margin == verdicts[1].margin
    fall = math.sqrt(2 * (0.12 - model.cup.rim_height) / G)  # [s] to the rim plane
    assert short.t == pytest.approx(1.4, abs=1e-9) if lateral == 0.0 else fall < short.t < fall + 0.002


def _swing_cases():
    """Free swings released by the string into a resting cup: (model, apex [deg]) of several lengths and cups."""
    cups = [
        Cup(),
        Cup(inner_radius=0.04, depth=0.06, rim_height=0.065, wall=0.004),
        Cup(inner_radius=0.025, depth=0.035, rim_height=0.04, wall=0.002),
    ]
    return [
        (StringModel(0.25, cup=cups[0]), 157.0),
        (StringModel(0.3, cup=cups[1], restitution=0.7), 162.0),
        (StringModel(0.18, cup=cups[2], ball=Ball(radius=0.008)), 157.0),
    ]


@pytest.mark.heavy
def test_the_stepper_and_the_event_driven_integrator_agree_event_by_event():
    t, pos = fixed_pivot(1.6)
    for model, apex in _swing_cases():
        sd0 = (0.0, apex_rate(math.radians(apex), model.length), 0.0)
        run = simulate_string(model, PivotMotion(t, pos), 1.5, sdot0=np.array(sd0))
        st, _ = step_path(model, PivotMotion(t, pos), 1.5, sdot0=sd0)
        ref = [(e.kind, e.t) for e in run.events][:8]
        got = [(e.kind, e.t) for e in st.events][:8]
        assert [k for k, _ in got] == [k for k, _ in ref]
        assert np.abs(np.array([x for _, x in got]) - np.array([x for _, x in ref])).max() < 1e-5
        assert outcome(st.events, st.resting, st.inside).caught == run.caught


@pytest.mark.slow
def test_the_penalty_judge_reaches_the_same_verdict_on_other_cups_lengths_and_heights():
    """A deliberately different integrator (penalty forces, Cartesian, symplectic Euler, spline anchor, its own
    cup distance): same catch / no catch; where the flight reaches the rim plane before touching anything, the same
    crossing within 2 ms and 1 mm."""
    t, pos = fixed_pivot(1.5)
    axes = np.tile((0.0, 0.0, 1.0), (len(t), 1))
    for model, apex in _swing_cases():
        heights = (apex, apex - 15.0)  # two release heights: one lands in the cup, the lower one beside it
        rates = [apex_rate(math.radians(a), model.length) for a in heights]
        pen = judge([model, model], t, pos, axes, 1.4, v0=np.array([[0.0, model.length * w, 0.0] for w in rates]))
        for j, rate in enumerate(rates):
            run = simulate_string(model, PivotMotion(t, pos), 1.4, sdot0=np.array([0.0, rate, 0.0]))
            ref = outcome(run.events, run.final_phase == RESTING, run.final_inside)
            assert bool(pen.caught[j]) == ref.caught == (j == 0), (model, heights[j])
            clean = [e for e in run.events if e.kind in ("entry", "contact")][0].kind == "entry"
            if clean:  # the first rim-plane crossing before any touch: the flights must agree
                assert pen.t_crossing[j] == pytest.approx(ref.t_crossing, abs=2e-3)
                margin = model.cup.inner_radius - model.ball.radius - pen.rho_crossing[j]
                assert margin == pytest.approx(ref.margin, abs=1e-3)


def test_model_validation_names_the_bad_value():
    with pytest.raises(ValueError, match="inner radius"):
        StringModel(0.25, ball=Ball(radius=0.05)).validate()
    with pytest.raises(ValueError, match="exceed the cup's extent"):
        StringModel(0.05).validate()
    with pytest.raises(ValueError, match="restitution"):
        dataclasses.replace(StringModel(0.25), restitution=1.5).validate()
