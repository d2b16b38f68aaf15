"""Model–experiment comparison of the string angle: time lag by cross-correlation, errors over the overlap.

Convention: the experiment's clock runs ``lag_s`` ahead of the model's, i.e. measured θ(t) ≈ model
θ(t − lag_s); a video that starts before the robot moves gives a positive lag. Pure functions on arrays.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from trajectories.errors import CheckFailed

_GAP_FACTOR = 2.5  # a gap longer than this × the median frame interval is masked, not interpolated over
_MIN_OVERLAP = 0.25  # a lag must overlap at least this fraction of the shorter series
_MIN_WINDOW_S = 2.0  # [s] the default lag window is at least ± this
_RIVAL_SEPARATION_S = 0.15  # [s] a rival peak lies at least this far from the chosen lag


@dataclass(frozen=True)
class LagEstimate:
    """Lag [s] (measured time − model time) and the match score 2Σxy/(Σx²+Σy²) over the overlap (−1..1)."""

    lag_s: float
    correlation: float
    window_s: float = math.inf  # the lag was searched within ± this [s]
    rival_lag_s: float = math.nan  # the best other peak of the score (NaN when none) [s]
    rival_correlation: float = math.nan  # its score


def default_lag_window(t_model: np.ndarray, t_meas: np.ndarray) -> float:
    """± window [s] searched for the lag by default: half the longer series, at least 2 s."""
    span = max(float(np.ptp(np.asarray(t_model, float))), float(np.ptp(np.asarray(t_meas, float))))
    return max(_MIN_WINDOW_S, 0.5 * span)


@dataclass(frozen=True)
class Comparison:
    """Aligned model and measurement over their overlap, and the error figures."""

    lag_s: float  # measured time − model time [s]
    lag_estimated: bool  # False when the lag was given
    lag_window_s: float  # the lag was searched within ± this [s] (NaN when given)
    rival_lag_s: float  # the best other peak of the lag score [s] (NaN when none or given)
    rival_correlation: float  # its score (close to `correlation`: the lag is ambiguous)
    correlation: float  # match score 2Σxy/(Σx²+Σy²) at the lag, −1..1 (NaN when the lag was given)
    mirrored: bool  # the negated measurement correlates better: the camera sees θ mirrored (use flip)
    rms_deg: float  # RMS of measured − model over the overlap [deg]
    max_deg: float  # largest |measured − model| [deg]
    overlap_s: float  # length of the overlap [s]
    samples: int  # measured samples in the overlap
    t: np.ndarray  # (m,) measurement times in the overlap [s] (measurement clock)
    model: np.ndarray  # (m,) model θ at t − lag [rad]
    measured: np.ndarray  # (m,) measured θ [rad] (negated when flipped)


def median_step(t: np.ndarray) -> float:
    """Median sample interval [s] of increasing times."""
    d = np.diff(np.asarray(t, float))
    d = d[d > 0]
    if not len(d):
        raise ValueError("need at least two distinct sample times")
    return float(np.median(d))


def resample(t: np.ndarray, x: np.ndarray, grid: np.ndarray, max_gap_s: float = math.inf) -> np.ndarray:
    """Linear interpolation of valid (finite) samples onto grid [s]; NaN outside them and inside gaps > max_gap_s."""
    t = np.asarray(t, float)
    x = np.asarray(x, float)
    ok = np.isfinite(t) & np.isfinite(x)
    t, x = t[ok], x[ok]
    out = np.full(len(grid), np.nan)
    if len(t) < 2:
        return out
    inside = (grid >= t[0]) & (grid <= t[-1])
    out[inside] = np.interp(grid[inside], t, x)
    if math.isfinite(max_gap_s):
        j = np.clip(np.searchsorted(t, grid, side="right"), 1, len(t) - 1)
        left, right = t[j - 1], t[j]
        out[inside & (right - left > max_gap_s) & (grid > left) & (grid < right)] = np.nan
    return out


def _series(t: np.ndarray, x: np.ndarray, step: float, max_gap_s: float) -> tuple[float, np.ndarray, np.ndarray]:
    ok = np.isfinite(x)
    t0 = float(t[ok][0])
    grid = np.arange(t0, float(t[ok][-1]) + 0.5 * step, step)
    y = resample(t, x, grid, max_gap_s)
    m = np.isfinite(y)
    y = np.where(m, y - (y[m].mean() if m.any() else 0.0), 0.0)
    return t0, y, m.astype(float)


def estimate_lag(
    t_model: np.ndarray,
    theta_model: np.ndarray,
    t_meas: np.ndarray,
    theta_meas: np.ndarray,
    max_lag_s: float | None = None,
    step_s: float | None = None,
) -> LagEstimate:
    """Lag [s] that best matches the two θ series (NaN samples in the measurement skipped).

    Both are resampled on a grid of step_s [s] (default: the measurement's median frame interval), mean
    removed, gaps masked. For every shift the overlap is scored by 2·Σxy / (Σx² + Σy²) — the normalised
    cross-correlation made amplitude-sensitive, so a shift by one period of a growing or decaying swing
    scores lower than the true lag (all sums by FFT). Shifts overlapping less than a quarter of the shorter
    series, or holding less than half of the weaker series' energy, are not considered, nor lags beyond
    ± max_lag_s (default :func:`default_lag_window`). The peak is refined to sub-sample by least squares of
    the residual; the best other local peak is reported as a rival (a periodic swing scores nearly alike one
    period off).
    """
    from scipy.optimize import minimize_scalar
    from scipy.signal import correlate

    step = step_s or median_step(t_meas[np.isfinite(theta_meas)])
    tm0, xm, mm = _series(np.asarray(t_model, float), np.asarray(theta_model, float), step, math.inf)
    ty0, ym, my = _series(np.asarray(t_meas, float), np.asarray(theta_meas, float), step, _GAP_FACTOR * step)

    def xc(a: np.ndarray, b: np.ndarray) -> np.ndarray:  # Σ_n a[n + s] b[n] for every shift s
        return correlate(a, b, mode="full", method="fft")

    sxy = xc(ym, xm)
    sxx = xc(my, xm * xm)  # model energy inside the overlap
    syy = xc(ym * ym, mm)  # measurement energy inside the overlap
    count = xc(my, mm)
    shifts = np.arange(-(len(xm) - 1), len(ym))
    lags = ty0 - tm0 + shifts * step
    ex, ey = float(np.dot(xm, xm)), float(np.dot(ym, ym))
    if ex == 0.0 or ey == 0.0:
        raise CheckFailed("cannot estimate the lag: a θ series is constant (give --lag)")
    energy = sxx + syy
    valid = (count >= _MIN_OVERLAP * min(mm.sum(), my.sum()) - 0.5) & (energy >= min(ex, ey))
    if max_lag_s is None:
        max_lag_s = default_lag_window(t_model, t_meas)
    valid &= np.abs(lags) <= max_lag_s
    if not valid.any():
        raise CheckFailed("no lag with enough overlap between prediction and track")
    score = np.where(valid, 2.0 * sxy / np.maximum(energy, 1e-300), -np.inf)
    k = int(np.argmax(score))
    lag0 = float(lags[k])
    peaks = np.flatnonzero(
        (score[1:-1] >= score[:-2]) & (score[1:-1] >= score[2:]) & np.isfinite(score[1:-1])
        & (np.abs(lags[1:-1] - lag0) >= _RIVAL_SEPARATION_S)
    ) + 1
    rival = int(peaks[np.argmax(score[peaks])]) if len(peaks) else None

    def residual(lag: float) -> float:
        e = _errors(t_model, theta_model, t_meas, theta_meas, lag)[2]
        return float(np.mean(e * e)) if len(e) else math.inf

    res = minimize_scalar(residual, bounds=(lag0 - step, lag0 + step), method="bounded", options={"xatol": step * 1e-3})
    lag = float(res.x) if res.success and res.fun <= residual(lag0) else lag0
    return LagEstimate(
        lag_s=lag,
        correlation=float(score[k]),
        window_s=float(max_lag_s),
        rival_lag_s=float(lags[rival]) if rival is not None else math.nan,
        rival_correlation=float(score[rival]) if rival is not None else math.nan,
    )


def _wrap(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2 * np.pi) - np.pi


def _errors(t_model, theta_model, t_meas, theta_meas, lag: float):
    t_meas = np.asarray(t_meas, float)
    theta_meas = np.asarray(theta_meas, float)
    tm = np.asarray(t_model, float)
    sel = np.isfinite(theta_meas) & (t_meas - lag >= tm[0]) & (t_meas - lag <= tm[-1])
    t = t_meas[sel]
    model = np.interp(t - lag, tm, np.asarray(theta_model, float))
    return t, model, _wrap(theta_meas[sel] - model)


def compare_angles(
    t_model: np.ndarray,
    theta_model: np.ndarray,
    t_meas: np.ndarray,
    theta_meas: np.ndarray,
    *,
    lag_s: float | None = None,
    flip: bool = False,
    max_lag_s: float | None = None,
) -> Comparison:
    """Align a measured θ [rad] (NaN = not found) with the model's θ [rad] and report the errors.

    lag_s: measured time − model time [s]; estimated by cross-correlation when None, within ± max_lag_s
    [s] (default :func:`default_lag_window`). flip negates the
    measurement (camera looking from the other side). Raises CheckFailed when the series do not overlap.
    """
    tm = np.asarray(t_model, float)
    xm = np.asarray(theta_model, float)
    ty = np.asarray(t_meas, float)
    y = np.asarray(theta_meas, float)
    if flip:
        y = -y
    if np.count_nonzero(np.isfinite(y)) < 2 or len(tm) < 2:
        raise CheckFailed("not enough samples: the track needs θ in at least two frames, the prediction two samples")
    mirrored = False
    corr = window = rival = rival_corr = math.nan
    if lag_s is None:
        est = estimate_lag(tm, xm, ty, y, max_lag_s)
        try:
            other = estimate_lag(tm, xm, ty, -y, max_lag_s)
            # mirrored when the negated track leaves less than half the mismatch (1 − score) of the track as given
            mirrored = (1.0 - other.correlation) < 0.5 * (1.0 - est.correlation)
        except CheckFailed:
            pass
        lag, corr = est.lag_s, est.correlation
        window, rival, rival_corr = est.window_s, est.rival_lag_s, est.rival_correlation
    else:
        lag = float(lag_s)
    t, model, err = _errors(tm, xm, ty, y, lag)
    if len(t) == 0:
        raise CheckFailed(
            f"no overlap: the prediction covers {tm[0]:.3f}–{tm[-1]:.3f} s, the track {ty[0]:.3f}–{ty[-1]:.3f} s "
            f"(with lag {lag:.3f} s)"
        )
    overlap = min(tm[-1] + lag, ty[-1]) - max(tm[0] + lag, ty[0])
    ad = np.degrees(np.abs(err))
    return Comparison(
        lag_s=lag,
        lag_estimated=lag_s is None,
        lag_window_s=window,
        rival_lag_s=rival,
        rival_correlation=rival_corr,
        correlation=corr,
        mirrored=mirrored,
        rms_deg=float(np.sqrt(np.mean(ad**2))),
        max_deg=float(ad.max()),
        overlap_s=float(max(overlap, 0.0)),
        samples=int(len(t)),
        t=t,
        model=model,
        measured=model + err,
    )
