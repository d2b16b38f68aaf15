"""Smoothing a ball's centres around a fixed pivot: codec-like noise is reduced, real motion is kept, and what the fits
cannot vouch for (a jerk, a slack string, an oblique view, frames not found) keeps its measured centre."""

from __future__ import annotations

import math

import numpy as np

from tracking.smoothing import MAX_SHIFT_PX, local_quadratic, smooth_centres

PIVOT = (640.0, 110.0)  # [px]
FPS = 60.0


def _swing(
    seconds: float = 4.0, length_px: float = 430.0, amplitude_deg: float = 35.0, period_s: float = 1.0, fps: float = FPS
):
    t = np.arange(int(seconds * fps)) / fps
    th = math.radians(amplitude_deg) * np.exp(-0.1 * t) * np.sin(2 * np.pi * t / period_s)
    return np.column_stack([PIVOT[0] + length_px * np.sin(th), PIVOT[1] + length_px * np.cos(th)])


def _rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.nanmean(np.sum((a - b) ** 2, axis=1))))


def test_local_quadratic_is_exact_on_a_parabola_with_gaps_and_needs_both_sides():
    k = np.arange(40, dtype=float)
    y = 3.0 - 0.5 * k + 0.02 * k**2
    ok = np.ones(40, bool)
    ok[[10, 11, 25]] = False
    c, rms, usable = local_quadratic(np.where(ok, y, 0.0), ok, 3)
    assert np.allclose(c[usable, 0], y[usable], atol=1e-9)
    assert np.all(rms[usable] < 1e-6)
    assert not usable[[0, 39, 10, 25]].any()  # an end (no frame on one side) and the frames not found
    assert usable[12]  # one found frame before it (9) is enough


def test_codec_like_noise_is_reduced_and_a_clean_swing_is_left_where_it_is():
    truth = _swing()
    clean = smooth_centres(truth, np.ones(len(truth), bool), PIVOT, FPS)
    assert _rms(clean, truth) < 0.02  # real pendulum motion is not flattened
    noisy = truth + np.random.default_rng(1).normal(0.0, 0.6, truth.shape)
    got = smooth_centres(noisy, np.ones(len(truth), bool), PIVOT, FPS)
    assert _rms(got, truth) < 0.6 * _rms(noisy, truth)


def test_a_fast_swing_up_is_kept():
    truth = _swing(amplitude_deg=150.0, length_px=280.0)  # ≈ 2,800 px/s at the bottom
    got = smooth_centres(truth, np.ones(len(truth), bool), PIVOT, FPS)
    assert _rms(got, truth) < 0.05


def test_a_jerk_and_frames_not_found_keep_their_measured_centres():
    truth = _swing()
    meas = truth.copy()
    meas[100:] += np.array([0.0, 4.0])  # the string snaps 4 px longer at frame 100 (a re-tension, a hit)
    found = np.ones(len(meas), bool)
    found[50:53] = False
    meas[50:53] = np.nan
    got = smooth_centres(meas, found, PIVOT, FPS)
    assert np.all(np.isnan(got[50:53]))
    shift = np.hypot(*(got - meas).T)
    assert np.nanmax(shift) <= MAX_SHIFT_PX + 1e-9
    assert np.all(shift[97:103] < 1e-12)  # around the jump the fits miss their frames: not smoothed


def test_an_oblique_view_where_the_circle_is_an_ellipse_is_not_smoothed():
    truth = _swing()
    d = truth - np.array(PIVOT)
    ellipse = np.array(PIVOT) + d * np.array([1.0, 0.8])  # the plane of motion seen 37° off
    got = smooth_centres(ellipse, np.ones(len(ellipse), bool), PIVOT, FPS)
    assert np.array_equal(got, ellipse)  # left as measured (an ellipse's radius changes over the window) ...
    on_circle = smooth_centres(truth, np.ones(len(truth), bool), PIVOT, FPS)
    assert np.mean(np.any(on_circle != truth, axis=1)) > 0.9  # ... where the same swing seen square on is smoothed


def test_a_clip_shorter_than_the_string_length_window_is_smoothed_within_it():
    truth = _swing(seconds=0.3)  # 18 frames, the length window ±0.25 s would be 31
    noisy = truth + np.random.default_rng(2).normal(0.0, 0.6, truth.shape)
    got = smooth_centres(noisy, np.ones(len(truth), bool), PIVOT, FPS)
    assert _rms(got, truth) < _rms(noisy, truth)


def test_too_few_frames_are_returned_unchanged():
    truth = _swing(seconds=0.05)
    got = smooth_centres(truth, np.ones(len(truth), bool), PIVOT, FPS)
    assert np.array_equal(got, truth)


def test_outliers_are_the_ghosts_a_few_pixels_off_and_never_the_real_motion():
    from tracking.smoothing import outliers

    truth = _swing()
    rng = np.random.default_rng(4)
    meas = truth + rng.normal(0.0, 0.6, truth.shape)
    ghosts = {40: (6.0, 0.0), 41: (0.0, 7.0), 122: (-40.0, 10.0), 180: (4.0, 4.0)}  # a codec's ghosts taken for it
    for k, off in ghosts.items():
        meas[k] += off
    found = np.ones(len(meas), bool)
    assert set(np.flatnonzero(outliers(meas, found, PIVOT, FPS))) == set(ghosts)
    assert not outliers(truth + rng.normal(0.0, 0.6, truth.shape), found, PIVOT, FPS).any()
    fast = _swing(amplitude_deg=150.0, length_px=280.0, fps=30.0)
    assert not outliers(fast, np.ones(len(fast), bool), PIVOT, 30.0).any()  # a swing-up at 30 fps: ≈ 90 px a frame


def test_a_tracked_video_is_smoothed_and_no_worse_for_it(run):
    from tracking import scenarios
    from tracking.color import color_spec
    from tracking.pipeline import track_video

    sc, track, out = run("plain")
    raw = track_video(sc.path, color_spec("red"), smooth=False, **sc.track_kwargs)
    assert raw.smoothed_frames == 0 and raw.outlier_frames == 0
    assert track.smoothed_frames > 0.8 * len(track.t)
    assert track.outlier_frames == 0
    assert out.centre_rms_px <= scenarios.score(sc, raw).centre_rms_px


def test_a_swing_seen_square_on_is_on_a_circle_and_an_oblique_one_is_not():
    from tracking.smoothing import on_circle

    truth = _swing()
    found = np.ones(len(truth), bool)
    noisy = truth + np.random.default_rng(5).normal(0.0, 0.7, truth.shape)  # a low-bitrate codec's centres
    assert on_circle(noisy, found, PIVOT)
    ellipse = np.array(PIVOT) + (truth - np.array(PIVOT)) * np.array([1.0, 0.9])  # the plane seen 26° off
    assert not on_circle(ellipse, found, PIVOT)
    assert not on_circle(truth, found, (PIVOT[0] + 30.0, PIVOT[1]))  # a pivot given 30 px off


def test_a_ball_hit_from_rest_loses_at_most_the_frames_at_the_kink():
    from tracking.smoothing import outliers

    t = np.arange(240) / FPS
    s = np.clip(t - 0.3, 0.0, None)
    th = math.radians(32.0) * np.sin(2 * np.pi * s)  # hanging still, then hit: ≈ 25 px a frame at once
    uv = np.column_stack([PIVOT[0] + 430.0 * np.sin(th), PIVOT[1] + 430.0 * np.cos(th)])
    uv += np.random.default_rng(6).normal(0.0, 0.5, uv.shape)
    odd = np.flatnonzero(outliers(uv, np.ones(len(uv), bool), PIVOT, FPS))
    assert len(odd) <= 3 and all(abs(k - 18) <= 2 for k in odd), odd  # unsure there, never elsewhere


def test_a_codec_scattering_the_centres_more_than_the_spread_bound_still_sees_a_circle():
    """The distances from the pivot of a low-bitrate codec's centres scatter frame by frame (judge 9's HEVC at
    45 kbit/s: 1.3 % of the string, 5th to 95th percentile) but not with the angle: still a circle, and the checks
    are made. A camera 18° off square (an ellipse) or a pivot given 10 px aside vary with the angle: no circle."""
    from tracking.smoothing import CIRCLE_SPREAD_PX, CIRCLE_SPREAD_SHARE, on_circle

    truth = _swing()
    found = np.ones(len(truth), bool)
    noisy = truth + np.random.default_rng(7).normal(0.0, 2.5, truth.shape)
    r = np.hypot(*(noisy - np.array(PIVOT)).T)
    lo, mid, hi = np.percentile(r, [5, 50, 95])
    assert hi - lo > max(CIRCLE_SPREAD_PX, CIRCLE_SPREAD_SHARE * mid)  # wider than the bound on the fitted part
    assert on_circle(noisy, found, PIVOT)
    ellipse = np.array(PIVOT) + (noisy - np.array(PIVOT)) * np.array([1.0, 0.95])
    assert not on_circle(ellipse, found, PIVOT)
    assert not on_circle(noisy, found, (PIVOT[0] + 10.0, PIVOT[1]))
    slack = noisy + np.random.default_rng(8).normal(0.0, 15.0, truth.shape)  # a slack string: anywhere inside
    assert not on_circle(slack, found, PIVOT)
