"""Length-robust rest-to-rest moves: the quickest piecewise-linear acceleration that leaves little swing.

For a segment of length s [m] the acceleration nodes a_k (``ramp_profile.RampProfile``) solve a linear
programme (scipy ``linprog``, HiGHS) at a fixed duration D:

    minimise ε  s.t.  (ω/g)·|∫ a(t)·e^{iωt} dt| ≤ ε  for ω across the band   (residual amplitude of the
                      linear pendulum θ̈ + ω²θ = −(ω²/g)·ẍ after the move, for every string length allowed)
                      |a_k| ≤ a_max, |a_{k+1} − a_k| ≤ j_max·δ, 0 ≤ v ≤ v_max, v(D) = 0, p(D) = s,
                      optionally |θ(t_k)| ≤ θ_max during the move at three frequencies of the band.

The modulus is bounded by a regular octagon (8 half-planes, exact within cos(π/8)). The duration is then the
shortest D (bisection) whose optimum meets the residual bound: for the linear model this is the time-optimal
move with a guaranteed residual over the whole band, i.e. the ZVD/EI idea without a fixed impulse pattern.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .pendulum import G
from .profiles import time_optimal_boxes
from .ramp_profile import RampProfile

OCTAGON = math.cos(math.pi / 8)  # |z| ≤ ε/OCTAGON when all 8 projections are ≤ ε


@dataclass(frozen=True)
class RobustSpec:
    """What a robust segment must meet: frequency band [rad/s], residual [rad], optional peak sway [rad]."""

    omega_lo: float
    omega_hi: float
    residual: float
    max_sway: float | None = None
    n_freq: int = 9
    offset: tuple[complex, ...] | None = None  # nonlinear − linear residual per band frequency [rad]

    @property
    def omegas(self) -> np.ndarray:
        """The band's check frequencies [rad/s]."""
        return np.linspace(self.omega_lo, self.omega_hi, self.n_freq)

    def with_offset(self, offset: np.ndarray) -> "RobustSpec":
        return RobustSpec(self.omega_lo, self.omega_hi, self.residual, self.max_sway, self.n_freq, tuple(offset))


def _grid_size(duration: float, omega_hi: float) -> int:
    """Nodes per move: ≥ 40 per shortest period, 48..220."""
    return int(np.clip(math.ceil(duration * omega_hi / (2 * math.pi) * 28), 40, 200))


def _sway_rows(tk: np.ndarray, omega: float, step: float, sub: int = 4) -> np.ndarray:
    """(N+1, N+1) map from acceleration nodes to the linear tilt θ(t_m) [rad] at the nodes (trapezoid, sub-steps)."""
    n = len(tk) - 1
    tf = np.arange(n * sub + 1) * (step / sub)
    # hat-function interpolation: fine samples = P @ nodes
    pos = tf / step
    k = np.minimum(pos.astype(int), n - 1)
    w = pos - k
    P = np.zeros((len(tf), n + 1))
    P[np.arange(len(tf)), k] = 1.0 - w
    P[np.arange(len(tf)), k + 1] += w
    lag = tk[:, None] - tf[None, :]
    K = np.where(lag >= 0, np.sin(omega * lag), 0.0) * (step / sub)
    # trapezoid: half weight at τ = 0 and τ = t_m (sin(0) = 0 there, so only τ = 0 matters)
    K[:, 0] *= 0.5
    return -(omega / G) * (K @ P)


def solve_at_duration(
    s: float, duration: float, spec: RobustSpec, a_max: float, j_max: float, v_max: float
) -> tuple[float, RampProfile] | None:
    """Least worst-case residual [rad] (octagon bound) and its profile at ``duration`` [s]; None if infeasible."""
    from scipy.optimize import linprog
    from scipy.sparse import csr_matrix, hstack, vstack

    n = _grid_size(duration, spec.omega_hi)
    d = duration / n
    m = n - 1  # free nodes a_1 … a_{n-1}
    tk = np.arange(1, n) * d
    # jerk: |a_{k+1} − a_k| ≤ j·δ with a_0 = a_n = 0
    D = csr_matrix(np.eye(m + 1, m) - np.eye(m + 1, m, -1))  # a_k − a_{k−1}, k = 1..n
    jd = j_max * d if math.isfinite(j_max) else 1e9
    # speed variables v_1 … v_m at the nodes (sparse): v_k − v_{k−1} = δ·(a_{k−1} + a_k)/2, 0 ≤ v ≤ v_max
    # residual over the band, 8 directions: Z = (ω/g)·∫ a e^{−iωt} dt (+ the nonlinear offset)
    w = spec.omegas
    scale = (w / G) * d * np.sinc(w * d / (2 * np.pi)) ** 2
    ph = np.multiply.outer(w, tk)
    c, sn = np.cos(ph) * scale[:, None], -np.sin(ph) * scale[:, None]
    ang = np.arange(8) * (np.pi / 4)
    R = (np.cos(ang)[:, None, None] * c[None] + np.sin(ang)[:, None, None] * sn[None]).reshape(-1, m)
    off = np.zeros(len(w), complex) if spec.offset is None else np.asarray(spec.offset, complex)
    b_res = -(np.cos(ang)[:, None] * off.real[None] + np.sin(ang)[:, None] * off.imag[None]).reshape(-1)
    nv = m + m + 1  # a, v, ε

    def pad(block: np.ndarray | csr_matrix, eps_col: float = 0.0) -> csr_matrix:
        """[block (acceleration columns), 0 (speed columns), eps_col·1]"""
        k = block.shape[0]
        return hstack([csr_matrix(block), csr_matrix((k, m)), csr_matrix(np.full((k, 1), eps_col))]).tocsr()

    A_ub = [pad(D), pad(-D), pad(R, -1.0)]
    b_ub = [np.full(m + 1, jd), np.full(m + 1, jd), b_res]
    if spec.max_sway is not None:
        tt = np.arange(n + 1) * d
        for om in (spec.omega_lo, 0.5 * (spec.omega_lo + spec.omega_hi), spec.omega_hi):
            S = _sway_rows(tt, om, d)[:, 1:-1]
            A_ub += [pad(S), pad(-S)]
            b_ub += [np.full(len(S), spec.max_sway)] * 2
    # equalities: speed recursion (m rows), v_n = v_m + δ·a_m/2 = 0, p(D) = −δ·Σ a_k t_k = s
    half = 0.5 * d * (np.eye(m) + np.eye(m, k=-1))
    dv = np.eye(m) - np.eye(m, k=-1)
    last = np.zeros((1, 2 * m))
    last[0, m - 1] = 0.5 * d
    last[0, 2 * m - 1] = 1.0
    pos = np.concatenate([-d * tk, np.zeros(m)])[None, :]
    A_eq = hstack([csr_matrix(np.vstack([np.hstack([-half, dv]), last, pos])), csr_matrix((m + 2, 1))]).tocsr()
    b_eq = np.concatenate([np.zeros(m + 1), [s]])
    vmax = None if not math.isfinite(v_max) else v_max
    bounds = [(-a_max, a_max)] * m + [(0.0, vmax)] * m + [(0.0, None)]
    cost = np.zeros(nv)
    cost[-1] = 1.0
    res = linprog(
        cost,
        A_ub=vstack(A_ub).tocsr(),
        b_ub=np.concatenate(b_ub),
        A_eq=A_eq,
        b_eq=b_eq,
        bounds=bounds,
        method="highs",
    )
    if res.status != 0:
        return None
    a = np.concatenate([[0.0], res.x[:m], [0.0]])
    a = np.clip(a, -a_max, a_max)
    prof = RampProfile(s, d, a)
    return float(res.x[-1]) / OCTAGON, _normalised(prof)


def _normalised(prof: RampProfile) -> RampProfile:
    """Remove the solver's round-off: end velocity exactly 0 and end position exactly the distance."""
    a = prof.accel.copy()
    a[1:-1] -= a[1:-1].mean()
    p_end = RampProfile(prof.distance, prof.step, a)._nodes()[1][-1]
    if p_end != 0.0:
        a *= prof.distance / p_end
    return RampProfile(prof.distance, prof.step, a)


def robust_profile(
    s: float,
    spec: RobustSpec,
    a_max: float,
    j_max: float,
    v_max: float,
    max_duration: float | None = None,
    min_duration: float = 0.0,
    rel_tol: float = 0.01,
) -> tuple[RampProfile, float]:
    """Shortest profile (bisection on D) whose band residual is ≤ spec.residual → (profile, residual bound [rad]).

    With ``max_duration`` [s] the search stops there and returns the least-residual profile of that duration
    (its bound may then exceed spec.residual). ``min_duration`` [s]: a duration known to be too short.
    Raises ValueError if no duration up to 16 periods works.
    """
    period = 2 * math.pi / spec.omega_lo
    lo = max(float(sum(time_optimal_boxes(s, v_max, a_max, j_max))), min_duration)
    best = None
    hi = lo + (0.5 if min_duration <= 0 else 0.15) * period
    cap = max_duration if max_duration is not None else math.inf
    while True:
        hi = min(hi, cap)
        sol = solve_at_duration(s, hi, spec, a_max, j_max, v_max)
        if sol is not None and sol[0] <= spec.residual:
            best = (hi, sol)
            break
        if hi >= cap:
            if sol is None:
                raise ValueError(f"no move of {s:g} m fits the limits within {cap:g} s")
            return sol[1], sol[0]
        lo = hi
        hi = hi + 0.3 * period
        if hi > lo + 16 * period:
            raise ValueError(f"no robust move of {s:g} m within {hi:g} s")
    while best[0] - lo > rel_tol * best[0]:
        mid = 0.5 * (lo + best[0])
        sol = solve_at_duration(s, mid, spec, a_max, j_max, v_max)
        if sol is not None and sol[0] <= spec.residual:
            best = (mid, sol)
        else:
            lo = mid
    return best[1][1], best[1][0]


def linear_residual_phasor(profile, omega: np.ndarray) -> np.ndarray:
    """Z = (ω/g)·∫ ẍ(t)·e^{−iωt} dt [rad] of a profile at ω [rad/s]: |Z| is the linear residual amplitude."""
    w = np.asarray(omega, dtype=float)
    return (w / G) * np.conj(profile.spectrum(w))


def planar_run(
    profile, lengths: np.ndarray, step: float = 0.004, until: float | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Nonlinear planar pendulum l·θ̈ + ẍ·cos θ + g·sin θ = 0 from rest, for several lengths at once (RK4).

    Returns the angle θ [rad] and rate θ̇ [rad/s] at the end of the move (or at ``until`` [s]) and the peak |θ|
    [rad] until then.
    """
    ls = np.asarray(lengths, dtype=float)
    dur = profile.duration if until is None else until
    n = max(8, int(math.ceil(dur / step)))
    h = dur / n
    tk = np.arange(n + 1) * h
    acc = profile.acceleration(tk)
    accm = profile.acceleration(tk[:-1] + 0.5 * h)
    th = np.zeros_like(ls)
    w = np.zeros_like(ls)
    peak = np.zeros_like(ls)
    il, gl = 1.0 / ls, G / ls
    cos, sin = np.cos, np.sin
    for k in range(n):
        x0, xm, x1 = acc[k], accm[k], acc[k + 1]
        k1t, k1w = w, -(x0 * cos(th) * il + gl * sin(th))
        t2, w2 = th + 0.5 * h * k1t, w + 0.5 * h * k1w
        k2t, k2w = w2, -(xm * cos(t2) * il + gl * sin(t2))
        t3, w3 = th + 0.5 * h * k2t, w + 0.5 * h * k2w
        k3t, k3w = w3, -(xm * cos(t3) * il + gl * sin(t3))
        t4, w4 = th + h * k3t, w + h * k3w
        k4t, k4w = w4, -(x1 * cos(t4) * il + gl * sin(t4))
        th = th + h / 6.0 * (k1t + 2 * k2t + 2 * k3t + k4t)
        w = w + h / 6.0 * (k1w + 2 * k2w + 2 * k3w + k4w)
        np.maximum(peak, np.abs(th), out=peak)
    return th, w, peak


def free_amplitude(theta: np.ndarray, theta_dot: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """Amplitude [rad] of the free swing through (θ, θ̇) (energy): cos θ_A = cos θ − l·θ̇²/(2g)."""
    return np.arccos(np.clip(np.cos(theta) - np.asarray(lengths) * theta_dot**2 / (2 * G), -1.0, 1.0))


def planar_band(profile, lengths: np.ndarray, step: float = 0.004) -> tuple[np.ndarray, np.ndarray]:
    """(residual amplitude after the move [rad], peak tilt [rad]) of the nonlinear planar pendulum per length."""
    th, w, peak = planar_run(profile, lengths, step)
    amp = free_amplitude(th, w, lengths)
    return amp, np.maximum(peak, amp)


def nonlinear_phasor(profile, omega: np.ndarray, step: float = 0.004) -> tuple[np.ndarray, np.ndarray]:
    """Residual phasor [rad] comparable with ``linear_residual_phasor`` from the nonlinear pendulum of length
    g/ω², and the peak tilt [rad] during the move, per ω [rad/s]."""
    w = np.asarray(omega, dtype=float)
    th, wd, peak = planar_run(profile, G / w**2, step)
    return -np.exp(-1j * w * profile.duration) * (wd / w + 1j * th), peak


__all__ = [
    "RobustSpec",
    "robust_profile",
    "solve_at_duration",
    "planar_band",
    "planar_run",
    "free_amplitude",
    "linear_residual_phasor",
    "nonlinear_phasor",
]
