"""The pendulum over sliding windows of a video file's track with a fixed pivot: fixes off it reported unsure, and
the centres of a noisy track put on it.

A low-bitrate codec moves the ball's colour by a pixel or two, alike in neighbouring frames (a stale reference's
chroma, blocks that move together), and now and then drags a fast ball's blob several pixels behind it (the ball and
its last place merged). A parabola over a few frames (:mod:`tracking.smoothing`) follows such errors; the pendulum
θ'' = −w2·sin θ − c·θ' over ``WINDOW_S`` does not. Per window (centred every half window; a frame is judged by the
window centred nearest to it), the pendulum is fitted to the trusted fixes (:func:`tracking.model_look.fit_pendulum`),
fitted again without the fixes more than ``TRIM_PX`` off it (a few at most), and used only when it then fits within
``model_look.MAX_FIT_RMS_PX`` (a push, a release, a catch or a slack string inside the window: not used). Then a fix
more than ``OFF_PX`` off it is reported unsure, and — only where the fixes scatter about it by at least
``MIN_NOISE_PX`` (the median's σ: a clean video's fixes are better than any model of them) — a fix is moved onto it: the fitted
angle at the window's median string length. A window with more bad fixes than the trim leaves out (a codec's images
of the ball frames ahead of it) gets a Cauchy-loss fit (:func:`_robust_window_fit`); off it, only fixes between fixes
on it are reported unsure, and none is moved. The live sensor never does this (it needs later frames).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .model_look import MAX_FIT_RMS_PX, PendulumFit, angles, fit_pendulum
from .smoothing import local_quadratic

WINDOW_S = 1.0  # [s] the pendulum is fitted over windows this long
TRIM_PX = 3.0  # [px] fixes farther than this from the first fit are left out of the second
MAX_TRIMMED = 3  # ... at most this many of them ...
MAX_TRIMMED_SHARE = 0.1  # ... or this share of the window's (else the window is not used)
ROBUST_MIN_SHARE = 0.75  # a window with more bad fixes than that is fitted robustly: kept when this share lies on it
ROBUST_BAND_PX = 6.0  # [px] ... within this of it
ROBUST_MAX_RMS_PX = 2.0  # [px] ... and the fit to those alone is within this (RMS)
OFF_PX = 4.0  # [px] a fix farther than this from the window's pendulum is reported unsure
CLEAN_PX = 0.4  # [px] a window whose every fix lies within this of the parabola through its neighbours (±3 frames)
# is clean: neither off nor noisy, left without a fit (a clean video costs no fits)
MIN_NOISE_PX = 0.3  # [px] the fixes are put on the pendulum only where they scatter about it by at least this
# (a robust σ: 1.4826 × the median miss — a few fixes cut by an occluder do not make a clean window noisy) ...
MIN_JITTER_PX = 0.35  # [px] ... and their misses change from frame to frame by at least this (robust σ of the change
# / √2: a codec's error alike in neighbouring frames shows only in part)


@dataclass(frozen=True)
class PendulumCheck:
    """Per frame: ``off`` (n,) bool, a trusted fix off its window's pendulum; ``uv`` (n, 2) [px] the place on the
    pendulum of each trusted fix to move there (NaN elsewhere)."""

    off: np.ndarray
    uv: np.ndarray

    @property
    def moved(self) -> np.ndarray:
        return np.all(np.isfinite(self.uv), axis=1)


def _window_fit(
    sel: np.ndarray, theta: np.ndarray, length_px: float, fps: float, guess: PendulumFit | None
) -> PendulumFit | None:
    """The pendulum fitted to the fixes sel (frame indices) and again without those more than TRIM_PX off it; None
    when it does not fit them within MAX_FIT_RMS_PX. guess: the previous window's fit to start from (from the
    fixes' own guess when that does not fit: a push between the windows)."""
    for start in (guess, None) if guess is not None else (None,):
        fit = fit_pendulum(sel, theta[sel], length_px, fps, start)
        if fit is None:
            return None
        keep = np.abs(length_px * (angles(fit, sel, fps) - theta[sel])) <= TRIM_PX
        if (~keep).sum() > max(MAX_TRIMMED, MAX_TRIMMED_SHARE * len(sel)):  # a push or a release, not a few bad fixes
            continue
        if not keep.all():
            fit = fit_pendulum(sel[keep], theta[sel[keep]], length_px, fps, fit)
        if fit is not None and fit.rms_px <= MAX_FIT_RMS_PX:
            return fit
    return None


def _robust_window_fit(
    sel: np.ndarray, theta: np.ndarray, length_px: float, fps: float, guess: PendulumFit | None
) -> PendulumFit | None:
    """For a window with more bad fixes than the trimmed fit leaves out (a low-bitrate codec's images of the ball a
    frame or more ahead of it, or behind): a Cauchy-loss fit of scale TRIM_PX, kept only when at least
    ROBUST_MIN_SHARE of the fixes lie within TRIM_PX of it and the plain fit to those alone is within MAX_FIT_RMS_PX
    (a push or a release leaves fewer on any one pendulum)."""
    for start in (guess, None) if guess is not None else (None,):
        fit = fit_pendulum(sel, theta[sel], length_px, fps, start, robust_px=TRIM_PX)
        if fit is None:
            return None
        keep = np.abs(length_px * (angles(fit, sel, fps) - theta[sel])) <= ROBUST_BAND_PX
        if keep.sum() < ROBUST_MIN_SHARE * len(sel):
            continue
        fit = fit_pendulum(sel[keep], theta[sel[keep]], length_px, fps, fit)
        if fit is not None and fit.rms_px <= ROBUST_MAX_RMS_PX:
            return fit
    return None


def _rough_px(arc_px: np.ndarray, trusted: np.ndarray) -> np.ndarray:
    """Per frame, how far [px] a trusted fix lies from the parabola through its neighbours' (±3 frames, itself left
    out); inf where that cannot be told (too few neighbours)."""
    c, _, usable = local_quadratic(np.where(trusted, arc_px, 0.0), trusted, 3, leave_out=True)
    return np.where(usable, np.abs(c[:, 0] - arc_px), np.inf)


def _noisy(frames: np.ndarray, miss_px: np.ndarray) -> bool:
    """The window's fixes (frame indices, their misses of the pendulum [px]) scatter about it by MIN_NOISE_PX at
    least (robust σ, 1.4826 × the median) and jitter from frame to frame by MIN_JITTER_PX at least (the same of the
    change of the miss between consecutive frames, / √2): a miss that changes slowly is the model's (a release, a
    swing that is not quite a pendulum's), not the fixes' noise."""
    step = np.diff(miss_px)[np.diff(frames) == 1]
    jitter = 1.4826 * float(np.median(np.abs(step))) / np.sqrt(2.0) if len(step) else 0.0
    return 1.4826 * float(np.median(np.abs(miss_px))) >= MIN_NOISE_PX and jitter >= MIN_JITTER_PX


def check(uv: np.ndarray, trusted: np.ndarray, pivot_uv: tuple[float, float], fps: float) -> PendulumCheck:
    """The pendulum check of a track (see the module): uv (n, 2) [px] the centres, trusted (n,) bool the fixes to
    judge, pivot_uv [px] fixed, fps [1/s] (frames evenly spaced)."""
    uv, trusted = np.asarray(uv, float), np.asarray(trusted, bool) & np.all(np.isfinite(uv), axis=1)
    n = len(uv)
    off, out = np.zeros(n, bool), np.full((n, 2), np.nan)
    d = uv - np.asarray(pivot_uv, float)
    theta = np.zeros(n)
    theta[trusted] = np.unwrap(np.arctan2(d[trusted, 0], d[trusted, 1]))
    length = np.hypot(d[:, 0], d[:, 1])
    half = max(3, round(0.5 * WINDOW_S * fps))
    rough = _rough_px(theta * np.median(length[trusted]) if trusted.any() else theta, trusted)
    guess = None
    for c in range(0, n + half // 2, half):  # (the last window's nearest frames reach the end)
        lo, hi = max(0, c - half), min(n, c + half + 1)
        sel = lo + np.flatnonzero(trusted[lo:hi])
        if np.all(rough[sel] <= CLEAN_PX):
            continue
        length_px = float(np.median(length[sel])) if len(sel) else 0.0
        plain = _window_fit(sel, theta, length_px, fps, guess) if len(sel) else None
        robust = plain is None and len(sel) > 0
        guess = plain  # (a robust fit is not the next window's start)
        fit = _robust_window_fit(sel, theta, length_px, fps, plain) if robust else plain
        if fit is None:
            continue
        inner = sel[(sel >= c - half // 2) & (sel < c - half // 2 + half)]  # the frames nearest to this centre
        th = angles(fit, inner, fps)
        miss = length_px * np.abs(th - theta[inner])
        if robust:  # only misses between fixes on it (a push or a release leaves the window's end off it): none moved
            on_it = sel[length_px * np.abs(angles(fit, sel, fps) - theta[sel]) <= OFF_PX]
            off[inner[(miss > OFF_PX) & (inner > on_it.min()) & (inner < on_it.max())]] = True
            continue
        off[inner[miss > OFF_PX]] = True
        if _noisy(sel, length_px * (angles(fit, sel, fps) - theta[sel])):
            on = inner[miss <= OFF_PX]
            th = th[miss <= OFF_PX]
            out[on] = np.asarray(pivot_uv, float) + length_px * np.column_stack([np.sin(th), np.cos(th)])
    return PendulumCheck(off, out)
