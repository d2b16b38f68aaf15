"""The model look: the pendulum integrated and fitted, the runs it fills, the frames it lets through, and a video where
a pale ball (a codec's smear) is reported at the fitted place while a ghost beside it is not."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from tracking import model_look
from tracking.color import color_spec
from tracking.model_look import (
    MAX_FIT_RMS_PX,
    MAX_LOOK_FIT_RMS_PX,
    MIN_SHARE,
    MIN_SHARE_CENTRED,
    MAX_GAP_S,
    MAX_SPREAD_OUT_PX,
    MODEL_LOOK,
    PendulumFit,
    angles,
    fit_around,
    fit_pendulum,
    integrate,
    runs,
    shows_ball,
    spread_px,
    trajectory,
)
from tracking.pipeline import track_video

RED = color_spec("red")
FPS = 60.0
PIVOT = (320.0, 40.0)  # [px]
LENGTH = 180.0  # [px]


def _pendulum(n: int, theta0: float = 0.5, w2: float = 39.0, c: float = 0.1) -> np.ndarray:
    """θ [rad] of frames 0 … n−1 released at rest from theta0."""
    return integrate(theta0, 0.0, w2, c, 1.0 / FPS, n - 1)


def test_integration_matches_the_small_angle_solution():
    th = integrate(1e-3, 0.0, 40.0, 0.0, 1.0 / FPS, 120)
    t = np.arange(121) / FPS
    assert np.max(np.abs(th - 1e-3 * np.cos(math.sqrt(40.0) * t))) < 2e-8  # 2e-5 of the amplitude after 2 swings
    back = integrate(th[-1], -1e-3 * math.sqrt(40.0) * math.sin(math.sqrt(40.0) * 2.0), 40.0, 0.0, -1.0 / FPS, 120)
    assert abs(back[-1] - 1e-3) < 5e-8  # backwards in time to the start


def test_the_variational_equations_give_the_derivatives_of_the_integration():
    p = np.array([0.6, -1.5, 39.0, 0.2])  # θ₀ [rad], θ'₀ [rad/s], w2 [1/s²], c [1/s]: a 34° swing, damped
    for dt in (1.0 / FPS, -1.0 / FPS):
        got = trajectory(*p, dt, 90)
        assert np.max(np.abs(got[:, 0] - integrate(*p, dt, 90))) < 1e-12  # the same θ as the plain integration
        for i, step in enumerate((1e-6, 1e-6, 1e-5, 1e-6)):
            hi, lo = p.copy(), p.copy()
            hi[i] += step
            lo[i] -= step
            fd = (integrate(*hi, dt, 90) - integrate(*lo, dt, 90)) / (2 * step)
            assert np.max(np.abs(got[:, 1 + i] - fd)) < 1e-6 * max(1.0, np.max(np.abs(fd)))


def test_a_noisy_swing_is_fitted_and_its_spread_is_small_inside_and_grows_outside():
    th = _pendulum(150)
    frames = np.arange(40, 110)
    noisy = th[frames] + np.random.default_rng(3).normal(0.0, 0.5 / LENGTH, len(frames))  # 0.5 px along the arc
    fit = fit_pendulum(frames, noisy, LENGTH, FPS)
    assert fit is not None and 0.3 < fit.rms_px < 0.7
    assert abs(fit.w2 - 39.0) < 0.5
    miss = LENGTH * np.abs(angles(fit, np.arange(20, 40), FPS) - th[20:40])
    assert miss.max() < 1.0  # 20 frames before the window: still within a pixel
    s = spread_px(fit, np.array([75, 20, 0]), FPS)
    assert s[0] < s[1] < s[2]


def test_runs_are_the_frames_not_trusted_beside_trusted_ones_and_not_too_long():
    trusted = np.array([0, 0, 1, 1, 0, 1, 0, 0, 0, 0, 1], bool)
    assert runs(trusted, 3) == [(0, 2), (4, 5)]  # 6–9 is four frames long
    late = np.array([0, 0, 0, 0, 0, 1, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0], bool)  # runs of five at the start, four inside
    assert runs(late, 3, 5) == [(0, 5), (12, 16)]  # and four at the end: the edges may be longer
    assert runs(late, 3) == []
    # a run at an edge longer than edge_len: its edge_len frames next to the trusted ones (a ball tracked only late
    # in the video is placed back from its first fixes as far as a fit reaches)
    assert runs(late, 3, 2) == [(3, 5), (12, 14)]
    assert runs(np.zeros(6, bool), 3, 5) == []  # nothing trusted: nothing beside a run


def test_fixes_scattered_as_on_low_bitrate_hevc_still_place_the_frames_between():
    """Fixes scattered about 1.4 px about the pendulum (a ball on HEVC at a low bitrate): over the pendulum check's
    bound, within the look's; the frames between them are placed within 1 px of the true swing."""
    th = _pendulum(200)
    noisy = th + np.random.default_rng(3).normal(0.0, 1.4 / LENGTH, 200)
    trusted = np.ones(200, bool)
    trusted[90:94] = False
    placed = fit_around((90, 94), trusted, noisy, np.full(200, LENGTH), FPS)
    assert sorted(placed) == [90, 91, 92, 93]
    for k, fit in placed.items():
        assert MAX_FIT_RMS_PX < fit.rms_px <= MAX_LOOK_FIT_RMS_PX
        assert LENGTH * abs(angles(fit, np.array([k]), FPS)[0] - th[k]) < 1.0  # [px]


def test_a_gap_is_filled_and_a_push_beside_it_is_not_fitted_across():
    th = _pendulum(200)
    rate = (th[100] - th[98]) * FPS / 2.0
    th[100:] = integrate(th[100], rate + 1.5, 39.0, 0.1, 1.0 / FPS, 99)  # a push at frame 100: +1.5 rad/s
    trusted = np.ones(200, bool)
    trusted[60:66] = False
    radius = np.full(200, LENGTH)
    placed = fit_around((60, 66), trusted, th, radius, FPS)
    assert sorted(placed) == list(range(60, 66))
    for k, fit in placed.items():
        assert LENGTH * abs(angles(fit, np.array([k]), FPS)[0] - th[k]) < 0.2  # [px]
    trusted[102:105] = False  # right after the push: a window across it does not fit, the one after it does
    placed = fit_around((102, 105), trusted, th, radius, FPS)
    assert sorted(placed) == [102, 103, 104]
    for k, fit in placed.items():
        assert fit.anchor > 100
        assert LENGTH * abs(angles(fit, np.array([k]), FPS)[0] - th[k]) < 0.2  # [px]


def test_a_release_smeared_by_the_codec_is_placed_back_from_the_fixes_after_it_only_while_the_fit_is_tight():
    # a ball released from 30°: a low-bitrate codec's first 0.63 s show it as a smear (no fix), then it is tracked
    # with 1 px of noise; the frames nearest the fixes are placed, extrapolated back only while the fit's spread
    # stays within the bound for extrapolated frames (tighter than between fixes), none of them a pixel off
    th = _pendulum(240)
    trusted = np.ones(240, bool)
    trusted[:38] = False
    noisy = th + np.random.default_rng(5).normal(0.0, 1.0 / LENGTH, 240)
    assert (0, 38) in runs(trusted, round(MAX_GAP_S * FPS))
    placed = fit_around((0, 38), trusted, noisy, np.full(240, LENGTH), FPS)
    assert 5 <= len(placed) < 38 and max(placed) == 37 and sorted(placed) == list(range(min(placed), 38))
    for k, fit in placed.items():
        assert LENGTH * abs(angles(fit, np.array([k]), FPS)[0] - th[k]) < 1.0  # [px]
        assert spread_px(fit, np.array([k]), FPS)[0] <= MAX_SPREAD_OUT_PX


def _ball(img: np.ndarray, u: float, v: float, r: float, bgr) -> None:
    s = 16
    cv2.circle(img, (round(u * s), round(v * s)), round(r * s), bgr, -1, cv2.LINE_AA, shift=4)


def test_shows_ball_wants_the_colour_at_the_place():
    img = np.full((200, 200, 3), 90, np.uint8)
    _ball(img, 100.0, 100.0, 8.0, (90, 90, 140))  # pale red: saturation ≈ 91, under the colour's 100
    assert shows_ball(img, RED, 100.5, 99.5, 8.0)
    assert not shows_ball(img, RED, 110.0, 100.0, 8.0)  # 10 px off: not even half of the disc
    assert not shows_ball(img, RED, 50.0, 50.0, 8.0)


def test_a_smeared_ball_shows_when_its_colour_is_centred_on_the_place():
    """A fast ball smeared along its motion covers less than MIN_SHARE of its disc: it still shows where its colour
    is centred on the place (a released ball's first swing), not 3 px across the smear."""
    img = np.full((200, 200, 3), 90, np.uint8)
    cv2.rectangle(img, (70, 98), (130, 102), (40, 40, 200), -1)  # a streak 5 px high through (100, 100)
    ys, xs = np.mgrid[0:200, 0:200]
    share = float(np.mean(img[(xs - 100) ** 2 + (ys - 100) ** 2 <= 64][:, 2] == 200))
    assert MIN_SHARE_CENTRED <= share < MIN_SHARE  # the case: under the plain rule's share
    assert shows_ball(img, RED, 100.0, 100.0, 8.0)
    assert shows_ball(img, RED, 100.3, 99.8, 8.0)  # the fit's own error
    assert not shows_ball(img, RED, 100.0, 103.0, 8.0)  # 3 px across the streak: its colour is off centre
    assert not shows_ball(img, RED, 100.0, 106.0, 8.0)


def test_pale_frames_are_reported_at_the_fitted_place_and_a_ghost_is_not(tmp_path):
    """The first pass misses a ball paler than the colour's threshold; the model look reports it where the fitted
    pendulum is, only in the frames that show it there (not where a ghost lies 9 px off)."""
    n, r = 150, 7.0
    th = _pendulum(n, theta0=0.45)
    uv = np.column_stack([PIVOT[0] + LENGTH * np.sin(th), PIVOT[1] + LENGTH * np.cos(th)])
    path = tmp_path / "pale.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), FPS, (640, 260))
    pale, ghost = set(range(70, 75)), 73
    for k in range(n):
        img = np.full((260, 640, 3), 90, np.uint8)
        u, v = uv[k] + (np.array([9.0, 0.0]) if k == ghost else 0.0)
        _ball(img, u, v, r, (90, 90, 140) if k in pale else (30, 30, 220))  # pale: saturation ≈ 90
        writer.write(img)
    writer.release()
    track = track_video(path, RED, pivot_uv=PIVOT)
    assert not track.found[ghost]
    assert set(np.flatnonzero(track.confidence == MODEL_LOOK)) == pale - {ghost}
    err = np.linalg.norm(track.uv - uv, axis=1)
    assert np.nanmax(err[list(pale - {ghost})]) < 0.5
    assert track.model_look_frames == 4
    without = track_video(path, RED, pivot_uv=PIVOT, second_look=False)
    assert not without.found[list(pale)].any()  # the first pass alone misses them all


def test_a_fit_without_covariance_has_none():
    assert PendulumFit(0, 0.1, 0.0, 39.0, 0.0, LENGTH, 0.0).cov is None


# -- the compiled integration (tracking._rk4) against the pure-Python one: the same values to the last bit, forwards
# and backwards in time, and the fallback taken when the extension is not built

_compiled = pytest.mark.skipif(model_look._rk4 is None, reason="tracking._rk4 not built (no C compiler at install)")


def _cases(n: int):
    rng = np.random.default_rng(7)
    for _ in range(n):  # large swings, damping of either sign, 30-240 fps either way, numpy scalars as arguments
        p = (rng.uniform(-3.1, 3.1), rng.uniform(-12, 12), rng.uniform(1.0, 400.0), rng.uniform(-0.5, 2.0))
        dt = float(rng.choice([1 / 30, 1 / 60, -1 / 120, 1 / 240, -1 / 30]))
        yield np.float64(p[0]), p[1], p[2], p[3], dt, np.int64(rng.integers(0, 300))


@_compiled
def test_compiled_integration_equals_python_to_the_last_bit() -> None:
    for theta, rate, w2, c, dt, steps in _cases(200):
        a = model_look.integrate(theta, rate, w2, c, dt, steps)
        b = model_look.integrate_py(float(theta), rate, w2, c, dt, int(steps))
        assert a.shape == (steps + 1,) and np.array_equal(a, b)
        j = model_look.trajectory(theta, rate, w2, c, dt, steps)
        k = model_look.trajectory_py(float(theta), rate, w2, c, dt, int(steps))
        assert j.shape == (steps + 1, 5) and np.array_equal(j, k)
    out = model_look.integrate(0.3, 0.0, 39.0, 0.1, 1 / 60, 5)
    out[1:] = 0.0  # a writable array, as the pure-Python one (callers fill runs of frames from it)
    assert out[0] == 0.3


@_compiled
def test_compiled_integration_refuses_bad_arguments() -> None:
    with pytest.raises(TypeError):
        model_look._rk4.integrate(0.1, 0.0, 39.0, 0.1, 1 / 60)
    with pytest.raises(ValueError):
        model_look._rk4.trajectory(0.1, 0.0, 39.0, 0.1, 1 / 60, -1)
    with pytest.raises(TypeError):
        model_look._rk4.integrate("0.1", 0.0, 39.0, 0.1, 1 / 60, 3)


def test_fallback_without_the_extension(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(model_look, "_rk4", None)
    th = model_look.integrate(1e-3, 0.0, 40.0, 0.0, 1 / 60, 120)  # small swing: θ₀ cos(√w2 t)
    t = np.arange(121) / 60
    assert np.max(np.abs(th - 1e-3 * np.cos(np.sqrt(40.0) * t))) < 5e-8  # RK4 at 60 fps
    j = model_look.trajectory(1e-3, 0.0, 40.0, 0.0, 1 / 60, 120)
    assert j.shape == (121, 5) and np.array_equal(j[:, 0], th)
