"""Where the ball's colour stays put: a coarse running average of the colour mask, so that static objects of
the ball's colour (labels, cables, a tool on the table) are learned and not taken for the ball.

At most ≈ 10 times a second, the colour mask of a subsampled frame (about 320 px wide) is blended into the map
with weight Δt/τ, except inside circles the caller names (the ball it is sure of: a ball hanging still must not become
"static"). A pixel that was of the colour for most of the last ~2τ reads close to 1; a ball swinging past
leaves a few per cent. Costs ≈ 0.1 ms per learned 720p frame.
"""

from __future__ import annotations

import math

import numpy as np

from .color import ColorSpec, color_mask

_TARGET_WIDTH_PX = 320  # the map's width [cells]
STATIC_LEVEL = 0.8  # a cell at or above this share of recent time in the colour is static
_MIN_STEP_S = 0.1  # [s] frames closer than this to the last one learned are skipped


class StaticMap:
    """Running share of recent time each (coarse) pixel showed the ball's colour."""

    def __init__(self, spec: ColorSpec, time_constant_s: float = 1.0) -> None:
        self.spec = spec
        self.tau = float(time_constant_s)
        self.factor = 1
        self._map: np.ndarray | None = None
        self._static: np.ndarray | None = None  # _map ≥ STATIC_LEVEL (asked per frame, changed at ≈ 10 Hz)
        self._t: float | None = None
        self.frames = 0

    def update(self, frame: np.ndarray, t: float, exclude: list[tuple[float, float, float]] = ()) -> None:
        """Blend in the frame taken at time t [s]; exclude: circles (u, v, radius) [px] left unchanged."""
        import cv2

        h, w = frame.shape[:2]
        if self._map is None:
            self.factor = max(1, w // _TARGET_WIDTH_PX)
        elif self.frames and t - self._t < _MIN_STEP_S:  # learning at ≈ 10 Hz is plenty for a ≈ 1 s average
            return
        f = self.factor
        small = cv2.resize(frame, (w // f, h // f), interpolation=cv2.INTER_NEAREST)
        mask = color_mask(cv2.cvtColor(small, cv2.COLOR_BGR2HSV), self.spec).astype(np.float32) * (1.0 / 255.0)
        if self._map is None or self._map.shape != mask.shape:
            self._map = np.zeros_like(mask)
            self._static = np.zeros(mask.shape, bool)
            self._t = t
        alpha = float(min(1.0, max(0.0, (t - self._t) / self.tau))) if self.frames else 0.0
        self._t = t
        self.frames += 1
        if alpha <= 0.0:
            return
        keep = [self._cells(u, v, r) for u, v, r in exclude]
        saved = [self._map[y0:y1, x0:x1].copy() for x0, y0, x1, y1 in keep]
        cv2.accumulateWeighted(mask, self._map, alpha)
        for (x0, y0, x1, y1), old in zip(keep, saved):
            self._map[y0:y1, x0:x1] = old
        np.greater_equal(self._map, STATIC_LEVEL, out=self._static)

    def _cells(self, u: float, v: float, r: float) -> tuple[int, int, int, int]:
        f = self.factor
        h, w = self._map.shape
        pad = r + 2.0 * f
        x0, y0 = int(max(0, math.floor((u - pad) / f))), int(max(0, math.floor((v - pad) / f)))
        x1, y1 = int(min(w, math.ceil((u + pad) / f) + 1)), int(min(h, math.ceil((v + pad) / f) + 1))
        return x0, y0, max(x0, x1), max(y0, y1)

    def static_share(self, u: float, v: float, r: float) -> float:
        """Share of the cells within radius r [px] of (u, v) that are static (0 before any learning)."""
        if self._map is None:
            return 0.0
        f = self.factor
        h, w = self._map.shape
        rr = max(r, 0.75 * f)
        x0, y0 = int(max(0, math.floor((u - rr) / f))), int(max(0, math.floor((v - rr) / f)))
        x1, y1 = int(min(w, math.ceil((u + rr) / f))), int(min(h, math.ceil((v + rr) / f)))
        if x1 <= x0 or y1 <= y0:
            return 0.0
        return np.count_nonzero(self._static[y0:y1, x0:x1]) / ((y1 - y0) * (x1 - x0))
