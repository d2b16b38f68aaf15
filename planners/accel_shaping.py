"""The thesis's anti-sway baseline: basic acceleration shaping (thesis Fig. 4.4, Hoang et al.).

Per segment of length s between turning points: s_min = ½·a_max·T², v_max = a_max·T; if s ≥ 2·s_min the pivot
accelerates with a = a_max for one period T, cruises t_max = (s − 2·s_min)/v_max and brakes for T, otherwise
t_max = 0 and a = s/T². The acceleration a·1(t) − a·1(t−T) − a·1(t−T−t_max) + a·1(t−2T−t_max) is integrated
twice, sampled every h and the segments are concatenated (each segment keeps its own t = 0 sample, so the
pivot rests one sample at every turning point). The symbolic profile stays at s after 2T + t_max; each segment
is sampled at t = k·h for k = 0 … ⌈(2T + t_max)/h⌉ so that it ends exactly at its turning point.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class BaselineSegment:
    """One segment of the baseline: length [m], acceleration [m/s²], cruise time t_max [s], period T [s]."""

    length: float
    accel: float
    t_cruise: float
    period: float

    @property
    def duration(self) -> float:
        """2T + t_max [s]."""
        return 2.0 * self.period + self.t_cruise

    def acceleration(self, t: np.ndarray) -> np.ndarray:
        """a·(1(t) − 1(t−T) − 1(t−T−t_max) + 1(t−2T−t_max)) [m/s²]."""
        t = np.asarray(t, dtype=float)
        T, tm, a = self.period, self.t_cruise, self.accel
        return a * ((t >= 0) * 1.0 - (t >= T) - (t >= T + tm) + (t >= 2 * T + tm))

    def position(self, t: np.ndarray) -> np.ndarray:
        """The acceleration integrated twice from rest: distance along the segment [m]."""
        t = np.asarray(t, dtype=float)
        T, tm, a = self.period, self.t_cruise, self.accel

        def r2(x: np.ndarray) -> np.ndarray:
            return np.where(x > 0, x, 0.0) ** 2 / 2.0

        return a * (r2(t) - r2(t - T) - r2(t - T - tm) + r2(t - 2 * T - tm))


def baseline_segment(length: float, a_max: float, period: float) -> BaselineSegment:
    """Fig. 4.4 lines 10–20 for one segment of ``length`` [m]."""
    s_min = 0.5 * a_max * period**2
    v_max = a_max * period
    if length >= 2.0 * s_min:
        return BaselineSegment(length, a_max, (length - 2.0 * s_min) / v_max, period)
    return BaselineSegment(length, length / period**2, 0.0, period)


def segment_lengths(points: np.ndarray) -> np.ndarray:
    """Distances [m] between consecutive points (n, 2)."""
    return np.linalg.norm(np.diff(np.asarray(points, dtype=float), axis=0), axis=1)


@dataclass(frozen=True)
class BaselinePlan:
    """Sampled pivot path: times t (n,) [s], horizontal positions xy (n, 2) [m], and the segments."""

    t: np.ndarray
    xy: np.ndarray
    segments: tuple[BaselineSegment, ...]
    segment_start: np.ndarray  # index of each segment's first sample


def plan_accel_shaping(points: np.ndarray, h: float, a_max: float, period: float) -> BaselinePlan:
    """PLANTRAJECTORY of thesis Fig. 4.4: start point + turning points (n, 2) [m], step h [s], a_max [m/s²], T [s]."""
    pts = np.asarray(points, dtype=float)
    chunks, starts, segs = [], [], []
    count = 0
    for p0, p1, s in zip(pts[:-1], pts[1:], segment_lengths(pts)):
        seg = baseline_segment(float(s), a_max, period)
        n = int(math.ceil(seg.duration / h - 1e-9)) + 1
        d = seg.position(np.arange(n) * h)
        direction = (p1 - p0) / s if s > 0 else np.zeros(2)
        chunk = p0 + d[:, None] * direction
        chunk[-1] = p1
        starts.append(count)
        count += n
        chunks.append(chunk)
        segs.append(seg)
    xy = np.vstack(chunks)
    return BaselinePlan(np.arange(len(xy)) * h, xy, tuple(segs), np.array(starts))
