"""Frame-to-frame tracking of one coloured ball: search a window around a constant-velocity prediction,
fall back to the full frame when it is not there, and report a lost frame as not found (never invented).

While the ball was seen recently (within ``max_coast_s``) only blobs inside a gate around the prediction
count — a ball does not jump, so a red object elsewhere is not taken even when the ball is hidden. The gate
is tight when the velocity is known (two fixes close in time) and grows with the time since the last fix;
after a single fix it allows any plausible speed. Inside the window the shape gates are relaxed (a fast
ball smeared by a long exposure and compression is ragged); acquisition on the full frame uses the strict
gates. After ``max_coast_s`` without a fix the whole frame is searched freely.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from .color import ColorSpec
from .detect import Blob, BlobGates, find_blobs


@dataclass(frozen=True)
class TrackerOptions:
    """Tuning of the search: blob gates, window, proximity gate, area consistency, coasting."""

    gates: BlobGates = field(default_factory=BlobGates)
    window_min_half_px: int = 32  # smallest half-size of the search window [px]
    window_radius_factor: float = 4.0  # window half-size ≥ this × the ball radius + the gate
    area_ratio_max: float = 2.5  # once locked, a blob whose area differs by more than this factor is not the ball
    gate_radius_factor: float = 3.0  # gate ≥ this × the ball radius [px]
    gate_step_factor: float = 0.6  # gate ≥ this × the predicted displacement since the last fix
    max_acceleration_px_s2: float = 1.5e4  # the gate grows by ½·a·Δt² with the time Δt since the last fix
    max_speed_px_s: float = 4000.0  # with a single recent fix (velocity unknown) the gate is speed × Δt
    velocity_max_gap_s: float = 0.1  # two fixes further apart than this [s] give no velocity
    max_coast_s: float = 0.25  # [s] after this long without a fix the whole frame is searched freely
    locked_min_circularity: float = 0.35  # relaxed shape gates inside the window while locked
    locked_min_ellipse_fit: float = 0.75


@dataclass(frozen=True)
class Prediction:
    """Where the ball should be: centre [px], displacement since the last fix [px], gate radius [px]."""

    u: float
    v: float
    step_px: float
    gate_px: float  # inf when the ball was not seen recently (free search)


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

    def _radius(self) -> float:
        if self._area is not None:
            return math.sqrt(self._area / math.pi)
        return math.sqrt(self.options.gates.max_area_px / math.pi) / 3.0

    def predict(self, t: float) -> Prediction | None:
        """The prediction for a frame at time t [s]; None before the first fix."""
        if not self._fixes:
            return None
        o = self.options
        last = self._fixes[-1]
        age = t - last.t
        if age > o.max_coast_s:
            return Prediction(last.u, last.v, 0.0, math.inf)
        base = o.gate_radius_factor * self._radius()
        if len(self._fixes) == 2 and 0 < last.t - self._fixes[0].t <= o.velocity_max_gap_s:
            prev = self._fixes[0]
            dt = last.t - prev.t
            du, dv = (last.u - prev.u) / dt * age, (last.v - prev.v) / dt * age
            step = math.hypot(du, dv)
            gate = max(base, o.gate_step_factor * step) + 0.5 * o.max_acceleration_px_s2 * age * age
            return Prediction(last.u + du, last.v + dv, step, gate)
        return Prediction(last.u, last.v, 0.0, base + o.max_speed_px_s * age)

    def _area_ok(self, b: Blob) -> bool:
        if self._area is None:
            return True
        r = b.area_px / self._area
        return 1.0 / self.options.area_ratio_max <= r <= self.options.area_ratio_max

    def _choose(self, blobs: list[Blob], pred: Prediction | None) -> Blob | None:
        cands = [b for b in blobs if self._area_ok(b)]
        if pred is not None:
            dist = [math.hypot(b.u - pred.u, b.v - pred.v) for b in cands]
            inside = [(d, b) for d, b in zip(dist, cands) if d <= pred.gate_px]
            return min(inside, key=lambda db: db[0])[1] if inside else None
        if not cands:
            return None
        return max(cands, key=lambda b: b.ellipse_fit)

    def update(self, frame: np.ndarray, t: float) -> Blob | None:
        """Find the ball in a BGR frame taken at time t [s]; None when it is not found."""
        h, w = frame.shape[:2]
        o = self.options
        pred = self.predict(t)
        blob = None
        if pred is not None:
            locked = math.isfinite(pred.gate_px)
            reach = pred.gate_px if locked else 0.0
            half = int(max(o.window_min_half_px, o.window_radius_factor * self._radius() + reach))
            x0, y0 = max(int(pred.u) - half, 0), max(int(pred.v) - half, 0)
            x1, y1 = min(int(pred.u) + half + 1, w), min(int(pred.v) + half + 1, h)
            if x1 - x0 > 4 and y1 - y0 > 4 and (x1 - x0) * (y1 - y0) < w * h // 2:
                gates = o.gates
                if locked:
                    gates = replace(
                        gates,
                        min_circularity=min(gates.min_circularity, o.locked_min_circularity),
                        min_ellipse_fit=min(gates.min_ellipse_fit, o.locked_min_ellipse_fit),
                    )
                blob = self._choose(find_blobs(frame[y0:y1, x0:x1], self.spec, gates, (x0, y0), (w, h)), pred)
                if blob is not None and blob.clipped:  # cut by the window: measure it on the whole frame
                    blob = None
        if blob is None:
            self.full_frame_searches += 1
            blob = self._choose(find_blobs(frame, self.spec, o.gates), pred)
        if blob is None:
            return None
        self._fixes = (self._fixes + [_Fix(t, blob.u, blob.v)])[-2:]
        self._area = blob.area_px if self._area is None else 0.8 * self._area + 0.2 * blob.area_px
        return blob
