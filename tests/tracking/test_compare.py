"""Model–experiment comparison: a known lag is recovered within one frame; errors over the overlap are exact."""

import math

import numpy as np
import pytest

from trajectories.errors import CheckFailed
from tracking.compare import compare_angles, estimate_lag, resample

FRAME_S = 1.0 / 60.0
OMEGA = math.sqrt(9.81 / 0.25)  # [rad/s] 25 cm string


def crane_move(t):
    """Still until 0.5 s, then a sway that builds up and decays (like an unshaped crane move) [rad]."""
    s = np.clip(t - 0.5, 0.0, None)
    return 0.35 * (1 - np.exp(-s / 0.6)) * np.exp(-s / 4.0) * np.sin(OMEGA * s)


def measure(model_fn, lag, duration=7.0, noise_deg=0.2, drop=0.03, seed=0, fps=60.0):
    """A 60 FPS track of model_fn delayed by lag [s], with noise, dropped frames and one longer gap."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(duration * fps)) / fps
    y = model_fn(t - lag) + np.radians(noise_deg) * rng.standard_normal(len(t))
    y[rng.random(len(t)) < drop] = np.nan
    y[(t > 3.0) & (t < 3.3)] = np.nan
    return t, y


T_MODEL = np.arange(0.0, 5.0, 0.001)


@pytest.mark.parametrize("lag", [-0.4, 0.0, 0.537, 1.9, 2.71])
def test_known_lag_recovered_within_one_frame(lag):
    t, y = measure(crane_move, lag, seed=int(lag * 100) % 7)
    cmp = compare_angles(T_MODEL, crane_move(T_MODEL), t, y)
    assert abs(cmp.lag_s - lag) <= FRAME_S
    assert cmp.rms_deg == pytest.approx(0.2, rel=0.25)  # just the noise left
    assert not cmp.mirrored
    assert cmp.overlap_s == pytest.approx(min(5.0 + lag, 7.0 - FRAME_S) - max(lag, 0.0), abs=0.01)


def test_free_swing_released_after_video_start():
    """A pure damped swing (periodic: shifts by one period also match well) held at θ0 before release."""

    def swing(t):
        return np.where(t < 0, 0.4, 0.4 * np.exp(-0.05 * OMEGA * np.clip(t, 0, None)) * np.cos(OMEGA * t))

    t, y = measure(swing, 1.234, duration=6.0)
    cmp = compare_angles(T_MODEL, swing(T_MODEL), t, y)
    assert abs(cmp.lag_s - 1.234) <= FRAME_S


def test_mirrored_camera_detected_and_flip():
    lag = 0.8
    t, y = measure(crane_move, lag)
    mirrored = compare_angles(T_MODEL, crane_move(T_MODEL), t, -y)
    assert mirrored.mirrored
    flipped = compare_angles(T_MODEL, crane_move(T_MODEL), t, -y, flip=True)
    assert not flipped.mirrored and abs(flipped.lag_s - lag) <= FRAME_S
    assert flipped.rms_deg < 0.3


def test_given_lag_and_exact_errors():
    lag = 0.25
    t = np.arange(0.0, 3.0, FRAME_S)
    y = crane_move(t - lag) + np.radians(1.0)  # the camera is rolled by 1°
    y[10] = np.nan
    cmp = compare_angles(T_MODEL, crane_move(T_MODEL), t, y, lag_s=lag)
    assert not cmp.lag_estimated and cmp.lag_s == lag
    assert cmp.rms_deg == pytest.approx(1.0, abs=1e-3) and cmp.max_deg == pytest.approx(1.0, abs=1e-3)
    inside = (t >= lag) & np.isfinite(y)
    assert cmp.samples == inside.sum()
    assert cmp.overlap_s == pytest.approx(t[-1] - lag, abs=1e-9)
    np.testing.assert_allclose(cmp.measured - cmp.model, np.radians(1.0), atol=1e-5)  # 1 ms model grid


def test_no_overlap_and_constant_series_fail():
    t = np.arange(0.0, 2.0, FRAME_S)
    with pytest.raises(CheckFailed, match="no overlap"):
        compare_angles(T_MODEL, crane_move(T_MODEL), t, crane_move(t), lag_s=-10.0)
    with pytest.raises(CheckFailed):
        compare_angles(T_MODEL, np.zeros_like(T_MODEL), t, crane_move(t))
    with pytest.raises(CheckFailed):
        compare_angles(T_MODEL, crane_move(T_MODEL), t, np.full_like(t, np.nan))


def test_max_lag_limits_the_search():
    t, y = measure(crane_move, 1.9)
    est = estimate_lag(T_MODEL, crane_move(T_MODEL), t, y, max_lag_s=1.0)
    assert abs(est.lag_s) <= 1.0 + FRAME_S
    assert est.correlation < estimate_lag(T_MODEL, crane_move(T_MODEL), t, y).correlation


def test_resample_masks_gaps_and_outside():
    t = np.array([0.0, 0.1, 0.2, 0.6, 0.7])
    x = np.array([0.0, 1.0, 2.0, 6.0, np.nan])
    grid = np.array([-0.1, 0.05, 0.15, 0.4, 0.6, 0.65])
    out = resample(t, x, grid, max_gap_s=0.25)
    assert np.isnan(out[0]) and np.isnan(out[3]) and np.isnan(out[5])  # before, inside the gap, after the last valid
    np.testing.assert_allclose(out[[1, 2, 4]], [0.5, 1.5, 6.0])
