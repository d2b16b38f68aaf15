"""Anti-sway crane moves: a layout of turning points → the pivot path p(t), stopping at every turning point.

Each segment is a rest-to-rest move along a straight line, written as a box profile (``profiles.BoxProfile``):

* ``accel`` — the thesis baseline (``accel_shaping``, Fig. 4.4), unchanged.
* ``box`` — the baseline made jerk-limited and exact: velocity = s·B(T_a) ⊗ B(τ) ⊗ B(a/j). The box of one
  (effective) period T_a cancels the swing, B(τ) with τ = s/(a·T_a) uses the full a_max also on short segments
  (the baseline slows to s/T² there), and the jerk box bounds the jerk. Never slower than the baseline + a/j.
* ``zv``, ``zvd``, ``zvdd``, ``mzv``, ``ei``, ``ei2`` — the time-optimal jerk-limited move (= ruckig's) convolved
  with that input shaper; ``box-zv``, ``box-zvd``, ``box-ei`` — the ``box`` move convolved with a shaper
  (robust to string-length errors at ≤ one added period).
* ``robust`` — the quickest piecewise-linear acceleration whose residual swing stays within the budget for every
  string length in the tolerance band (``robust_shaping``: a linear programme per duration, bisection on the
  duration), checked and tightened on the nonlinear pendulum at five lengths across the band; with
  ``max_sway`` the transient tilt is a constraint of the same programme.
* ``auto`` (default) — with a length tolerance (default ±10 %) the ``robust`` design; a segment whose robust move
  would take longer than the baseline's is capped at the baseline's duration when the least residual reachable
  in that time still fits the layout's budget. With ``length_tolerance=0`` per segment the quicker of ``box``
  and ``zv`` (nominal length only).

Nonlinear correction: while the pivot accelerates with a the pendulum hangs in the effective gravity
√(g² + a²) and swings about a tilted equilibrium with amplitude atan(a/g), so the design period starts from
the exact large-amplitude period in that field. Designs with a simple zero (box, zv, mzv) are then tuned per
segment on the nonlinear planar pendulum: all profiles are antisymmetric in acceleration about mid-move, so the
pendulum ends at rest exactly when its angle is zero at mid-move (time-reversal symmetry) — a scalar root.
All shapers have non-negative impulses, so velocity, acceleration and jerk limits hold by construction.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from trajectories.errors import PlanningError

from .accel_shaping import BaselineSegment, baseline_segment, segment_lengths
from .pendulum import G, PendulumRun, SampledAcceleration, natural_period
from .sway_prediction import predict
from .profiles import BoxProfile, time_optimal_boxes
from .ramp_profile import RampProfile
from .robust_shaping import RobustSpec, linear_residual_phasor, nonlinear_phasor, planar_run, robust_profile
from .shapers import SHAPER_NAMES, Shaper, identity_shaper, make_shaper

SHAPERS = ("auto", "robust", "accel", "box", *SHAPER_NAMES, "box-zv", "box-zvd", "box-ei")
"""The designs ``AntiSwayOptions.shaper`` takes, the default (`auto`) first."""
TUNABLE = ("box", "zv", "mzv")  # designs with a simple zero at the design frequency

# Thesis-like obstacle course (thesis Fig. 4.6: 90° turns on the table beside the robot), base frame [m].
DEFAULT_LAYOUT = ((0.40, -0.30), (0.62, -0.30), (0.62, 0.05), (0.45, 0.05), (0.45, 0.30))
"""The default turning points (x, y) [m] in the base frame: a thesis-like obstacle layout, start first."""
DEFAULT_Z = 0.45  # flange height [m]
"""The default flange height of an anti-sway move [m]."""
JERK_RAMP = 0.04  # default jerk ramp a_max/j_max as a fraction of the period [-] (≤ 5 % added time)
ROBUST_BUDGET_RAD = math.radians(0.3)  # worst-case residual allowed per layout with a length tolerance
DEFAULT_LENGTH_TOLERANCE = 0.1  # relative string-length uncertainty the default design is robust to
BAND_LENGTHS = (-1.0, -0.5, 0.0, 0.5, 1.0)  # where in the tolerance band the paths are simulated [× tolerance]
DENSE_FACTOR = 5  # robust designs are judged at this many times the frequencies their programme constrains
DENSE_LENGTHS = 41  # plans are judged (figures, AntiSwayOptions.max_sway) at this many string lengths across the band


@dataclass(frozen=True)
class AntiSwayOptions:
    """Planner settings: shaper name, pivot jerk/velocity limits, string-length tolerance, tuning."""

    shaper: str = "auto"
    j_max: float | None = None  # [m/s³]; None: a_max / (JERK_RAMP·T), a ramp of 4 % of the period
    v_max: float = math.inf  # [m/s]
    length_tolerance: float = DEFAULT_LENGTH_TOLERANCE  # relative, e.g. 0.2 for ±20 %
    tune: bool = True
    robust_budget: float = ROBUST_BUDGET_RAD  # [rad] residual allowed over the whole layout and band
    max_sway: float | None = None  # [rad] largest tilt allowed during the move (robust/auto designs plan for it)
    time_cap: bool = True  # auto: cap a segment at the baseline's duration when the budget allows


@dataclass(frozen=True)
class SegmentPlan:
    """One rest-to-rest segment: end points (2,) [m], the design used and its profile along the segment."""

    index: int  # 1-based
    start: np.ndarray
    end: np.ndarray
    design: str
    profile: BoxProfile | BaselineSegment | RampProfile
    period: float  # design period after correction and tuning [s]
    accel: float  # peak pivot acceleration of the design [m/s²]
    band_residual: float = math.nan  # worst residual [rad] of the planar nonlinear pendulum over the band
    band_peak: float = math.nan  # worst tilt [rad] during the segment over the band

    @property
    def length(self) -> float:
        return float(np.linalg.norm(self.end - self.start))

    @property
    def duration(self) -> float:
        return float(self.profile.duration)

    @property
    def direction(self) -> np.ndarray:
        return (self.end - self.start) / max(self.length, 1e-300)


@dataclass(frozen=True)
class AntiSwayPlan:
    """Pivot path sampled every dt: t (n,) [s], position (n, 3) [m]; segments and their first sample index."""

    t: np.ndarray
    position: np.ndarray
    segments: tuple[SegmentPlan, ...]
    segment_start: np.ndarray
    string_length: float  # [m]
    a_max: float  # [m/s²]
    shaper: str
    options: AntiSwayOptions = field(default_factory=AntiSwayOptions)

    @property
    def dt(self) -> float:
        return float(self.t[1] - self.t[0])

    @property
    def duration(self) -> float:
        return float(self.t[-1])

    @property
    def stop_time(self) -> float:
        """Time of the last stop [s] (end of the last segment's motion)."""
        return float(self.t[self.segment_start[-1]] + self.segments[-1].duration)

    def acceleration(self) -> np.ndarray:
        """(n, 3) pivot acceleration realised by the samples (second differences, rest outside) [m/s²]."""
        return SampledAcceleration(self.t, self.position).samples()

    def segment_of(self, time: float) -> int:
        """1-based index of the segment running at ``time`` [s]."""
        k = int(np.searchsorted(self.t[self.segment_start], time, side="right"))
        return max(1, min(k, len(self.segments)))


def effective_period(length: float, accel: float) -> float:
    """Exact period [s] of the pendulum released at rest while the pivot accelerates with ``accel`` [m/s²].

    Effective gravity g' = √(g² + a²), amplitude θ0 = atan(a/g) about the tilted equilibrium:
    T = 4·√(l/g')·K(sin²(θ0/2)) (complete elliptic integral); a = 0 gives 2π√(l/g).
    """
    from scipy.special import ellipk

    g_eff = math.hypot(G, accel)
    theta0 = math.atan2(abs(accel), G)
    return 4.0 * math.sqrt(length / g_eff) * float(ellipk(math.sin(theta0 / 2) ** 2))


def _box_boxes(s: float, period: float, a_max: float, j_max: float, v_max: float) -> tuple[float, ...]:
    """B(T_a) ⊗ B(τ) ⊗ B(a/j) with τ = s/(a·T_a), kept ≥ T_a + a/j or ≤ T_a − a/j so the jerk bound holds."""
    tau = max(s / (a_max * period), s / v_max)
    if math.isinf(j_max):
        return (period, tau)
    tj = a_max / j_max
    if period - tj < tau < period + tj:
        tau = period + tj
    return (period, tau, tj)


def design_profile(design: str, s: float, period: float, a_max: float, j_max: float, v_max: float) -> BoxProfile:
    """Box profile of ``design`` for a segment of length s [m] with the design period [s]."""
    if design.startswith("box"):
        boxes = _box_boxes(s, period, a_max, j_max, v_max)
        shaper = make_shaper(design[4:], period) if design != "box" else identity_shaper()
    else:
        boxes = time_optimal_boxes(s, v_max, a_max, j_max)
        shaper = make_shaper(design, period)
    return BoxProfile(s, boxes, shaper)


def planar_midpoint_angle(profile: BoxProfile, length: float, step: float = 0.002) -> float:
    """Angle [rad] at mid-move of the nonlinear planar pendulum l·θ̈ + ẍ·cos θ + g·sin θ = 0 (RK4).

    Zero means the pendulum ends the (antisymmetric) move at rest.
    """
    th, _, _ = planar_run(profile, np.array([length]), step, until=0.5 * profile.duration)
    return float(th[0])


def _tune(design: str, s: float, period0: float, a_max: float, j_max: float, v_max: float, length: float) -> float:
    """Design period [s] near ``period0`` for which the nonlinear pendulum ends at rest."""
    from scipy.optimize import brentq, minimize_scalar

    def f(period: float) -> float:
        return planar_midpoint_angle(design_profile(design, s, period, a_max, j_max, v_max), length)

    f0 = f(period0)
    for width in (0.01, 0.03, 0.08):
        for other in (period0 * (1 - width), period0 * (1 + width)):
            f1 = f(other)
            if f0 == 0.0:
                return period0
            if f0 * f1 < 0:
                lo, hi = sorted((period0, other))
                return float(brentq(f, lo, hi, xtol=1e-9 * period0))
    res = minimize_scalar(lambda p: abs(f(p)), bounds=(0.92 * period0, 1.08 * period0), method="bounded")
    return float(res.x)


def linear_residual(profile: BoxProfile, omega: np.ndarray) -> np.ndarray:
    """Residual swing amplitude [rad] of the linear pendulum ω [rad/s] after the move (from rest).

    θ̈ + ω²θ = −(ω²/g)·ẍ ⇒ |θ_res| = (ω²·s/g)·Π|sinc(ωτ_i/2)|·|Σ A_i e^{iωt_i}|.
    """
    w = np.asarray(omega, dtype=float)
    out = w**2 * abs(profile.distance) / G * profile.shaper.residual(w)
    for b in profile.boxes:
        out = out * np.abs(np.sinc(w * b / (2 * np.pi)))
    return out


def band_lengths(length: float, tolerance: float) -> np.ndarray:
    """String lengths [m] at which a design is checked across ±tolerance."""
    return length * (1.0 + tolerance * np.array(BAND_LENGTHS if tolerance > 0 else (0.0,)))


def robust_spec(length: float, a_max: float, tolerance: float, residual: float, max_sway: float | None) -> RobustSpec:
    """Frequency band [rad/s] from the longest string at rest to the shortest one in the accelerating field."""
    lo = 2 * math.pi / natural_period(length * (1 + tolerance))
    hi = 2 * math.pi / effective_period(length * (1 - tolerance), a_max)
    return RobustSpec(lo, hi, residual, max_sway)


@functools.lru_cache(maxsize=128)
def _robust_segment_cached(*args) -> tuple[RampProfile, float, float]:
    """:func:`_robust_segment`, remembered: a fallback re-plans a layout with a lower a_max on some segments only,
    and the designs of the others are the same (their profile's array is read-only: shared)."""
    prof, res, pk = _robust_segment(*args)
    prof.accel.setflags(write=False)
    return prof, res, pk


def _robust_segment(
    s: float,
    length: float,
    a_max: float,
    j_max: float,
    options: AntiSwayOptions,
    budget: float,
    cap: float | None,
    total_budget: float,
) -> tuple[RampProfile, float, float]:
    """Robust design of one segment checked on the nonlinear pendulum → (profile, band residual, band peak) [rad].

    Sequential correction (≤ 5 rounds): the nonlinear pendulum's residual phasor at each band frequency minus
    the linear one is added to the next programme as a fixed offset, and the linear sway bound is tightened,
    until the nonlinear pendulum across the band meets ``budget`` and ``options.max_sway``. With ``cap`` [s] a
    segment whose quickest robust move is longer takes the baseline's duration instead if its nonlinear
    residual then stays within ``total_budget``.
    """
    spec = robust_spec(length, a_max, options.length_tolerance, budget, options.max_sway)
    omegas = spec.omegas
    # judged on a grid 5× denser than the programme's: the residual peaks between the frequencies it constrains
    dense = np.linspace(spec.omega_lo, spec.omega_hi, (spec.n_freq - 1) * DENSE_FACTOR + 1)
    best, too_short = None, 0.0

    def check(prof):
        z, peak = nonlinear_phasor(prof, dense)
        res = float(np.abs(z).max())
        return z[::DENSE_FACTOR], res, float(np.maximum(peak, np.abs(z)).max())

    for _ in range(5):
        try:
            prof, _ = robust_profile(s, spec, a_max, j_max, options.v_max, min_duration=too_short)
        except ValueError as exc:
            if best is not None:
                return best
            raise PlanningError(f"robust design of a {s:.3f} m segment: {exc}") from None
        if cap is not None and prof.duration > cap:
            try:
                capped, _ = robust_profile(s, spec, a_max, j_max, options.v_max, max_duration=cap)
            except ValueError:  # nothing fits within the cap (e.g. with a max_sway): keep the longer move
                capped = None
            if capped is not None:
                _, res_c, pk_c = check(capped)
                if res_c <= total_budget and (options.max_sway is None or pk_c <= options.max_sway):
                    return capped, res_c, pk_c
        z, res, pk = check(prof)
        if best is None or (res, pk) < (best[1], best[2]):
            best = (prof, res, pk)
        sway_ok = options.max_sway is None or pk <= options.max_sway
        if res <= budget and sway_ok:
            return prof, res, pk
        too_short = 0.97 * prof.duration  # the corrected problem is about as hard (up to the grid)
        offset = z - linear_residual_phasor(prof, omegas)
        sway = None if sway_ok else spec.max_sway * min(0.9, 0.95 * options.max_sway / pk)
        at_grid = float(np.abs(z).max())
        target = spec.residual if res <= budget or at_grid > budget else spec.residual * 0.97 * budget / res
        spec = RobustSpec(
            spec.omega_lo,
            spec.omega_hi,
            target,
            sway if sway is not None else spec.max_sway,
            spec.n_freq,
            tuple(offset),
        )
    return best


def design_segment(
    index: int,
    start: np.ndarray,
    end: np.ndarray,
    length: float,
    a_max: float,
    options: AntiSwayOptions,
    budget: float,
    total_budget: float | None = None,
) -> SegmentPlan:
    """Choose (``auto``), correct and tune the design of one segment; ``budget`` [rad] is its residual share."""
    s = float(np.linalg.norm(end - start))
    T = natural_period(length)
    if options.shaper == "accel":
        seg = baseline_segment(s, a_max, T)
        return SegmentPlan(index, start, end, "accel", seg, seg.period, seg.accel)
    period0 = effective_period(length, a_max)
    j_max = options.j_max if options.j_max is not None else a_max / (JERK_RAMP * T)
    args = (a_max, j_max, options.v_max)
    robust = options.shaper == "robust" or (options.shaper == "auto" and options.length_tolerance > 0)
    if robust:
        cap = baseline_segment(s, a_max, T).duration if options.shaper == "auto" and options.time_cap else None
        tb = budget if total_budget is None else total_budget
        prof, res, pk = _robust_segment_cached(s, length, a_max, j_max, options, budget, cap, tb)
        return SegmentPlan(index, start, end, "robust", prof, T, prof.peaks()[1], res, pk)
    design = options.shaper
    if options.shaper == "auto":
        design = min(("box", "zv"), key=lambda d: design_profile(d, s, period0, *args).duration)
    period = period0
    if options.tune and design in TUNABLE:
        period = _tune(design, s, period0, *args, length)
    prof = design_profile(design, s, period, *args)
    return SegmentPlan(index, start, end, design, prof, period, prof.peaks()[1])


def plan_layout(
    points: np.ndarray,
    length: float,
    a_max: float | Sequence[float],
    z: float,
    dt: float,
    options: AntiSwayOptions = AntiSwayOptions(),
) -> AntiSwayPlan:
    """Pivot path through the start point and turning points (n, 2) [m] at height z [m], sampled every dt [s].

    ``a_max`` [m/s²] is one value or one per segment. Every segment starts and ends at rest; each is sampled at
    k·dt from its own start (the pivot rests one sample at each turning point, as in the thesis's
    concatenation). The robust designs share ``options.robust_budget`` equally between the segments (residual
    swings of successive segments add at most linearly).
    """
    pts = np.asarray(points, dtype=float)
    if options.shaper not in SHAPERS:
        raise ValueError(f"unknown shaper {options.shaper!r}; known: {', '.join(SHAPERS)}")
    nseg = len(pts) - 1
    accels = np.broadcast_to(np.asarray(a_max, dtype=float), (nseg,))
    budget = options.robust_budget / max(1, nseg)
    # a capped segment may spend what the others leave: at most the whole budget minus the others' shares
    total = options.robust_budget - budget * (nseg - 1) * 0.5
    segments = tuple(
        design_segment(i + 1, pts[i], pts[i + 1], length, float(accels[i]), options, budget, total) for i in range(nseg)
    )
    return sample_plan(segments, length, float(accels.max()), z, dt, options)


def sample_plan(
    segments: tuple[SegmentPlan, ...], length: float, a_max: float, z: float, dt: float, options: AntiSwayOptions
) -> AntiSwayPlan:
    """Sample designed segments every dt [s] and concatenate them at height z [m]."""
    chunks, starts, count = [], [], 0
    for seg in segments:
        n = int(math.ceil(seg.duration / dt - 1e-9)) + 1
        d = seg.profile.position(np.arange(n) * dt)
        chunk = seg.start + d[:, None] * seg.direction
        chunk[-1] = seg.end
        chunks.append(chunk)
        starts.append(count)
        count += n
    xy = np.vstack(chunks)
    pos = np.column_stack([xy, np.full(len(xy), z)])
    return AntiSwayPlan(
        np.arange(len(xy)) * dt, pos, segments, np.array(starts), length, a_max, options.shaper, options
    )


def simulate_path(
    t: np.ndarray, positions: np.ndarray, length: float, stop_time: float, settle_periods: float = 3.0
) -> PendulumRun:
    """Nonlinear spherical pendulum (hanging at rest at t = 0) driven by a pivot path sampled at t (n,) [s].

    The pivot acceleration is what a position-controlled robot realises from the samples (second differences,
    ``sway_prediction``); the run goes on ``settle_periods`` small-angle periods past ``stop_time`` [s],
    sampled at the path step.
    """
    return predict(t, positions, length, stop_time, settle_periods)


def residual_sway(run: PendulumRun, stop_time: float) -> float:
    """Largest tilt [rad] after ``stop_time`` [s]."""
    return float(run.theta[run.t >= stop_time - 1e-12].max())


def baseline_duration(points: np.ndarray, length: float, a_max: float) -> float:
    """Total moving time [s] of the thesis baseline on a layout (sum of 2T + t_max)."""
    T = natural_period(length)
    return float(sum(baseline_segment(float(s), a_max, T).duration for s in segment_lengths(points)))


__all__ = [
    "AntiSwayOptions",
    "AntiSwayPlan",
    "SegmentPlan",
    "SHAPERS",
    "DEFAULT_LAYOUT",
    "DEFAULT_Z",
    "plan_layout",
    "effective_period",
    "linear_residual",
    "planar_midpoint_angle",
    "design_profile",
    "baseline_duration",
    "Shaper",
    "simulate_path",
    "residual_sway",
]
