"""Choosing the ball among several candidates that all look like it: prefer motion a pendulum can make.

Each candidate was followed for a while (its centre per frame, NaN where not seen). A ball on a string moves
(a round red object in the scene does not), keeps its distance to the pivot (the string length), and when it
does not move it hangs straight below the pivot. Pure functions on arrays.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

_MIN_SEEN = 0.5  # a candidate seen in fewer than this share of the frames is dropped
_MIN_SEEN_MOVING = 0.8  # a moving candidate is seen in at least this share of the frames
_MAX_JERK = 0.5  # and moves smoothly: |second difference| ≤ this × the largest |first difference|
_JERK_NOISE_PX = 1.0  # ... + this [px] (centroid noise)
_STEP_NOISE_PX = 0.5  # [px] a frame step shorter than this is centroid noise
_MIN_MOVING_SHARE = 0.5  # a moving candidate moves in at least this share of the frame steps
_MAX_JERKY_SHARE = 0.1  # ... in all but this share of the frames (a hopping fragment jerks at every hop)
_PALE = 0.7  # a static candidate less saturated than this × the most saturated one is not the ball
_MOVE_PX = 3.0  # [px] a candidate whose centre strays less than max(this, half a radius) from its median is static


@dataclass(frozen=True)
class Choice:
    """The chosen candidate (index) and why, or index None while the candidates cannot be told apart yet."""

    index: int | None
    reason: str
    moving: bool = False  # the chosen one was judged to move like a pendulum


def _spread(p: np.ndarray) -> float:
    """Largest distance [px] of the finite points (m, 2) from their median."""
    q = p[np.all(np.isfinite(p), axis=1)]
    if len(q) == 0:
        return 0.0
    return float(np.max(np.linalg.norm(q - np.median(q, axis=0), axis=1)))


def _smooth(p: np.ndarray) -> bool:
    """Consecutive positions (m, 2) change smoothly (a swinging ball), not by hops (a flickering fragment)."""
    d1 = np.linalg.norm(np.diff(p, axis=0), axis=1)
    d2 = np.linalg.norm(np.diff(p, 2, axis=0), axis=1)
    d1, d2 = d1[np.isfinite(d1)], d2[np.isfinite(d2)]
    if len(d2) < 3:
        return False
    jerky = d2 > _MAX_JERK * float(np.max(d1)) + _JERK_NOISE_PX
    return float(np.mean(jerky)) <= _MAX_JERKY_SHARE


def _steady(p: np.ndarray) -> bool:
    """The centre moves (more than centroid noise) in at least half of the frame steps, not in a few hops."""
    d1 = np.linalg.norm(np.diff(p, axis=0), axis=1)
    d1 = d1[np.isfinite(d1)]
    return len(d1) > 0 and float(np.mean(d1 > _STEP_NOISE_PX)) >= _MIN_MOVING_SHARE


def choose_pendulum(
    centres: list[np.ndarray],
    pivots: np.ndarray | None,
    radius_px: float,
    fits: list[float],
    saturations: list[float] | None = None,
    final: bool = False,
) -> Choice:
    """Pick the candidate that moves like a pendulum.

    centres: per candidate (m, 2) centres [px] over the same m frames (NaN where lost); pivots: (m, 2) pivot
    [px] (NaN where unknown) or None; radius_px: ball radius [px]; fits, saturations: ellipse fit and peak
    saturation of each candidate when first seen. Rules, in order: drop candidates seen in < half the
    frames; if some move (seen in most frames, in most frame steps, smoothly, farther than half a radius) keep
    the moving ones,
    and with a pivot take the one whose distance to the pivot varies least (relative). If none moves, the
    choice waits (index None) until final: then drop those much paler than the most saturated one, and with a
    pivot take the one hanging closest to straight below it, else the best ellipse fit.
    """
    n = len(centres)
    seen = [float(np.mean(np.all(np.isfinite(c), axis=1))) if len(c) else 0.0 for c in centres]
    alive = [k for k in range(n) if seen[k] >= _MIN_SEEN]
    if not alive:
        return Choice(int(np.argmax(fits)) if final else None, "no candidate was seen in most frames")
    thr = max(_MOVE_PX, 0.5 * radius_px)

    def moves(k: int) -> bool:
        return seen[k] >= _MIN_SEEN_MOVING and _spread(centres[k]) > thr and _smooth(centres[k]) and _steady(centres[k])

    if len(alive) == 1:
        return Choice(alive[0], "the only candidate seen in most frames", moves(alive[0]))
    moving = [k for k in alive if moves(k)]
    pool = moving if moving else alive
    if len(pool) == 1:
        return Choice(pool[0], "the only one moving" if moving else "the only candidate left", bool(moving))
    if not moving and not final:
        return Choice(None, "none moves yet")
    if not moving and saturations is not None:
        top = max(saturations[k] for k in pool)
        pool = [k for k in pool if not saturations[k] < _PALE * top]
        if len(pool) == 1:
            return Choice(pool[0], "none moves; the others are paler")
    piv_ok = pivots is not None and np.any(np.all(np.isfinite(pivots), axis=1))
    if piv_ok:
        if moving:

            def cv(k: int) -> float:
                r = np.linalg.norm(centres[k] - pivots, axis=1)
                r = r[np.isfinite(r)]
                return float(np.std(r) / max(np.mean(r), 1.0)) if len(r) >= 2 else math.inf

            best = min(pool, key=cv)
            return Choice(best, f"its distance to the pivot is the steadiest ({100 * cv(best):.1f} % variation)", True)

        def tilt(k: int) -> float:
            d = np.nanmedian(centres[k] - pivots, axis=0)
            return abs(math.atan2(d[0], d[1]))

        best = min(pool, key=tilt)
        return Choice(
            best, f"none moves; it hangs closest to straight below the pivot ({math.degrees(tilt(best)):.1f}°)"
        )
    if final:
        best = max(pool, key=lambda k: fits[k])
        return Choice(best, "none could be told apart by motion; took the roundest")
    return Choice(None, "undecided")
