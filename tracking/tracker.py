"""Frame-to-frame tracking of one coloured ball: search a window around a constant-velocity prediction,
fall back to the full frame when it is not there, and report a lost frame as not found (never invented).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .color import ColorSpec
from .detect import Blob, BlobGates, find_blobs


@dataclass(frozen=True)
class TrackerOptions:
    """Tuning of the search: gates for blobs, window size, area consistency once locked, coasting."""

    gates: BlobGates = field(default_factory=BlobGates)
    window_min_half_px: int = 32  # smallest half-size of the search window [px]
    window_radius_factor: float = 4.0  # window half-size ≥ this × the ball radius
    window_step_factor: float = 2.0  # + this × the predicted displacement since the last fix
    area_ratio_max: float = 2.5  # once locked, a blob whose area differs by more than this factor is not the ball
    max_coast_s: float = 0.25  # [s] after this long without a fix the velocity is forgotten


@dataclass
class _Fix:
    t: float  # [s]
    u: float  # [px]
    v: float  # [px]


class BallTracker:
    """Stateful tracker of one coloured ball; call :meth:`update` once per frame in time order."""

    def __init__(self, spec: ColorSpec, options: TrackerOptions | None = None) -> None:
        self.spec = spec
        self.options = options or TrackerOptions()
        self._fixes: list[_Fix] = []  # the last two fixes
        self._area: float | None = None  # learned ball area [px²]
        self.full_frame_searches = 0  # how often the window failed and the whole frame was searched

    def predict(self, t: float) -> tuple[float, float, float] | None:
        """Predicted centre (u, v) [px] at time t [s] and the predicted displacement [px] since the last fix."""
        if not self._fixes:
            return None
        last = self._fixes[-1]
        if len(self._fixes) < 2 or t - last.t > self.options.max_coast_s:
            return last.u, last.v, 0.0
        prev = self._fixes[-2]
        dt = last.t - prev.t
        if dt <= 0:
            return last.u, last.v, 0.0
        vu, vv = (last.u - prev.u) / dt, (last.v - prev.v) / dt
        du, dv = vu * (t - last.t), vv * (t - last.t)
        return last.u + du, last.v + dv, math.hypot(du, dv)

    def _area_ok(self, b: Blob) -> bool:
        if self._area is None:
            return True
        r = b.area_px / self._area
        return 1.0 / self.options.area_ratio_max <= r <= self.options.area_ratio_max

    def _choose(self, blobs: list[Blob], near: tuple[float, float] | None) -> Blob | None:
        cands = [b for b in blobs if self._area_ok(b)]
        if not cands:
            return None
        if near is not None:
            return min(cands, key=lambda b: math.hypot(b.u - near[0], b.v - near[1]))
        if self._area is not None:
            return max(cands, key=lambda b: b.ellipse_fit - abs(math.log(b.area_px / self._area)))
        return max(cands, key=lambda b: b.ellipse_fit)

    def _radius(self) -> float:
        if self._area is not None:
            return math.sqrt(self._area / math.pi)
        return math.sqrt(self.options.gates.max_area_px / math.pi) / 3.0

    def update(self, frame: np.ndarray, t: float) -> Blob | None:
        """Find the ball in a BGR frame taken at time t [s]; None when it is not found."""
        h, w = frame.shape[:2]
        pred = self.predict(t)
        blob = None
        if pred is not None:
            pu, pv, step = pred
            o = self.options
            half = int(max(o.window_min_half_px, o.window_radius_factor * self._radius() + o.window_step_factor * step))
            x0, y0 = max(int(pu) - half, 0), max(int(pv) - half, 0)
            x1, y1 = min(int(pu) + half + 1, w), min(int(pv) + half + 1, h)
            if x1 - x0 > 4 and y1 - y0 > 4:
                found = find_blobs(frame[y0:y1, x0:x1], self.spec, self.options.gates, (x0, y0), (w, h))
                blob = self._choose(found, (pu, pv))
                if blob is not None and blob.clipped:  # cut by the window: measure it on the whole frame
                    blob = None
        if blob is None:
            self.full_frame_searches += 1
            near = (pred[0], pred[1]) if pred is not None else None
            blob = self._choose(find_blobs(frame, self.spec, self.options.gates), near)
        if blob is None:
            return None
        self._fixes = (self._fixes + [_Fix(t, blob.u, blob.v)])[-2:]
        self._area = blob.area_px if self._area is None else 0.8 * self._area + 0.2 * blob.area_px
        return blob
