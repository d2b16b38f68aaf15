"""A look guided by the pendulum's motion, for video files with a fixed pivot: the frames not found between or next to
trusted fixes, where the decoded frame shows the ball's colour where a pendulum fitted to those fixes puts the ball.

At a low bitrate the encoder's first frames and a fast ball's frames are blocks: the ball's colour is there, but no
blob has the ball's shape, and a centroid of the blocks is off by 2–5 px. The motion around them is well measured.
So, per run of frames not found (at most ``MAX_GAP_S`` long), a pendulum θ'' = −ω²·sin θ − c·θ' about the fixed pivot
(string length the median of the fixes') is fitted to the trusted fixes in one of ``WINDOWS`` around the run (the first
window that the pendulum fits within ``MAX_LOOK_FIT_RMS_PX``, and the ``NEAR_FIXES`` fixes nearest the run within
``MAX_NEAR_RMS_PX``: a push, a release or a catch inside a window makes it fail; and that places the frame to within
``MAX_SPREAD_PX``, one standard deviation from the fit's covariance). A frame is then reported at the fitted place, with
confidence ``MODEL_LOOK``, only when the frame shows the ball there: at least ``MIN_SHARE`` of the ball's disc in its
colour, the colour's centroid within ``MAX_OFF_RADII`` ball radii of the fitted place (or ``MIN_SHARE_CENTRED``
within ``MAX_OFF_CENTRED_RADII``: a ball smeared along its motion), and the place not one the
tracker found static in the ball's colour, excluded, or out of the string's reach. The live sensor never does this.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from .color import ColorSpec, color_mask, with_min_saturation
from .detect import Blob
from .patches import Patch
from .tracker import BallTracker

try:  # the compiled integration (setup.py builds it when a C compiler is present); else the pure-Python one below
    from . import _rk4
except ImportError:  # pragma: no cover - depends on the install
    _rk4 = None

MODEL_LOOK = 0.6  # confidence of a frame reported by the model look
MAX_GAP_S = 0.7  # [s] runs of frames not found longer than this are left alone (a released ball smeared
# by a codec's first frames lasts 0.5-0.6 s)
WINDOWS = ((1.2, 1.2), (0.6, 0.6), (0.3, 0.3), (0.0, 0.6), (0.6, 0.0), (0.0, 0.3), (0.3, 0.0))  # [s] (before, after)
# a run: fit windows tried in this order, the longest first, then one side only (a push or a release on the other)
MIN_FIXES = 12  # trusted fixes a fit needs at least
MAX_FIT_RMS_PX = 1.2  # [px] the pendulum check's bound on a window's fit (RMS; tracking.pendulum_check)
MAX_LOOK_FIT_RMS_PX = 1.6  # [px] the look's: the pendulum must fit the window's fixes within this (RMS; the fixes of
# a ball on low-bitrate HEVC scatter about 1.4 px about a pendulum that places the frames between them within 1 px) ...
NEAR_FIXES = 6  # ... and the fixes nearest the run within
MAX_NEAR_RMS_PX = 2.0  # ... this [px] (RMS)
MAX_SPREAD_PX = (
    1.0  # [px] a frame is placed only where the fit's standard deviation there is at most this (the true miss
)
# can be 3× that: the codec's errors of neighbouring frames are alike, which the covariance does not know) ...
MAX_SPREAD_OUT_PX = 0.7  # [px] ... or this, in a run longer than SHORT_GAP_S where the frame lies outside the
# window's fixes (extrapolated far: the model's own error — damping, the codec's lag of a fast ball — grows there
# faster than its covariance says)
SHORT_GAP_S = 0.4  # [s]
MAX_EDGE_GAP_S = 1.5  # [s] of a run at the video's start or end, the frames this close to the fixes are looked at
# (no push beyond it to fit across; its frames are all extrapolated, each placed only within MAX_SPREAD_OUT_PX)
MIN_SHARE = 0.45  # share of the ball's disc at the fitted place that must be in its colour ...
MIN_SATURATION = 60  # ... (its hue, at least this saturated)
MAX_OFF_RADII = 0.4  # ... and the colour's centroid there within this many ball radii (at least 3 px) of it;
MIN_SHARE_CENTRED = 0.3  # or this share, with the colour centred on the place within MAX_OFF_CENTRED_RADII (no
MAX_OFF_CENTRED_RADII = 0.25  # floor in px): a released ball's first swing smeared by motion blur and the codec


@dataclass(frozen=True)
class PendulumFit:
    """θ(t) of a pendulum about a fixed pivot from frame ``anchor``: θ'' = −w2·sin θ − c·θ' (θ from the downward
    vertical towards +u [rad], t [s]); ``length_px`` the string's length, ``rms_px`` the fit's RMS miss [px]."""

    anchor: int
    theta: float  # [rad] at the anchor frame
    rate: float  # [rad/s] at the anchor frame
    w2: float  # [1/s²]
    c: float  # [1/s]
    length_px: float
    rms_px: float
    cov: np.ndarray | None = None  # (4, 4) covariance of (theta, rate, w2, c)


def integrate(theta: float, rate: float, w2: float, c: float, dt: float, steps: int) -> np.ndarray:
    """θ [rad] at 0, dt, …, steps·dt (dt may be negative: backwards in time) by classical Runge–Kutta (compiled
    when built: the same values to the last bit as :func:`integrate_py`, about a hundred times faster)."""
    if _rk4 is not None:
        return np.frombuffer(_rk4.integrate(theta, rate, w2, c, dt, steps))
    return integrate_py(theta, rate, w2, c, dt, steps)


def trajectory(theta: float, rate: float, w2: float, c: float, dt: float, steps: int) -> np.ndarray:
    """(steps + 1, 5): θ [rad] at 0, dt, …, steps·dt and its derivatives by (θ₀, θ'₀, w2, c) (compiled when built,
    as :func:`integrate`; else :func:`trajectory_py`)."""
    if _rk4 is not None:
        return np.frombuffer(_rk4.trajectory(theta, rate, w2, c, dt, steps)).reshape(steps + 1, 5)
    return trajectory_py(theta, rate, w2, c, dt, steps)


def integrate_py(theta: float, rate: float, w2: float, c: float, dt: float, steps: int) -> np.ndarray:
    """:func:`integrate` in pure Python (the fallback without the compiled extension)."""
    out = np.empty(steps + 1)
    out[0] = theta
    y, z = theta, rate
    for i in range(steps):
        k1y, k1z = z, -w2 * math.sin(y) - c * z
        y2, z2 = y + 0.5 * dt * k1y, z + 0.5 * dt * k1z
        k2y, k2z = z2, -w2 * math.sin(y2) - c * z2
        y3, z3 = y + 0.5 * dt * k2y, z + 0.5 * dt * k2z
        k3y, k3z = z3, -w2 * math.sin(y3) - c * z3
        y4, z4 = y + dt * k3y, z + dt * k3z
        k4y, k4z = z4, -w2 * math.sin(y4) - c * z4
        y += dt / 6.0 * (k1y + 2 * k2y + 2 * k3y + k4y)
        z += dt / 6.0 * (k1z + 2 * k2z + 2 * k3z + k4z)
        out[i + 1] = y
    return out


def trajectory_py(theta: float, rate: float, w2: float, c: float, dt: float, steps: int) -> np.ndarray:
    """:func:`trajectory` in pure Python: θ [rad] and its derivatives by (θ₀, θ'₀, w2, c) — the pendulum and its
    variational equations (a' = b, b' = −w2·cos θ·a − c·b − [sin θ for w2, θ' for c]) by classical Runge–Kutta in one
    pass: the least-squares fit's Jacobian without finite differences (written out: Python's cost is per operation)."""
    rows = [(theta, 1.0, 0.0, 0.0, 0.0)]
    y, z = theta, rate
    a0, b0, a1, b1, a2, b2, a3, b3 = 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0
    h2, h6, sin, cos = 0.5 * dt, dt / 6.0, math.sin, math.cos
    for _ in range(steps):
        s, m = sin(y), -w2 * cos(y)  # the first stage: the rates at the state itself
        p = (
            z,
            -w2 * s - c * z,
            b0,
            m * a0 - c * b0,
            b1,
            m * a1 - c * b1,
            b2,
            m * a2 - c * b2 - s,
            b3,
            m * a3 - c * b3 - z,
        )
        q = _stage(y, z, a0, b0, a1, b1, a2, b2, a3, b3, *p, h2, w2, c, sin, cos)
        r = _stage(y, z, a0, b0, a1, b1, a2, b2, a3, b3, *q, h2, w2, c, sin, cos)
        t = _stage(y, z, a0, b0, a1, b1, a2, b2, a3, b3, *r, dt, w2, c, sin, cos)
        y += h6 * (p[0] + 2.0 * q[0] + 2.0 * r[0] + t[0])
        z += h6 * (p[1] + 2.0 * q[1] + 2.0 * r[1] + t[1])
        a0 += h6 * (p[2] + 2.0 * q[2] + 2.0 * r[2] + t[2])
        b0 += h6 * (p[3] + 2.0 * q[3] + 2.0 * r[3] + t[3])
        a1 += h6 * (p[4] + 2.0 * q[4] + 2.0 * r[4] + t[4])
        b1 += h6 * (p[5] + 2.0 * q[5] + 2.0 * r[5] + t[5])
        a2 += h6 * (p[6] + 2.0 * q[6] + 2.0 * r[6] + t[6])
        b2 += h6 * (p[7] + 2.0 * q[7] + 2.0 * r[7] + t[7])
        a3 += h6 * (p[8] + 2.0 * q[8] + 2.0 * r[8] + t[8])
        b3 += h6 * (p[9] + 2.0 * q[9] + 2.0 * r[9] + t[9])
        rows.append((y, a0, a1, a2, a3))
    return np.array(rows)


def _stage(y, z, a0, b0, a1, b1, a2, b2, a3, b3, k0, k1, k2, k3, k4, k5, k6, k7, k8, k9, h, w2, c, sin, cos) -> tuple:  # noqa: ANN001
    """The rates of (θ, θ', the four sensitivity pairs) at the state moved by h·k (one Runge–Kutta stage)."""
    y, z = y + h * k0, z + h * k1
    a0, b0, a1, b1 = a0 + h * k2, b0 + h * k3, a1 + h * k4, b1 + h * k5
    a2, b2, a3, b3 = a2 + h * k6, b2 + h * k7, a3 + h * k8, b3 + h * k9
    s, m = sin(y), -w2 * cos(y)
    return (
        z,
        -w2 * s - c * z,
        b0,
        m * a0 - c * b0,
        b1,
        m * a1 - c * b1,
        b2,
        m * a2 - c * b2 - s,
        b3,
        m * a3 - c * b3 - z,
    )


def _along(fit: PendulumFit, frames: np.ndarray, fps: float, path) -> np.ndarray:  # noqa: ANN001
    """path(θ, θ', w2, c, dt, steps) run forwards and backwards from the anchor, taken at the frame indices."""
    frames = np.asarray(frames, int)
    out: np.ndarray | None = None
    for sign in (1, -1):
        sel = (frames - fit.anchor) * sign >= 0
        if sel.any():
            steps = int(np.max(np.abs(frames[sel] - fit.anchor)))
            got = path(fit.theta, fit.rate, fit.w2, fit.c, sign / fps, steps)
            if out is None:
                out = np.empty((len(frames), *got.shape[1:]))
            out[sel] = got[np.abs(frames[sel] - fit.anchor)]
    return out if out is not None else np.empty(0)


def angles(fit: PendulumFit, frames: np.ndarray, fps: float) -> np.ndarray:
    """θ [rad] of the fit at the frame indices (evenly spaced at fps [1/s])."""
    return _along(fit, frames, fps, integrate)


def angles_jac(fit: PendulumFit, frames: np.ndarray, fps: float) -> np.ndarray:
    """(len(frames), 5): θ [rad] of the fit at the frame indices and its derivatives by (θ, θ', w2, c)."""
    return _along(fit, frames, fps, trajectory)


def fit_pendulum(
    frames: np.ndarray,
    theta: np.ndarray,
    length_px: float,
    fps: float,
    guess: PendulumFit | None = None,
    robust_px: float | None = None,
) -> PendulumFit | None:
    """The pendulum that best fits θ [rad] at the frame indices (least squares in px along the string's arc,
    Levenberg–Marquardt with the variational equations' Jacobian), from the frame nearest their middle, with the
    covariance of its parameters (θ, θ', w2, c) in ``cov``; None when there are too few fixes. guess: a fit of
    the same motion nearby (an overlapping window) to start from: fewer iterations. robust_px [px]: a Cauchy loss
    of that scale instead (trust-region reflective), so that misses far beyond it barely pull the fit."""
    frames, theta = np.asarray(frames, int), np.asarray(theta, float)
    if len(frames) < MIN_FIXES:
        return None
    k = int(np.argmin(np.abs(frames - np.median(frames))))
    anchor = int(frames[k])
    lo, hi = max(k - 1, 0), min(k + 1, len(frames) - 1)
    rate0 = (theta[hi] - theta[lo]) * fps / max(1, frames[hi] - frames[lo])
    last: dict[bytes, np.ndarray] = {}  # the residuals and the Jacobian come from one integration

    def run(p: np.ndarray) -> np.ndarray:
        key = p.tobytes()
        if key not in last:
            last.clear()
            last[key] = angles_jac(PendulumFit(anchor, p[0], p[1], p[2], p[3], length_px, 0.0), frames, fps)
        return last[key]

    p0 = [theta[k], rate0, _w2_guess(frames, theta, fps), 0.0]
    if guess is not None:  # its angle and rate at this anchor (central difference: only a start)
        th = angles(guess, np.array([anchor - 1, anchor, anchor + 1]), fps)
        p0 = [th[1], 0.5 * (th[2] - th[0]) * fps, guess.w2, guess.c]
    with np.errstate(all="ignore"):  # a diverging trial step overflows; LM then shortens it
        sol = least_squares(
            lambda p: length_px * (run(p)[:, 0] - theta),
            p0,
            jac=lambda p: length_px * run(p)[:, 1:],
            method="lm" if robust_px is None else "trf",
            loss="linear" if robust_px is None else "cauchy",
            f_scale=1.0 if robust_px is None else robust_px,
            x_scale=[0.1, 1.0, 10.0, 0.1],
            max_nfev=60,
            ftol=1e-6,  # a fit's RMS to a thousandth of a pixel is enough: fewer iterations
            xtol=1e-6,
            gtol=1e-6,
        )
    if not np.all(np.isfinite(sol.fun)) or not np.all(np.isfinite(sol.jac)):
        return None
    dof = max(len(frames) - 4, 1)
    sigma2 = float(np.sum(sol.fun**2)) / dof
    try:
        cov = np.linalg.inv(sol.jac.T @ sol.jac) * sigma2
    except np.linalg.LinAlgError:
        return None
    rms = float(np.sqrt(np.mean(sol.fun**2)))
    return PendulumFit(anchor, *map(float, sol.x), length_px, rms, cov)


def spread_px(fit: PendulumFit, frames: np.ndarray, fps: float) -> np.ndarray:
    """Standard deviation [px] of the fitted place at the frame indices, from the parameters' covariance."""
    grad = angles_jac(fit, frames, fps)[:, 1:]
    var = np.einsum("ni,ij,nj->n", grad, fit.cov, grad)
    return fit.length_px * np.sqrt(np.clip(var, 0.0, None))


def _w2_guess(frames: np.ndarray, theta: np.ndarray, fps: float) -> float:
    """ω² [1/s²] from θ'' ≈ −ω²·sin θ over consecutive triples of fixes ((2π)², a 1 s swing, when they tell nothing)."""
    triple = (frames[2:] - frames[1:-1] == 1) & (frames[1:-1] - frames[:-2] == 1)
    acc = (theta[2:] - 2 * theta[1:-1] + theta[:-2]) * fps * fps
    s = np.sin(theta[1:-1])
    den = float(np.sum(s[triple] ** 2))
    w2 = -float(np.sum(acc[triple] * s[triple])) / den if den > 1e-6 else math.nan
    return w2 if math.isfinite(w2) and w2 > 0 else (2 * math.pi) ** 2


def runs(trusted: np.ndarray, max_len: int, edge_len: int | None = None) -> list[tuple[int, int]]:
    """(first, last + 1) of each run of frames not trusted, at most max_len long, with a trusted frame beside it; a
    run at the video's start or end (edge_len, when given) is cut to its edge_len frames next to the trusted ones
    (farther from them, no fit would place a frame anyway)."""
    n = len(trusted)
    edges = np.flatnonzero(np.diff(np.r_[False, ~np.asarray(trusted, bool), False].astype(np.int8)))
    out = []
    for a, b in zip(edges[::2], edges[1::2]):
        if a == 0 and b == n:
            continue
        if edge_len is not None and (a == 0 or b == n):
            a, b = (max(a, b - edge_len), b) if a == 0 else (a, min(b, a + edge_len))
        elif b - a > max_len:
            continue
        out.append((int(a), int(b)))
    return out


def fit_around(
    run: tuple[int, int],
    trusted: np.ndarray,
    theta: np.ndarray,
    radius: np.ndarray,
    fps: float,
    cache: dict | None = None,
) -> dict[int, PendulumFit]:
    """Per frame of the run, the pendulum it is placed by: the first of the windows around the run (both sides, the
    longest first, then one side only: a push or a release on the other) that the pendulum fits (see the module) and
    that places that frame to within MAX_SPREAD_PX (one standard deviation). cache: fits by window, kept between runs."""
    cache = {} if cache is None else cache
    first, end = run
    idx = np.flatnonzero(trusted)
    out: dict[int, PendulumFit] = {}
    for before_s, after_s in WINDOWS:
        sel = idx[(idx >= first - round(before_s * fps)) & (idx < end + round(after_s * fps))]
        if len(sel) < MIN_FIXES:
            continue
        key = (int(sel[0]), int(sel[-1]), len(sel))
        if key not in cache:  # runs close together share windows
            cache[key] = fit_pendulum(sel, theta[sel], float(np.median(radius[sel])), fps)
        fit = cache[key]
        if fit is None or fit.rms_px > MAX_LOOK_FIT_RMS_PX:
            continue
        near = sel[np.argsort(np.minimum(np.abs(sel - first), np.abs(sel - (end - 1))))[:NEAR_FIXES]]
        miss = fit.length_px * (angles(fit, near, fps) - theta[near])
        if float(np.sqrt(np.mean(miss**2))) > MAX_NEAR_RMS_PX:
            continue
        todo = np.array([k for k in range(first, end) if k not in out], int)
        # (a long run's frames outside the window's fixes, extrapolated: held to MAX_SPREAD_OUT_PX)
        between = (todo > sel[0]) & (todo < sel[-1]) | (end - first <= round(SHORT_GAP_S * fps))
        for k, s, inner in zip(todo, spread_px(fit, todo, fps), between):
            if s <= (MAX_SPREAD_PX if inner else MAX_SPREAD_OUT_PX):
                out[int(k)] = fit
        if len(out) == end - first:
            break
    return out


def shows_ball(
    bgr: np.ndarray, spec: ColorSpec, u: float, v: float, radius_px: float, origin: tuple[int, int] = (0, 0)
) -> bool:
    """The frame shows the ball's colour at (u, v) [px]: MIN_SHARE of the disc of radius_px there, its centroid
    within MAX_OFF_RADII radii (≥ 3 px), or MIN_SHARE_CENTRED with the centroid within MAX_OFF_CENTRED_RADII. origin: bgr is a patch of the frame whose first pixel is the frame's (x, y)
    (False when the disc is not inside it)."""
    import cv2

    h, w = bgr.shape[:2]
    ox, oy = origin
    x0, y0, x1, y1 = disc_box(u, v, radius_px)
    if x0 < ox or y0 < oy or x1 > ox + w or y1 > oy + h:
        return False
    patch = bgr[y0 - oy : y1 - oy, x0 - ox : x1 - ox]
    hue = color_mask(cv2.cvtColor(patch, cv2.COLOR_BGR2HSV), with_min_saturation(spec, MIN_SATURATION))
    ys, xs = np.mgrid[y0:y1, x0:x1]
    disc = (xs - u) ** 2 + (ys - v) ** 2 <= radius_px * radius_px
    on = (hue > 0) & disc
    share = on.sum() / disc.sum() if disc.any() else 0.0
    if share < min(MIN_SHARE, MIN_SHARE_CENTRED) or not on.any():
        return False
    off = math.hypot(float(xs[on].mean()) - u, float(ys[on].mean()) - v)
    if share >= MIN_SHARE and off <= max(3.0, MAX_OFF_RADII * radius_px):
        return True
    return share >= MIN_SHARE_CENTRED and off <= MAX_OFF_CENTRED_RADII * radius_px


def disc_box(u: float, v: float, radius_px: float) -> tuple[int, int, int, int]:
    """(x0, y0, x1, y1) [px]: the pixels x0 ≤ x < x1, y0 ≤ y < y1 :func:`shows_ball` looks at."""
    return (
        int(math.floor(u - radius_px)),
        int(math.floor(v - radius_px)),
        int(math.ceil(u + radius_px)) + 1,
        int(math.ceil(v + radius_px)) + 1,
    )


def place(fit: PendulumFit, pivot: tuple[float, float], k: int, fps: float, radius_px: float) -> Blob:
    """A blob of the ball's radius [px] at the fitted place in frame k (for the tracker's checks)."""
    (th,) = angles(fit, np.array([k]), fps)
    u, v = pivot[0] + fit.length_px * math.sin(th), pivot[1] + fit.length_px * math.cos(th)
    return Blob(u, v, math.pi * radius_px**2, 1.0, 1.0, False)


def recover(
    tracker: BallTracker,
    path: str,
    fps: float,
    uv: np.ndarray,
    trusted: np.ndarray,
    pivot: tuple[float, float],
    radius_px: float,
    kept: dict[int, np.ndarray] | None = None,
    patches: dict[int, Patch] | None = None,
) -> list[tuple[int, Blob]]:
    """The model look over a tracked video (``path``, frames evenly spaced at ``fps`` [1/s]; the frames ``kept`` since
    the first pass used, then the ``patches`` kept around its fixes that hold the place, the rest decoded again):
    (frame index, blob at the fitted place) of the frames it reports. uv (n, 2) [px] and trusted (n,) are the track's
    centres and its fixes to trust; pivot [px] fixed; radius_px the ball's."""
    from .video import frames_at

    d = np.asarray(uv, float) - np.asarray(pivot, float)
    theta = np.full(len(d), np.nan)
    theta[trusted] = np.unwrap(np.arctan2(d[trusted, 0], d[trusted, 1]))  # across gaps too (a swing-up passes 180°)
    radius = np.hypot(d[:, 0], d[:, 1])
    plans: dict[int, Blob] = {}
    cache: dict = {}
    for run in runs(trusted, round(MAX_GAP_S * fps), round(MAX_EDGE_GAP_S * fps)):
        for k, fit in fit_around(run, trusted, theta, radius, fps, cache).items():
            plans[k] = place(fit, pivot, k, fps, radius_px)
    if not plans:
        return []
    kept, patches = kept or {}, patches or {}
    local = {
        k: patches[k]
        for k, b in plans.items()
        if k not in kept and k in patches and patches[k].covers(*disc_box(b.u, b.v, radius_px))
    }
    frames = frames_at(path, None, [k for k in plans if k not in local], kept)
    looks = {k: (p.pixels, (p.x0, p.y0)) for k, p in local.items()} | {k: (f, (0, 0)) for k, f in frames.items()}
    return [
        (k, b)
        for k, b in sorted(plans.items())
        if shows_ball(looks[k][0], tracker.spec, b.u, b.v, radius_px, looks[k][1]) and tracker.could_be_ball(b, pivot)
    ]
