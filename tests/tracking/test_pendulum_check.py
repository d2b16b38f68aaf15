"""The pendulum check: over each window a fix dragged off the pendulum is found, codec-like noise alike in neighbouring
frames is taken out, a clean track is left as measured, and a push inside a window marks no fix off."""

from __future__ import annotations

import numpy as np

from tracking.model_look import integrate
from tracking.pendulum_check import check

PIVOT = (640.0, 110.0)  # [px]
LENGTH = 430.0  # [px]
FPS = 60.0


def _uv(theta: np.ndarray) -> np.ndarray:
    return np.column_stack([PIVOT[0] + LENGTH * np.sin(theta), PIVOT[1] + LENGTH * np.cos(theta)])


def _swing(n: int = 240) -> np.ndarray:
    return integrate(0.6, 0.0, 39.0, 0.1, 1.0 / FPS, n - 1)  # a 34° swing of 1 s, damped


def _codec_noise(n: int, px: float, seed: int) -> np.ndarray:
    """(n, 2) [px] a codec-like error, px RMS per axis: half its variance alike in neighbouring frames (white noise
    averaged over 4 frames), half new in each frame."""
    w = np.random.default_rng(seed).normal(0.0, 1.0, (n + 4, 2))
    alike = (w[:-4] + w[1:-3] + w[2:-2] + w[3:-1]) / 2.0
    return px * np.sqrt(0.5) * (alike + w[4:])


def _rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum((a - b) ** 2, axis=1))))


def test_noise_alike_in_neighbouring_frames_is_taken_out_and_a_dragged_fix_is_off():
    th = _swing()
    truth = _uv(th)
    uv = truth + _codec_noise(len(th), 0.9, 1)
    k = 119  # a fast frame, the blob dragged 6 px behind the ball along its motion
    step = truth[k] - truth[k - 1]
    uv[k] -= 6.0 * step / np.linalg.norm(step)
    got = check(uv, np.ones(len(th), bool), PIVOT, FPS)
    assert np.flatnonzero(got.off).tolist() == [k]
    moved = got.moved
    assert moved.sum() > 0.9 * len(th) and not moved[k]
    assert _rms(got.uv[moved], truth[moved]) < 0.6 * _rms(uv[moved], truth[moved])


def test_a_clean_track_is_left_as_measured_even_with_a_few_fixes_off_by_pixels():
    th = _swing()
    uv = _uv(th) + np.random.default_rng(2).normal(0.0, 0.05, (len(th), 2))
    uv[[50, 52, 55, 57, 120, 180]] += 2.0  # a few fixes cut by an occluder: the window is still clean
    got = check(uv, np.ones(len(th), bool), PIVOT, FPS)
    assert not got.off.any() and not got.moved.any()


def test_a_push_inside_a_window_marks_no_fix_off_and_frames_not_trusted_are_not_judged():
    a = integrate(0.0, 0.0, 39.0, 0.1, 1.0 / FPS, 119)  # at rest ...
    b = integrate(0.0, 2.5, 39.0, 0.1, 1.0 / FPS, 120)[1:]  # ... hit at frame 120 (2.5 rad/s at once)
    th = np.r_[a, b]
    uv = _uv(th) + _codec_noise(len(th), 0.3, 3)
    trusted = np.ones(len(th), bool)
    trusted[[30, 31, 200]] = False
    uv[[30, 31, 200]] += 20.0  # not trusted: neither judged nor moved
    got = check(uv, trusted, PIVOT, FPS)
    assert not got.off.any()
    assert not got.moved[[30, 31, 200]].any()


def test_images_of_the_ball_frames_ahead_are_off_even_when_they_are_many():
    """A low-bitrate codec shows the ball where it will be one to three frames later in a fifth of the frames of each
    window (more than the trimmed fit leaves out, so that fit fails): the robust fit still finds the pendulum, and
    exactly those fixes are off; none is moved."""
    th = _swing()
    truth = _uv(th)
    uv = truth + np.random.default_rng(3).normal(0.0, 0.4, (len(th), 2))
    rng = np.random.default_rng(4)
    ahead = np.sort(rng.choice(np.arange(5, len(th) - 5), size=len(th) // 5, replace=False))
    lead = rng.integers(1, 4, size=len(ahead))
    far = (
        np.linalg.norm(truth[ahead + lead] - truth[ahead], axis=1) > 6.0
    )  # (slow frames near a turning point: not off)
    uv[ahead] = truth[ahead + lead]
    got = check(uv, np.ones(len(th), bool), PIVOT, FPS)
    assert set(np.flatnonzero(got.off)) >= set(ahead[far])
    assert set(np.flatnonzero(got.off)) <= set(ahead)
    assert not got.moved.any()
