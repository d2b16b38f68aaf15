"""A ball hanging from a fixed pivot, its centres smoothed over a few frames, for video files only.

A low-bitrate codec moves the ball's colour by up to a pixel or two from frame to frame (blocks, chroma from a stale
reference), more than any single-frame centre can undo. The motion of a ball on a string is smooth where the codec's
error is not, and separates into two parts around the pivot:

- the string's length, constant while it is taut: fitted over ``RADIUS_HALF_S`` either side (a local quadratic),
  and used only where it changes by at most ``MAX_RADIUS_CHANGE_PX`` over that window (a slack string, or a camera
  that sees the plane of motion obliquely, where the image of the circle is not one, keep their measured centres);
- the angle, a local quadratic over ``ANGLE_HALF_S`` either side: the fit misses a pendulum's angle by
  3/35·θ''''·T⁴/24 (T the half-window), under a hundredth of a pixel for a 35° swing of 1 s on a 430 px string, so
  real motion is kept (a 150° swing-up: a few hundredths).

A frame keeps its measured centre when either fit needs both sides and lacks them, when the fit misses the frames it
was made of by more than ``MAX_RESIDUAL_PX`` RMS (motion that is not smooth: a string snapping taut, a hit), or when
it would move the centre by more than ``MAX_SHIFT_PX`` (something the fit cannot follow). Frames are taken as evenly
spaced (the decoder's frame index). The live sensor never smooths (a live fix is final, and this needs later frames).
"""

from __future__ import annotations

import math

import numpy as np

RADIUS_HALF_S = 0.25  # [s] the string's length is fitted over this either side of the frame
ANGLE_HALF_S = 0.05  # [s] the angle is fitted over this either side (at least MIN_HALF_FRAMES frames)
MIN_HALF_FRAMES = 2  # frames either side a fit needs at least (and one found on each side)
MAX_RESIDUAL_PX = 1.5  # [px] a fit whose frames lie farther than this from it (RMS) is not used
MAX_RADIUS_CHANGE_PX = 2.0  # [px] the fitted string length may change by this over its window (else not smoothed)
MAX_SHIFT_PX = 1.5  # [px] a smoothed centre farther than this from the measured one is not used
CIRCLE_SPREAD_PX = 4.0  # [px] the fixes' distances from the pivot (5th to 95th percentile) span at most this, or
CIRCLE_SPREAD_SHARE = 0.01  # ... this share of the string, for the image of the swing to be a circle about the pivot
CIRCLE_NOISE_SHARE = 0.05  # ... and the distances themselves (the codec's scatter included) at most this share
OUTLIER_HALF_S = 0.07  # [s] a fix is judged by a parabola through the fixes this far either side ...
OUTLIER_PX = 4.0  # [px] ... and taken out when it lies farther than this from it
OUTLIER_ROUNDS = 8  # at most this many rounds of taking the worst out


def local_quadratic(
    y: np.ndarray, ok: np.ndarray, half: int, leave_out: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per frame k, the least-squares parabola c0 + c1·j + c2·j² through the frames k+j, j = −half … half, where ``ok``:
    (coefficients (n, 3), RMS residual of those frames, usable). Usable needs ≥ 4 frames, one on each side. Frames evenly
    spaced; y (n,), ok (n,) bool. A window longer than the clip is cut to it. leave_out: frame k itself is left out
    of its own fit (the parabola then predicts it from its neighbours)."""
    half = min(half, (len(y) - 1) // 2)
    d = np.arange(-half, half + 1, dtype=float)
    keep = (d != 0) if leave_out else np.ones_like(d, bool)
    f = ok.astype(float)
    fy = np.where(ok, y, 0.0)

    def conv(a: np.ndarray, m: int) -> np.ndarray:  # Σ_j a[k+j]·j^m over the window, per k
        return np.convolve(a, (np.where(keep, d**m, 0.0))[::-1], mode="same")

    s = [conv(f, m) for m in range(5)]
    t = [conv(fy, m) for m in range(3)]
    a = np.stack([np.stack(s[i : i + 3], -1) for i in range(3)], -2)  # (n, 3, 3) normal equations, powers 0..2
    b = np.stack(t, -1)
    left = np.convolve(f, np.r_[np.zeros(half + 1), np.ones(half)], mode="same")  # found frames before k
    right = np.convolve(f, np.r_[np.ones(half), np.zeros(half + 1)], mode="same")  # ... and after k
    usable = ok & (s[0] >= 4) & (left >= 1) & (right >= 1)
    if leave_out:
        usable = (s[0] >= 4) & (left >= 2) & (right >= 2)
    safe = np.where(usable[:, None, None], a, np.eye(3))
    c = np.linalg.solve(safe, np.where(usable[:, None], b, 0.0)[..., None])[..., 0]
    u2 = conv(np.where(ok, y * y, 0.0), 0)
    sq = u2 - 2.0 * np.einsum("ni,ni->n", c, b) + np.einsum("ni,nij,nj->n", c, a, c)
    rms = np.sqrt(np.clip(sq, 0.0, None) / np.maximum(s[0], 1.0))
    return c, rms, usable


def smooth_centres(uv: np.ndarray, found: np.ndarray, pivot_uv: tuple[float, float], fps: float) -> np.ndarray:
    """The ball's centres [px] (n, 2) smoothed around a fixed pivot [px] (see the module); frames not found, and those
    the fits cannot vouch for, keep theirs. fps [1/s]: the frame rate (the windows are in seconds)."""
    uv = np.asarray(uv, float)
    found = np.asarray(found, bool) & np.all(np.isfinite(uv), axis=1)
    if found.sum() < 5 or not (math.isfinite(fps) and fps > 0):
        return uv.copy()
    d = uv - np.asarray(pivot_uv, float)
    r = np.hypot(d[:, 0], d[:, 1])
    th = np.unwrap(np.where(found, np.arctan2(d[:, 0], d[:, 1]), 0.0))
    half_r = max(MIN_HALF_FRAMES, round(RADIUS_HALF_S * fps))
    half_a = max(MIN_HALF_FRAMES, round(ANGLE_HALF_S * fps))
    r_fit, r_res, r_ok = local_quadratic(np.where(found, r, 0.0), found, half_r)
    a_fit, a_res, a_ok = local_quadratic(np.where(found, th, 0.0), found, half_a)
    ok = r_ok & a_ok & (r_res <= MAX_RESIDUAL_PX) & (a_res * r <= MAX_RESIDUAL_PX)
    ok &= np.abs(r_fit[:, 1]) * half_r + np.abs(r_fit[:, 2]) * half_r**2 <= MAX_RADIUS_CHANGE_PX
    out = np.asarray(pivot_uv, float) + r_fit[:, :1] * np.column_stack([np.sin(a_fit[:, 0]), np.cos(a_fit[:, 0])])
    ok &= np.hypot(*(out - uv).T) <= MAX_SHIFT_PX
    return np.where(ok[:, None], out, uv)


def on_circle(uv: np.ndarray, found: np.ndarray, pivot_uv: tuple[float, float]) -> bool:
    """The found centres [px] lie on a circle about the pivot [px]: a taut string seen square on. A camera that sees
    the plane of motion obliquely (an ellipse), a slack string, or a pivot given wrongly, is not — and the checks and
    fits that take the motion for a circle (:func:`outliers`, :mod:`tracking.model_look`) are not made.

    Judged on the part of the distances from the pivot that varies with the angle: their least-squares fit by the
    first two harmonics of the angle (a pivot given off moves the first, an ellipse the second) must span, 5th to
    95th percentile over the fixes, at most CIRCLE_SPREAD_PX or CIRCLE_SPREAD_SHARE of the string; and the
    distances themselves at most CIRCLE_NOISE_SHARE of it (a slack string). A low-bitrate codec scatters the
    centres frame by frame, not with the angle: on HEVC at 45 kbit/s the distances spanned 1.3 % of the string
    while their fit stayed on the circle, and the checks meant for such a codec were skipped."""
    uv = np.asarray(uv, float)
    ok = np.asarray(found, bool) & np.all(np.isfinite(uv), axis=1)
    if ok.sum() < 7:
        return False
    d = uv[ok] - np.asarray(pivot_uv, float)
    r = np.hypot(*d.T)
    th = np.arctan2(d[:, 0], d[:, 1])
    basis = np.column_stack([np.ones_like(th), np.cos(th), np.sin(th), np.cos(2 * th), np.sin(2 * th)])
    fit = basis @ np.linalg.lstsq(basis, r, rcond=None)[0]
    mid = float(np.median(r))
    lo, hi = np.percentile(fit, [5, 95])
    r_lo, r_hi = np.percentile(r, [5, 95])
    return bool(hi - lo <= max(CIRCLE_SPREAD_PX, CIRCLE_SPREAD_SHARE * mid) and r_hi - r_lo <= CIRCLE_NOISE_SHARE * mid)


def outliers(uv: np.ndarray, found: np.ndarray, pivot_uv: tuple[float, float], fps: float) -> np.ndarray:
    """(n,) bool: the fixes that their neighbours place elsewhere — farther than OUTLIER_PX along the swing from the
    parabola through the fixes within OUTLIER_HALF_S either side (the frame itself left out), or than OUTLIER_PX
    from the string's length there. A kink of the motion (a ball hit from rest, a catch) loses its fix at the kink
    too: unsure, never false. The worst in reach goes first and the rest are judged again without it (one
    far-off fix does not condemn its neighbours). A codec's ghost taken for the ball, a few pixels beside it."""
    uv = np.asarray(uv, float)
    ok = np.asarray(found, bool) & np.all(np.isfinite(uv), axis=1)
    out = np.zeros(len(ok), bool)
    if ok.sum() < 7 or not (math.isfinite(fps) and fps > 0):
        return out
    d = uv - np.asarray(pivot_uv, float)
    r = np.hypot(d[:, 0], d[:, 1])
    th = np.zeros(len(ok))
    th[ok] = np.unwrap(np.arctan2(d[ok, 0], d[ok, 1]))
    half_a = max(MIN_HALF_FRAMES, round(OUTLIER_HALF_S * fps))
    half_r = max(MIN_HALF_FRAMES, round(RADIUS_HALF_S * fps))
    for _ in range(OUTLIER_ROUNDS):
        r_fit, _, r_ok = local_quadratic(np.where(ok, r, 0.0), ok, half_r, leave_out=True)
        miss = np.where(r_ok, np.abs(r_fit[:, 0] - r), 0.0)
        a_fit, _, a_ok = local_quadratic(np.where(ok, th, 0.0), ok, half_a, leave_out=True)
        miss = np.where(ok, np.maximum(miss, np.where(a_ok, np.abs(a_fit[:, 0] - th) * r, 0.0)), 0.0)
        bad = miss > OUTLIER_PX
        if not bad.any():
            break
        peak = np.array([miss[k] >= miss[max(0, k - half_a) : k + half_a + 1].max() for k in range(len(miss))])
        worst = bad & peak
        out |= worst
        ok &= ~worst
    return out
