"""The thesis baseline (Fig. 4.4) against hand-computed timings and positions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planners.accel_shaping import baseline_segment, plan_accel_shaping
from planners.pendulum import natural_period

# Hand computation for l = 0.25 m, g = 9.81: T = 2π·√(0.25/9.81) = 2π·0.1596424 = 1.0030333 s
T_025 = 1.0030333


def test_period_of_a_quarter_metre_string():
    assert natural_period(0.25) == pytest.approx(T_025, abs=1e-7)
    assert round(natural_period(0.25), 3) == 1.003
    assert natural_period(0.15) == pytest.approx(0.777, abs=5e-4)
    assert natural_period(0.20) == pytest.approx(0.897, abs=5e-4)


def test_long_segment_cruises():
    # s = 1.5 m, a_max = 1: s_min = ½·1·T² = 0.503038, 2·s_min = 1.006076 ≤ s
    # → t_max = (1.5 − 1.006076)/(1·T) = 0.493924/1.0030333 = 0.492430 s, a = a_max
    seg = baseline_segment(1.5, 1.0, T_025)
    assert seg.accel == 1.0
    assert seg.t_cruise == pytest.approx(0.492430, abs=1e-6)
    assert seg.duration == pytest.approx(2 * 1.0030333 + 0.492430, abs=1e-6)
    # positions: ½·a·T² = 0.503038 at t = T; + v_max·t_max = 1.0030333·0.492430 = 0.493924 at T + t_max
    assert seg.position(T_025) == pytest.approx(0.503038, abs=1e-6)
    assert seg.position(T_025 + 0.492430) == pytest.approx(0.503038 + 0.493924, abs=1e-6)
    assert seg.position(seg.duration) == pytest.approx(1.5, abs=1e-12)
    assert seg.position(seg.duration + 1.0) == pytest.approx(1.5, abs=1e-12)


def test_short_segment_branch_uses_s_over_T_squared():
    # s = 0.3 m < 2·s_min = 1.006076 → t_max = 0, a = s/T² = 0.3/1.0060759 = 0.298188 m/s²
    seg = baseline_segment(0.3, 1.0, T_025)
    assert seg.t_cruise == 0.0
    assert seg.accel == pytest.approx(0.298188, abs=1e-6)
    assert seg.duration == pytest.approx(2 * T_025, abs=1e-7)
    assert seg.position(T_025) == pytest.approx(0.15, abs=1e-7)  # half way at the switch
    assert seg.position(0.5) == pytest.approx(0.5 * 0.298188 * 0.25, abs=1e-7)


def test_branch_boundary_is_two_s_min():
    # exactly s = 2·s_min = a·T² takes the a_max branch with zero cruise
    a, T = 1.5, 0.8
    seg = baseline_segment(a * T * T, a, T)
    assert seg.accel == a and seg.t_cruise == pytest.approx(0.0, abs=1e-15)
    seg2 = baseline_segment(a * T * T * 0.999, a, T)
    assert seg2.accel == pytest.approx(0.999 * a)


def test_sampled_layout_matches_the_closed_form_and_concatenates():
    h = 0.01
    pts = np.array([[0.0, 0.0], [1.5, 0.0], [1.5, 0.3]])
    plan = plan_accel_shaping(pts, h, 1.0, T_025)
    seg1, seg2 = plan.segments
    n1 = math.ceil(seg1.duration / h) + 1  # 2.498497 s → 251 samples (k = 0 … 250)
    n2 = math.ceil(seg2.duration / h) + 1  # 2.006067 s → 202 samples
    assert (n1, n2) == (251, 202)
    assert len(plan.t) == n1 + n2
    np.testing.assert_allclose(np.diff(plan.t), h, atol=1e-12)
    assert list(plan.segment_start) == [0, n1]
    # sample k = 50 (t = 0.5 s, accelerating): x = ½·1·0.25 = 0.125
    assert plan.xy[50] == pytest.approx([0.125, 0.0], abs=1e-12)
    # sample k = 120 (t = 1.2 s, cruising since T): x = 0.503038 + 1.0030333·(1.2 − 1.0030333) = 0.503038 + 0.197564 = 0.700602
    assert plan.xy[120] == pytest.approx([0.700602, 0.0], abs=1e-6)
    # the pivot rests one sample at the turning point, then starts the y segment
    assert plan.xy[n1 - 1] == pytest.approx([1.5, 0.0], abs=1e-12)
    assert plan.xy[n1] == pytest.approx([1.5, 0.0], abs=1e-12)
    assert plan.xy[n1 + 50] == pytest.approx([1.5, 0.5 * 0.298188 * 0.25], abs=1e-7)
    assert plan.xy[-1] == pytest.approx([1.5, 0.3], abs=1e-12)


def test_second_differences_show_the_acceleration_steps():
    h = 0.005
    T = natural_period(0.25)
    plan = plan_accel_shaping(np.array([[0.0, 0.0], [2.0, 0.0]]), h, 1.0, T)
    acc = np.diff(plan.xy[:, 0], 2) / h**2
    t = plan.t[1:-1]
    seg = plan.segments[0]
    inside_acc = (t > 2 * h) & (t < T - 2 * h)
    inside_cruise = (t > T + 2 * h) & (t < T + seg.t_cruise - 2 * h)
    inside_brake = (t > T + seg.t_cruise + 2 * h) & (t < seg.duration - 2 * h)
    np.testing.assert_allclose(acc[inside_acc], 1.0, atol=1e-6)
    np.testing.assert_allclose(acc[inside_cruise], 0.0, atol=1e-6)
    np.testing.assert_allclose(acc[inside_brake], -1.0, atol=1e-6)
