"""Rest-to-rest motion profiles written as a step convolved with normalised boxes and an impulse shaper.

The distance s [m] travelled along a segment is s·(H ⊗ B(τ_1) ⊗ … ⊗ B(τ_n) ⊗ Σ A_i δ(t − t_i))(t), where H is
the unit step and B(τ) the box of length τ [s] and area 1. With τ_1 ≥ τ_2 ≥ τ_3 the peak velocity is s/τ_1,
the peak acceleration s/(τ_1 τ_2) and the peak jerk s/(τ_1 τ_2 τ_3): the classic jerk-limited "S-curve" is
three boxes (τ_1 ≥ τ_2 + τ_3 keeps the jerk bound), the thesis's acceleration shaping is two boxes one of which lasts one pendulum period, and a box
of length T is also a (distributed) zero-vibration shaper. Position, velocity, acceleration and jerk are
closed-form piecewise polynomials; shapers with A_i ≥ 0 never raise the peaks.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from .shapers import Shaper, identity_shaper


class ProfileDerivatives:
    """position … jerk of a rest-to-rest profile from its ``derivative(t, order)``."""

    def derivative(self, t: np.ndarray, order: int) -> np.ndarray:  # pragma: no cover - interface
        raise NotImplementedError

    def position(self, t: np.ndarray) -> np.ndarray:
        """Distance along the segment [m] at times t [s]."""
        return self.derivative(t, 0)

    def velocity(self, t: np.ndarray) -> np.ndarray:
        """[m/s]"""
        return self.derivative(t, 1)

    def acceleration(self, t: np.ndarray) -> np.ndarray:
        """[m/s²]"""
        return self.derivative(t, 2)

    def jerk(self, t: np.ndarray) -> np.ndarray:
        """[m/s³] (steps where the acceleration has corners)."""
        return self.derivative(t, 3)


@dataclass(frozen=True)
class BoxProfile(ProfileDerivatives):
    """distance [m] moved by H ⊗ boxes (widths [s]) ⊗ shaper impulses."""

    distance: float
    boxes: tuple[float, ...]
    shaper: Shaper = identity_shaper()

    @property
    def duration(self) -> float:
        """Time from start to rest [s]."""
        return float(sum(self.boxes) + self.shaper.duration)

    def _terms(self) -> tuple[np.ndarray, np.ndarray]:
        """Shifts [s] and signed weights of the ramp terms: subsets of boxes × shaper impulses."""
        shifts, weights = [], []
        scale = self.distance / math.prod(self.boxes)
        for mask in itertools.product((0, 1), repeat=len(self.boxes)):
            shift = sum(b for b, m in zip(self.boxes, mask) if m)
            sign = -1.0 if sum(mask) % 2 else 1.0
            for a, ti in zip(self.shaper.amplitudes, self.shaper.times):
                shifts.append(shift + ti)
                weights.append(sign * a * scale)
        return np.array(shifts), np.array(weights)

    def derivative(self, t: np.ndarray, order: int) -> np.ndarray:
        """d^order/dt^order of the position at times t [s] (order 0..n; units m/s^order)."""
        t = np.asarray(t, dtype=float)
        n = len(self.boxes)
        if order > n:
            raise ValueError(f"order {order} exceeds the profile's smoothness ({n} boxes)")
        shifts, weights = self._terms()
        p = n - order
        tc = np.clip(t, 0.0, self.duration)[..., None] - shifts
        if p == 0:
            ramps = (tc >= 0).astype(float)
        else:
            ramps = np.where(tc > 0, tc, 0.0) ** p / math.factorial(p)
        out = ramps @ weights
        if order == 0:
            out = np.where(t >= self.duration, self.distance, out)
        else:
            out = np.where((t >= self.duration) | (t < 0), 0.0, out)
        return out

    def breakpoints(self) -> np.ndarray:
        """Sorted times [s] where the highest derivative jumps (box corners shifted by the impulses)."""
        shifts, _ = self._terms()
        return np.unique(np.round(shifts, 12))

    def peaks(self) -> tuple[float, float, float]:
        """Exact peak |velocity| [m/s], |acceleration| [m/s²], |jerk| [m/s³] (inf where a derivative jumps)."""
        n = len(self.boxes)
        bp = self.breakpoints()
        mids = 0.5 * (bp[1:] + bp[:-1])
        grid = np.concatenate([bp, np.linspace(0.0, self.duration, 401)])
        v = float(np.abs(self.velocity(grid)).max())
        a = float(np.abs(self.acceleration(np.concatenate([bp, mids]))).max()) if n >= 2 else math.inf
        j = float(np.abs(self.jerk(mids)).max()) if n >= 3 else math.inf
        return v, a, j


def time_optimal_boxes(distance: float, v_max: float, a_max: float, j_max: float) -> tuple[float, ...]:
    """Box widths [s] of the time-optimal rest-to-rest move over ``distance`` [m] within v, a, j limits.

    Any limit may be math.inf. Returns 3 widths (2 without a jerk limit). Equivalent to ruckig's 1-DoF
    time-optimal profile from rest to rest.
    """
    s = abs(distance)
    if s == 0.0:
        return (0.0,)
    c1, c2 = s / v_max, s / a_max  # τ1 ≥ c1 (velocity), τ1·τ2 ≥ c2 (acceleration)
    if math.isinf(j_max):
        t1 = max(c1, math.sqrt(c2))
        return (t1, c2 / t1)
    c3 = s / j_max  # τ1·τ2·τ3 ≥ c3 (jerk), valid with τ1 ≥ τ2 + τ3, τ2 ≥ τ3
    tj = a_max / j_max
    candidates = []
    if math.isfinite(v_max):
        candidates.append((c1, c2 / c1, tj))  # cruise at v_max, accelerate at a_max
        r = math.sqrt(c3 / c1)
        candidates.append((c1, r, r))  # cruise at v_max, a_max not reached
    t2 = 0.5 * (-tj + math.sqrt(tj * tj + 4 * c2))
    candidates.append((t2 + tj, t2, tj))  # no cruise, a_max reached
    r = (c3 / 2) ** (1 / 3)
    candidates.append((2 * r, r, r))  # no cruise, a_max not reached
    best = None
    for t1, t2, t3 in candidates:
        eps = 1e-9
        ok = (
            t1 * (1 + eps) >= t2 + t3
            and t2 * (1 + eps) >= t3
            and t1 * (1 + eps) >= c1
            and t1 * t2 * (1 + eps) >= c2
            and t1 * t2 * t3 * (1 + eps) >= c3
        )
        if ok and (best is None or t1 + t2 + t3 < sum(best)):
            best = (t1, t2, t3)
    assert best is not None, (distance, v_max, a_max, j_max)
    return best
