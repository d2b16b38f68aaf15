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
_MIN_WINDOW_S = 2.0  # [s] the default lag window is at least ± this
_RIVAL_SEPARATION_S = 0.15  # [s] a rival peak lies at least this far from the chosen lag
UNCOVERED_WEIGHT = 0.5  # measured samples outside the model's span count this share of their energy as misfit
_REFINED_MINIMA = 4  # the best local minima of the misfit on the grid refined to sub-sample before ranking
AMBIGUOUS_RMS_RATIO = (
    1.5  # a rival lag whose RMS misfit is within this factor of the best one's makes the lag ambiguous
)
LAG_SETTING = "compare_angles.lag_s"  # the setting that gives the lag instead (the CLI names its option)


@dataclass(frozen=True)
class LagEstimate:
    """Lag [s] (measured time − model time) and the match score: the share of the measured θ the model explains
    (1 − Σ(y − model)²/Σy² over the whole measurement, the model taken as 0 outside its span; ≤ 1)."""

    lag_s: float
    correlation: float
    window_s: float = math.inf  # the lag was searched within ± this [s]
    rival_lag_s: float = math.nan  # the best other peak of the score (NaN when none) [s]
    rival_correlation: float = math.nan  # its score
    rms_rad: float = (
        math.nan
    )  # RMS of (measured − model) over the whole measurement at the lag, 0 outside the model [rad]
    rival_rms_rad: float = math.nan  # the same at the rival lag [rad]
    at_window_edge: bool = False  # the best lag lies on the edge of the window: the true one may be outside
    overlap_misfit: float = math.nan  # Σ(y − model)² / Σy² over the overlap alone at the lag
    overlap_rms_rad: float = math.nan  # RMS of (y − model) over the overlap alone at the lag [rad]

    @property
    def ambiguous(self) -> bool:
        """The rival explains the measurement nearly as well (see below), or the lag sits on the edge of the window."""
        if self.at_window_edge:
            return True
        if not math.isfinite(self.rival_rms_rad):
            return False
        # the rival's misfit exceeds the best one's by less than it would if the best one's residual inside the
        # overlap grew by the ratio (the same as rival RMS ≤ ratio × best RMS when both overlap the whole track)
        margin = (AMBIGUOUS_RMS_RATIO**2 - 1.0) * self.overlap_rms_rad**2
        return self.rival_rms_rad**2 - self.rms_rad**2 <= margin


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
    correlation: float  # match score at the lag (see LagEstimate), ≤ 1 (NaN when the lag was given)
    rms_fit_deg: float  # RMS misfit at the lag over the whole track, model 0 outside its span [deg] (NaN when given)
    rival_rms_fit_deg: float  # the same at the rival lag [deg]
    ambiguous: bool  # a rival lag explains the track nearly as well, or the lag is on the window's edge
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
    """(first time [s], values on the grid (0 where unknown), mask of known samples) — θ keeps its physical zero."""
    ok = np.isfinite(x)
    t0 = float(t[ok][0])
    grid = np.arange(t0, float(t[ok][-1]) + 0.5 * step, step)
    y = resample(t, x, grid, max_gap_s)
    m = np.isfinite(y)
    return t0, np.where(m, y, 0.0), m.astype(float)


def _local_minima(e: np.ndarray) -> np.ndarray:
    """Indices of the finite local minima of e (plateau edges included)."""
    inner = np.flatnonzero((e[1:-1] <= e[:-2]) & (e[1:-1] <= e[2:]) & np.isfinite(e[1:-1])) + 1
    ends = [k for k, nb in ((0, 1), (len(e) - 1, len(e) - 2)) if len(e) > 1 and np.isfinite(e[k]) and e[k] <= e[nb]]
    return np.union1d(inner, np.array(ends, int))


@dataclass(frozen=True)
class _ShiftMisfits:
    """The misfit of the measurement against the model at every whole-sample shift on a common grid."""

    step: float  # grid step [s]
    lags: np.ndarray  # (s,) lag of each shift [s]
    error: np.ndarray  # (s,) Σ over the overlap of (y − model)² + UNCOVERED_WEIGHT × the measured energy outside it
    inside: np.ndarray  # (s,) its part inside the overlap
    syy: np.ndarray  # (s,) measured energy inside the overlap
    overlapping: np.ndarray  # (s,) bool: at least two samples overlap


def _shift_misfits(t_model, theta_model, t_meas, theta_meas, step: float) -> _ShiftMisfits:
    """:class:`_ShiftMisfits` by FFT cross-correlations of both series resampled on a grid of step [s] (gaps in the
    measurement masked). CheckFailed when a series is constant."""
    from scipy.signal import correlate

    tm0, xm, mm = _series(np.asarray(t_model, float), np.asarray(theta_model, float), step, math.inf)
    ty0, ym, my = _series(np.asarray(t_meas, float), np.asarray(theta_meas, float), step, _GAP_FACTOR * step)

    def xc(a: np.ndarray, b: np.ndarray) -> np.ndarray:  # Σ_n a[n + s] b[n] for every shift s
        return correlate(a, b, mode="full", method="fft")

    sxy = xc(ym, xm)
    sxx = xc(my, xm * xm)  # model energy where it is compared with a measured sample
    count = xc(my, mm)
    shifts = np.arange(-(len(xm) - 1), len(ym))
    lags = ty0 - tm0 + shifts * step
    ey = float(np.dot(ym, ym))
    if float(np.ptp(xm[mm > 0])) == 0.0 or float(np.ptp(ym[my > 0])) == 0.0:
        raise CheckFailed(f"cannot estimate the lag: a θ series is constant (give {LAG_SETTING})")
    syy = xc(ym * ym, mm)  # measured energy inside the overlap
    inside = np.clip(syy - 2.0 * sxy + sxx, 0.0, None)  # Σ over the overlap of (y − model)²
    error = inside + UNCOVERED_WEIGHT * np.clip(ey - syy, 0.0, None)
    return _ShiftMisfits(step, lags, error, inside, syy, count >= 2.0 - 0.5)


def _refine_minima(shifts: _ShiftMisfits, minima: np.ndarray, t_model, theta_model, t_meas, theta_meas) -> list:
    """The best few minima of the grid's misfit, each refined to sub-sample by a bounded search within ± a step (the
    grid misaligns the series by up to half a step): [(misfit, its part inside the overlap, lag [s], grid index)],
    the best first."""
    from scipy.optimize import minimize_scalar

    step, lags = shifts.step, shifts.lags
    order = minima[np.argsort(shifts.error[minima])][:_REFINED_MINIMA]
    refined = []
    for j in order:
        lo, hi = float(lags[j] - step), float(lags[j] + step)
        res = minimize_scalar(
            lambda lag: _misfit(t_model, theta_model, t_meas, theta_meas, lag, (lo, hi))[0],
            bounds=(lo, hi),
            method="bounded",
            options={"xatol": step * 1e-3},
        )
        lag = float(res.x)
        if _misfit(t_model, theta_model, t_meas, theta_meas, float(lags[j]), (lo, hi))[0] < res.fun:
            lag = float(lags[j])
        refined.append((*_misfit(t_model, theta_model, t_meas, theta_meas, lag), lag, int(j)))
    refined.sort()
    return refined


def estimate_lag(
    t_model: np.ndarray,
    theta_model: np.ndarray,
    t_meas: np.ndarray,
    theta_meas: np.ndarray,
    max_lag_s: float | None = None,
    step_s: float | None = None,
) -> LagEstimate:
    """Lag [s] at which the model explains the measurement best (NaN samples in the measurement skipped).

    Both are resampled on a grid of step_s [s] (default: the measurement's median frame interval), gaps in
    the measurement masked. For every shift the whole measurement is scored: inside the overlap by its squared
    difference from the model, outside it by half its own square (what was measured where the model says
    nothing is unexplained; half, because the sway may go on after the prediction ends). The score is 1 − that
    error / the measurement's energy — the share of the measured θ the model explains — so a shift that
    overlaps only part of the clip pays for the rest (a periodic swing matches itself one period off over a
    shorter overlap, and must not win). Lags beyond
    ± max_lag_s (default :func:`default_lag_window`) are not considered; the minimum is refined to
    sub-sample by least squares of the residual; the best other local minimum at least 0.15 s away is the
    rival (a steady swing scores nearly alike one period off: then the lag is ambiguous).
    """
    step = step_s or median_step(t_meas[np.isfinite(theta_meas)])
    shifts = _shift_misfits(t_model, theta_model, t_meas, theta_meas, step)
    default_window = max_lag_s is None
    if max_lag_s is None:
        max_lag_s = default_lag_window(t_model, t_meas)
    valid = (np.abs(shifts.lags) <= max_lag_s) & shifts.overlapping
    if not valid.any():
        raise CheckFailed("no lag with enough overlap between prediction and track")
    minima = _local_minima(np.where(valid, shifts.error, np.inf))
    if (
        default_window and not valid[shifts.overlapping].all()
    ):  # the default window is a guess: a better lag beyond it rivals
        beyond = np.where(shifts.overlapping & ~valid, shifts.error, np.inf)
        minima = np.append(minima, int(np.argmin(beyond)))
    t_meas, theta_meas = np.asarray(t_meas, float), np.asarray(theta_meas, float)
    refined = _refine_minima(shifts, minima, t_model, theta_model, t_meas, theta_meas)
    best_ms, best_inside, lag, k = refined[0]
    if abs(lag) > max_lag_s + step:  # only a rival may lie beyond the window: keep the best inside as the lag
        best_ms, best_inside, lag, k = next((r for r in refined if abs(r[2]) <= max_lag_s + step), refined[0])
    rivals = [r for r in refined if abs(r[2] - lag) >= _RIVAL_SEPARATION_S]
    ey_n = float(np.mean(np.asarray(theta_meas)[np.isfinite(theta_meas)] ** 2))
    rival = rivals[0] if rivals else None
    return LagEstimate(
        lag_s=lag,
        correlation=1.0 - best_ms / ey_n,
        window_s=float(max_lag_s),
        rival_lag_s=rival[2] if rival else math.nan,
        rival_correlation=1.0 - rival[0] / ey_n if rival else math.nan,
        rms_rad=math.sqrt(best_ms),
        rival_rms_rad=math.sqrt(rival[0]) if rival else math.nan,
        at_window_edge=abs(lag) >= float(max_lag_s) - 1.5 * step,
        overlap_misfit=float(shifts.inside[k] / max(shifts.syy[k], 1e-300)),
        overlap_rms_rad=math.sqrt(best_inside),
    )


def _misfit(t_model, theta_model, t_meas, theta_meas, lag: float, bracket: tuple[float, float] | None = None):
    """(misfit, its part inside the overlap) [rad²]: the mean over the measured samples of (measured − model)²
    where the model covers them and of half the measured value² elsewhere (see :func:`estimate_lag`), and the
    mean of the first alone over the covered samples. bracket: (lo, hi) lags [s] — then only the samples the
    model covers at every lag in it are compared (the rest count as uncovered), so that the misfit is smooth in
    the lag for a sub-sample search."""
    ok = np.isfinite(theta_meas)
    t, y = t_meas[ok], theta_meas[ok]
    tm = np.asarray(t_model, float)
    lo, hi = bracket if bracket is not None else (lag, lag)
    cover = (t - hi >= tm[0]) & (t - lo <= tm[-1])
    e = _wrap(y[cover] - np.interp(t[cover] - lag, tm, np.asarray(theta_model, float)))
    sq = float(np.sum(e * e))
    total = (sq + UNCOVERED_WEIGHT * float(np.sum(y[~cover] ** 2))) / max(len(y), 1)
    return total, sq / max(int(cover.sum()), 1)


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
    mirrored = ambiguous = False
    corr = window = rival = rival_corr = fit = rival_fit = math.nan
    if lag_s is None:
        est = estimate_lag(tm, xm, ty, y, max_lag_s)
        try:
            other = estimate_lag(tm, xm, ty, -y, max_lag_s)
            # mirrored when the negated track leaves less than half the misfit (over the overlap) of the track as given
            mirrored = other.overlap_misfit < 0.5 * est.overlap_misfit
        except CheckFailed:
            pass
        lag, corr = est.lag_s, est.correlation
        window, rival, rival_corr = est.window_s, est.rival_lag_s, est.rival_correlation
        fit, rival_fit, ambiguous = math.degrees(est.rms_rad), math.degrees(est.rival_rms_rad), est.ambiguous
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
        rms_fit_deg=fit,
        rival_rms_fit_deg=rival_fit,
        ambiguous=ambiguous,
        mirrored=mirrored,
        rms_deg=float(np.sqrt(np.mean(ad**2))),
        max_deg=float(ad.max()),
        overlap_s=float(max(overlap, 0.0)),
        samples=int(len(t)),
        t=t,
        model=model,
        measured=model + err,
    )
