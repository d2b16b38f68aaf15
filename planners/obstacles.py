"""Obstacles on the table and the clearance of the swinging ball: axis-aligned boxes in the base frame [m].

The ball is a sphere of radius r whose centre hangs at the string length below the pivot along the string
direction s(t) of the predicted spherical pendulum: r_ball(t) = p(t) + l·s(t). A box is touched when the distance
from the ball centre to the box is below r (the distance is 0 inside the box).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Obstacle:
    """Axis-aligned box: corner ``lower`` (x, y, z) ≤ ``upper`` [m], base frame."""

    name: str
    lower: tuple[float, float, float]
    upper: tuple[float, float, float]

    def distance(self, points: np.ndarray) -> np.ndarray:
        """Euclidean distance [m] from points (n, 3) to the box (0 inside)."""
        p = np.asarray(points, dtype=float)
        below = np.maximum(np.asarray(self.lower) - p, 0.0)
        above = np.maximum(p - np.asarray(self.upper), 0.0)
        return np.linalg.norm(below + above, axis=-1)


@dataclass(frozen=True)
class Clearance:
    """Least clearance [m] (distance − ball radius; < 0: contact) over all swept paths and obstacles."""

    clearance: float
    obstacle: str
    time: float  # [s] of the least clearance (first contact if there is one)
    length: float  # [m] string length of the path that came closest
    position: tuple[float, float, float]  # ball centre there [m]

    @property
    def touches(self) -> bool:
        return self.clearance < 0.0


def ball_path(pivot: np.ndarray, string_dir: np.ndarray, length: float) -> np.ndarray:
    """Ball centres (n, 3) [m] for pivot positions (n, 3) [m] and unit string directions (n, 3)."""
    return np.asarray(pivot, dtype=float) + length * np.asarray(string_dir, dtype=float)


def clearance(
    t: np.ndarray, paths: dict[float, np.ndarray], obstacles: tuple[Obstacle, ...], radius: float
) -> Clearance | None:
    """Least clearance of ball paths {length [m]: (n, 3) [m] sampled at t (n,) [s]}; the first contact if any.

    None without obstacles.
    """
    best: Clearance | None = None
    first: Clearance | None = None
    for length, path in paths.items():
        for ob in obstacles:
            c = ob.distance(path) - radius
            k = int(np.argmin(c))
            cand = Clearance(float(c[k]), ob.name, float(t[k]), float(length), tuple(map(float, path[k])))
            if best is None or cand.clearance < best.clearance:
                best = cand
            hit = np.nonzero(c < 0.0)[0]
            if len(hit) and (first is None or t[hit[0]] < first.time):
                j = int(hit[0])
                first = Clearance(float(c[k]), ob.name, float(t[j]), float(length), tuple(map(float, path[j])))
    return first if first is not None else best


__all__ = ["Obstacle", "Clearance", "ball_path", "clearance"]
