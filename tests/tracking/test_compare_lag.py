"""The lag from the model over the whole track: short clips, ambiguity, uneven and missing samples."""

import math

import numpy as np
import pytest

from tracking.compare import compare_angles
from tracking.samples import sample_report

OMEGA = math.sqrt(9.81 / 0.25)  # [rad/s] 25 cm string
T_MODEL = np.arange(0.0, 6.0, 0.001)


def crane(t):
    """Still until 0.5 s, a sway that builds up and decays [rad]."""
    s = np.clip(t - 0.5, 0.0, None)
    return 0.35 * (1 - np.exp(-s / 0.6)) * np.exp(-s / 3.0) * np.sin(OMEGA * s)


def clip(model_fn, start_s, duration_s, fps=60.0, noise_deg=0.05, seed=0):
    """A track of duration_s [s] whose first frame shows the model at time start_s: lag = −start_s."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(duration_s * fps)) / fps
    return t, model_fn(t + start_s) + np.radians(noise_deg) * rng.standard_normal(len(t))


@pytest.mark.parametrize(
    "start_s,duration_s,fps,seed",
    [(0.9, 2.0, 60.0, 0), (1.7, 2.2, 30.0, 1), (2.4, 3.0, 120.0, 2), (0.3, 2.0, 60.0, 3), (3.1, 2.5, 60.0, 4)],
)
def test_short_clips_recover_the_lag_within_1_ms(start_s, duration_s, fps, seed):
    """Clips of 2–3 s cut out of a 6 s crane move: the lag (−start) to ≤ 1 ms, not one period off."""
    t, y = clip(crane, start_s, duration_s, fps, seed=seed)
    cmp = compare_angles(T_MODEL, crane(T_MODEL), t, y, max_lag_s=4.0)
    assert not cmp.ambiguous, cmp.rival_lag_s
    assert abs(cmp.lag_s + start_s) <= 1e-3
    assert cmp.rms_deg < 0.1


def test_a_longer_rival_overlap_wins_over_a_shorter_better_looking_one():
    """The issue's case: a 3 s clip starting 0.41 s into a 3.4 s prediction (overlap 2.98 s); one period later
    (+0.94 s) the overlap is 2.05 s and fits as well where it overlaps — it must not win."""
    t_model = np.arange(0.0, 3.4, 0.001)
    t, y = clip(crane, 0.41, 3.0)
    cmp = compare_angles(t_model, crane(t_model), t, y)
    assert abs(cmp.lag_s + 0.41) <= 1e-3 and not cmp.ambiguous
    assert cmp.overlap_s == pytest.approx(2.98, abs=0.02)


def test_a_steady_swing_is_ambiguous_and_max_lag_resolves_it():
    """A steady sine: a clip matches the model equally one period (1.003 s) off, so the lag is ambiguous."""
    steady = lambda t: 0.3 * np.sin(OMEGA * t)  # noqa: E731
    t, y = clip(steady, 2.0, 2.0)
    cmp = compare_angles(T_MODEL, steady(T_MODEL), t, y)
    assert cmp.ambiguous
    assert abs(abs(cmp.rival_lag_s - cmp.lag_s) - 2 * math.pi / OMEGA) < 0.05
    near = compare_angles(T_MODEL, steady(T_MODEL), t, y, max_lag_s=2.3)  # excludes −1 s and −3 s, not −2 s
    assert abs(near.lag_s + 2.0) <= 1e-3


def test_a_better_lag_beyond_the_default_window_makes_it_ambiguous():
    t_model = np.arange(0.0, 12.0, 0.001)
    t, y = clip(crane, 7.2, 2.5)  # lag −7.2 s, beyond the default ±6 s
    cmp = compare_angles(t_model, crane(t_model), t, y)
    assert cmp.ambiguous and abs(cmp.rival_lag_s + 7.2) < 0.02
    assert abs(compare_angles(t_model, crane(t_model), t, y, max_lag_s=8.0).lag_s + 7.2) <= 1e-3


def test_sample_report_counts_drops_and_missing():
    t = np.arange(100) / 60.0
    keep = np.ones(100, bool)
    keep[[10, 11, 40]] = False  # three frames dropped by the camera
    t = t[keep]
    y = np.sin(t)
    y[50:56] = np.nan  # six frames without θ
    rep = sample_report(t, y)
    assert rep.dropped_frames == 3 and rep.uneven
    assert rep.longest_gap_s == pytest.approx(3 / 60.0)
    assert rep.missing == 6 and rep.incomplete
    assert rep.longest_missing_s == pytest.approx(7 / 60.0)
    even = sample_report(np.arange(100) / 60.0, np.zeros(100))
    assert not even.uneven and not even.incomplete and even.dropped_frames == 0
