"""Patches of frames kept around the ball's fix during the first pass, for the looks after it.

The model look (:mod:`tracking.model_look`) asks frames where a fix was found but later judged off the motion (an
outlier, off the pendulum fitted over its window) whether they show the ball at the fitted place, a few pixels from
that fix. Those frames are not kept whole (the ball was found in them), and decoding the video again up to the last of
them costs as much as the first pass's decoding. A patch of PATCH_RADII ball radii + PATCH_MARGIN_PX around every fix
answers them at a copy of a few kilobytes a frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

PATCH_RADII = 3.0  # a patch reaches this many ball radii ...
PATCH_MARGIN_PX = 16  # ... + this [px] from the fix (the fitted place is a few px off it)
MAX_SHARE = 1.0 / 8.0  # a patch larger than this share of the frame is not kept (a large ball: decoded again)


@dataclass(frozen=True)
class Patch:
    """Pixels of a frame from (x0, y0) [px] on (a copy: the frame's buffer is decoded into again)."""

    x0: int
    y0: int
    pixels: np.ndarray

    def covers(self, x0: int, y0: int, x1: int, y1: int) -> bool:
        """The box x0 ≤ x < x1, y0 ≤ y < y1 [px] of the frame lies within the patch."""
        h, w = self.pixels.shape[:2]
        return x0 >= self.x0 and y0 >= self.y0 and x1 <= self.x0 + w and y1 <= self.y0 + h


def patch_around(frame: np.ndarray, u: float, v: float, radius_px: float) -> Patch | None:
    """The patch of the frame around a fix at (u, v) of radius_px [px]; None when it would be too large to keep."""
    h, w = frame.shape[:2]
    half = int(PATCH_RADII * radius_px + PATCH_MARGIN_PX) if math.isfinite(radius_px) else w
    if 4 * half * half > MAX_SHARE * w * h or not (math.isfinite(u) and math.isfinite(v)):
        return None
    x0, y0 = min(max(int(u) - half, 0), w), min(max(int(v) - half, 0), h)
    x1, y1 = min(max(int(u) + half + 1, 0), w), min(max(int(v) + half + 1, 0), h)
    return Patch(x0, y0, frame[y0:y1, x0:x1].copy())
