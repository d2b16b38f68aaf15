"""Input shapers (residual vibration) and box profiles (limits, agreement with ruckig)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planners.profiles import BoxProfile, time_optimal_boxes
from planners.shapers import SHAPER_NAMES, box_residual, frequency_ratio_band, make_shaper


@pytest.mark.parametrize("name", SHAPER_NAMES)
def test_shaper_impulses_are_positive_and_sum_to_one(name):
    sh = make_shaper(name, 1.0)
    assert np.all(sh.amplitudes >= 0)
    assert sh.amplitudes.sum() == pytest.approx(1.0)
    assert sh.times[0] == 0.0 and np.all(np.diff(sh.times) > 0)


@pytest.mark.parametrize(
    "name, duration, v_at_design",
    [("zv", 0.5, 0.0), ("zvd", 1.0, 0.0), ("zvdd", 1.5, 0.0), ("mzv", 0.75, 0.0), ("ei", 1.0, 0.05)],
)
def test_residual_at_the_design_frequency(name, duration, v_at_design):
    T = 0.9
    sh = make_shaper(name, T)
    assert sh.duration == pytest.approx(duration * T)
    assert float(sh.residual(2 * math.pi / T)) == pytest.approx(v_at_design, abs=1e-12)
    assert float(sh.residual(0.0)) == pytest.approx(1.0)


def _band(sh, T, level=0.05):
    r = np.linspace(0.5, 1.6, 22001)
    ok = r[sh.residual(2 * math.pi / T * r) <= level]
    return ok.min(), ok.max()


@pytest.mark.parametrize(
    "name, lo, hi", [("zv", 0.968, 1.032), ("zvd", 0.856, 1.144), ("zvdd", 0.760, 1.240), ("ei", 0.801, 1.199)]
)
def test_five_percent_bands_match_the_literature(name, lo, hi):
    # facts/physics.md shaper table (Singhose): the r range where V ≤ 5 %
    got = _band(make_shaper(name, 1.0), 1.0)
    assert got == pytest.approx((lo, hi), abs=2e-3)


def test_two_hump_ei_is_wider_than_ei():
    lo2, hi2 = _band(make_shaper("ei2", 1.0), 1.0)
    lo1, hi1 = _band(make_shaper("ei", 1.0), 1.0)
    assert lo2 < lo1 - 0.1 and hi2 > hi1 + 0.1
    assert (lo2, hi2) == pytest.approx((0.64, 1.36), abs=0.01)


def test_length_band_and_box_zero():
    lo, hi = frequency_ratio_band(0.2)
    assert lo == pytest.approx(1 / math.sqrt(1.2)) and hi == pytest.approx(1 / math.sqrt(0.8))
    T = 1.0
    assert float(box_residual(2 * math.pi / T, T)) == pytest.approx(0.0, abs=1e-15)
    assert float(box_residual(2 * math.pi / T * 1.118, T)) == pytest.approx(
        abs(math.sin(math.pi * 1.118) / (math.pi * 1.118))
    )


def _ruckig_duration(s, v, a, j):
    from ruckig import InputParameter, Result, Ruckig, Trajectory

    otg, inp, traj = Ruckig(1), InputParameter(1), Trajectory(1)
    inp.current_position, inp.target_position = [0.0], [s]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [v], [a], [j]
    assert otg.calculate(inp, traj) == Result.Working
    return traj.duration


def test_time_optimal_boxes_match_ruckig_and_respect_limits():
    rng = np.random.default_rng(3)
    for k in range(30):
        s, v, a, j = rng.uniform(0.02, 1.5), rng.uniform(0.1, 2.0), rng.uniform(0.3, 6.0), rng.uniform(2.0, 80.0)
        prof = BoxProfile(s, time_optimal_boxes(s, v, a, j))
        assert prof.duration == pytest.approx(_ruckig_duration(s, v, a, j), rel=1e-7, abs=1e-9)
        vp, ap, jp = prof.peaks()
        assert vp <= v * (1 + 1e-9) and ap <= a * (1 + 1e-9) and jp <= j * (1 + 1e-9)
        assert float(prof.position(prof.duration)) == pytest.approx(s, abs=1e-12)


def test_box_profile_derivatives_are_consistent():
    prof = BoxProfile(0.4, (0.9, 0.5, 0.05), make_shaper("zvd", 0.8))
    h = 1e-5
    t = np.linspace(0.01, prof.duration - 0.01, 157)
    for order in (1, 2):
        fd = (prof.derivative(t + h, order - 1) - prof.derivative(t - h, order - 1)) / (2 * h)
        np.testing.assert_allclose(prof.derivative(t, order), fd, atol=1e-5 * 10**order)
    # rest to rest over the shaped duration
    assert float(prof.position(0.0)) == 0.0 and float(prof.position(prof.duration)) == pytest.approx(0.4)
    assert float(prof.velocity(prof.duration + 0.1)) == 0.0


def test_shaping_never_raises_the_peaks():
    base = BoxProfile(0.3, time_optimal_boxes(0.3, math.inf, 2.0, 20.0))
    for name in SHAPER_NAMES:
        shaped = BoxProfile(base.distance, base.boxes, make_shaper(name, 1.0))
        for p_shaped, p_base in zip(shaped.peaks(), base.peaks()):
            assert p_shaped <= p_base * (1 + 1e-9)
