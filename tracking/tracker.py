"""Frame-to-frame tracking of one coloured ball: search a window around a constant-velocity prediction,
fall back to the full frame when it is not there, and report a lost frame as not found (never invented).

While the ball was seen recently (within ``max_coast_s``) only blobs inside a gate around the prediction
count — a ball does not jump, so a red object elsewhere is not taken even when the ball is hidden. The gate
is tight when the velocity is known (two fixes close in time) and grows with the time since the last fix;
after a single fix it allows any plausible speed. Inside the window the shape gates are relaxed (a fast
ball smeared by a long exposure and compression is ragged), and when the ball moves fast the colour's
saturation threshold is lowered step by step (a blurred streak is the ball's colour mixed with the
background's). Acquisition on the full frame uses the strict gates. After ``max_coast_s`` without a fix the
whole frame is searched freely and what was learned about the ball (its area) is forgotten.

No lock-in on a bad first fix: the learned area is the median of the last fixes, and when a blob at the
predicted place, passing the strict shape gates, is rejected for its area alone in ``area_reset_misses``
frames in a row, the learned area is dropped (a fragment seen in a dark frame does not shut out the real ball). When the free search finds
several candidates, each is followed, and once one moves like a pendulum over the last ``resolve_s`` it is
kept (:mod:`tracking.ambiguity`); if none moves within ``max_resolve_s`` (or by the end of the video) the
static rules choose. The frames seen meanwhile are then revised (:meth:`BallTracker.pop_revision`).
``start_uv`` names the ball instead: the first fix is the candidate nearest to it.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field, replace
from statistics import median

import numpy as np
import numpy.ma  # noqa: F401  # np.percentile imports it on its first call: a 15-35 ms stall in a live stream's first second

from .ambiguity import choose_pendulum
from .color import ColorSpec, with_min_saturation
from .detect import (
    SHAPE_MIN_AREA_PX,
    TINY_MAX_AREA_PX,
    Blob,
    BlobGates,
    coarse_factor,
    coarse_hsv,
    detail_scale,
    find_blobs,
    find_blobs_coarse,
    find_blobs_scaled,
    find_tiny,
    to_hsv,
    too_dark,
)
from .static_map import StaticMap

COARSE_WINDOW_PX = 250_000  # search windows larger than this [px²] get the coarse first pass of whole frames
TENTATIVE = 0.4  # confidence of a fix on a lock not yet confirmed, or while candidates are being judged
CONFIRMED = 0.9  # confidence given to the frames of a lock once it is confirmed
_ON_STATIC = 0.3  # confidence factor of a fix on a place where the ball's colour has been static
_WEAK_SHAPE = 0.8  # ... of a fix less round than the strict gates while not moving fast


@dataclass(frozen=True)
class TrackerOptions:
    """Tuning of the search: blob gates, window, proximity gate, area consistency, coasting, acquisition."""

    gates: BlobGates = field(default_factory=BlobGates)
    window_min_half_px: int = 32  # smallest half-size of the search window [px]
    window_radius_factor: float = 2.5  # window half-size ≥ this × the ball radius + the gate ...
    window_streak_radii: float = 1.5  # ... + the last frame step (a motion-blurred streak), at most this × the radius
    near_radius_factor: float = 2.0  # first a small window: half-size this × the radius + the streak + near_margin_px
    near_margin_px: float = 8.0  # [px] (where the ball nearly always is: the whole window only when it is not there)
    area_ratio_max: float = 2.5  # once locked, a blob whose area differs by more than this factor is not the ball
    area_history: int = 15  # the learned area is the median of this many last fixes
    area_reset_misses: int = 3  # frames in a row with a blob rejected for its area alone → forget the area
    gate_radius_factor: float = 3.0  # gate ≥ this × the ball radius [px]
    gate_step_factor: float = 0.6  # gate ≥ this × the predicted displacement since the last fix
    max_acceleration_px_s2: float = 4e4  # the gate grows by ½·a·Δt² with the time Δt since the last fix
    max_speed_px_s: float = 4000.0  # with a single recent fix (velocity unknown) the gate is speed × Δt
    velocity_max_gap_s: float = 0.1  # two fixes further apart than this [s] give no velocity
    max_coast_s: float = 0.25  # [s] after this long without a fix the whole frame is searched freely
    locked_min_circularity: float = 0.35  # relaxed shape gates inside the window while locked
    locked_min_ellipse_fit: float = 0.75
    streak_min_circularity: float = 0.2  # ... and more so for a streak (moving more than its diameter per frame)
    streak_min_ellipse_fit: float = 0.65
    learned_saturation_factor: float = (
        0.55  # in the window, first try pixels this saturated relative to the ball's peak
    )
    acquire_min_saturation: int = 170  # on a free search finding nothing, retry with only this saturated pixels
    blur_min_step_radii: float = 0.5  # moving more than this many radii per frame, the ball is a blurred streak:
    blur_saturation_factor: float = 0.5  # ... its pixels are taken from this × its expected peak saturation
    blur_min_saturation: int = 20  # ... but never below this (the background's own saturation and noise)
    start_uv: tuple[float, float] | None = None  # [px] the ball at the first fix is the candidate nearest to this
    start_radius_px: float = 60.0  # [px] ... within this distance
    resolve_s: float = 0.4  # [s] several candidates on a free search: follow each, judge the motion over this
    max_resolve_s: float = 10.0  # [s] ... and wait up to this long for one to move (else the static rules)
    max_candidates: int = 6  # at most this many candidates are followed
    max_radius_share: float | None = 1.0 / 6.0  # a ball's radius may reach this share of the frame height (None: gates)
    loose_circularity: float = 0.45  # when no blob passes the strict gates, acquire from blobs this round ...
    loose_ellipse_fit: float = 0.75  # ... (a ball turned into blocks by a low-bitrate codec), tentatively
    max_aspect: float = 2.5  # acquisition: a blob longer than this × its width is not a ball (a tool's handle)
    tiny_search: bool = True  # when nothing else is found, look for balls a few pixels across (detect.find_tiny)
    confirm_frames: int = 3  # a new lock is tentative (unsure) until followed this many frames ...
    confirm_move_radii: float = (
        1.0  # ... and moved this many radii (at least 3 px), or hangs at rest (round, plumb when a pivot is known)
    )
    min_confidence: float = 0.5  # a fix below this confidence is reported unsure (not found)
    string_tolerance: float = (
        0.25  # with a pivot: a fix farther than (1 + this) × the learned string length is rejected
    )
    string_min_fixes: int = 20  # the string length [px] is learned from this many confident fixes
    static_lock_s: float = 0.6  # [s] a lock that has not moved for this long may be an object, not the ball:
    recheck_s: float = 0.5  # [s] ... look this often for other candidates and keep the one moving like a pendulum
    plumb_deg: float = 15.0  # a new lock at rest is confirmed only within this of the pivot's vertical (a hanging ball)
    rest_confirm_s: float = 0.25  # [s] ... once followed this long (a codec's ghost of the ball stays a few frames)
    regain_missed_frames: int = 2  # a confirmed lock that finds a blob after missing this many frames or more ...
    regain_radii: float = (
        3.0  # ... this many radii off its prediction (and more, see below) is tentative until confirmed again
    )
    static_time_constant_s: float = 1.0  # [s] of the map of static objects in the ball's colour (tracking.static_map)


@dataclass(frozen=True)
class Prediction:
    """Where the ball should be: centre [px], displacement since the last fix [px], gate radius [px]."""

    u: float
    v: float
    step_px: float
    gate_px: float  # inf when the ball was not seen recently (free search)
    frame_step_px: float = (
        0.0  # displacement between the last two fixes [px] (the length of a motion-blur streak at most)
    )


@dataclass
class _Fix:
    t: float  # [s]
    u: float  # [px]
    v: float  # [px]


class _Follower:
    """One locked ball hypothesis: last fixes, learned area, window search."""

    def __init__(self, spec: ColorSpec, options: TrackerOptions, blob: Blob, t: float) -> None:
        self.spec = spec
        self.options = options
        self.fixes: list[_Fix] = [_Fix(t, blob.u, blob.v)]
        self.areas: deque[float] = deque([blob.area_px], maxlen=options.area_history)
        self._area: float | None = None  # median of ``areas``, None after they change
        self.area_misses = 0
        self.fit = blob.ellipse_fit
        self.sats: deque[float] = deque([blob.saturation], maxlen=options.area_history)
        self._peak_cache: tuple[float | None] | None = None  # (median of the finite sats,) once asked
        self._radius = (math.nan, math.nan)  # (area [px²], radius [px]) last computed
        self._min_s = min(b.lower[1] for b in spec.bands)
        self._sat_specs: dict[int, ColorSpec] = {}
        self.tiny = blob.area_px <= TINY_MAX_AREA_PX and blob.circularity == 1.0 and blob.ellipse_fit == 1.0
        self.hits = 1  # fixes since acquisition
        self.confirmed = False
        self.pending: list[tuple[int, Blob]] = []  # tentative frames (update index, blob) until confirmed
        self.origin = (blob.u, blob.v)
        self.origin_t = t  # [s] when the lock began
        self.round = True  # acquired by the strict shape gates
        self.recent: deque[tuple[float, float, float, int]] = deque()  # (t, u, v, update index) of the last fixes
        self.string_misses = 0
        self.last_recheck = t
        self.named = False  # the user named it (start_uv)

    def _at(self, level: int) -> ColorSpec:
        if level not in self._sat_specs:
            self._sat_specs[level] = with_min_saturation(self.spec, level)
        return self._sat_specs[level]

    def _specs(self, pred: Prediction) -> list[ColorSpec]:
        """Colour thresholds to try in the window, in order. Moving fast, the ball is a streak whose colour is
        mixed with the background's: its peak saturation falls to about the ball's × its coverage 2r/ℓ (ℓ the
        distance moved in a frame, the longest the exposure can smear it, doubled for a ball speeding up), so
        the threshold is half of that.
        Otherwise the ball's own saturation first (keeps out paler objects of the same hue, such as skin
        beside an orange ball), then the colour's."""
        o = self.options
        known = self._peak()
        peak = known if known is not None else 255.0
        if pred.frame_step_px > o.blur_min_step_radii * self.radius():
            coverage = min(1.0, self.radius() / pred.frame_step_px)  # allowing the speed to double
            level = int(o.blur_saturation_factor * coverage * peak) // 5 * 5
            level = max(o.blur_min_saturation, level)
            if level < self._min_s:
                return [self._at(level), self.spec]
            return [self.spec]
        level = int(o.learned_saturation_factor * peak) // 10 * 10
        if known is not None and level > self._min_s:
            return [self._at(level), self.spec]
        return [self.spec]

    @property
    def area(self) -> float:
        """Median of the learned areas [px²] (cached: asked for many times per frame)."""
        if self._area is None:
            self._area = float(median(self.areas))
        return self._area

    def radius(self) -> float:
        """Radius [px] of the disc of the learned area (cached with it)."""
        area = self.area
        if self._radius[0] != area:
            self._radius = (area, math.sqrt(area / math.pi))
        return self._radius[1]

    def _peak(self) -> float | None:
        """Median of the learned peak saturations (None before any), cached until the next is learned."""
        if self._peak_cache is None:
            sats = [x for x in self.sats if math.isfinite(x)]
            self._peak_cache = (median(sats) if sats else None,)
        return self._peak_cache[0]

    def learned_saturation(self) -> float | None:
        """The ball's learned peak saturation (0–255; the median of the last fixes'), None before any."""
        return self._peak()

    def min_radius(self) -> float:
        """Radius [px] of the smallest blob that can still be the ball (area_ratio_max below the learned area)."""
        return self.radius() / math.sqrt(self.options.area_ratio_max)

    def predict(self, t: float) -> Prediction:
        o = self.options
        last = self.fixes[-1]
        age = t - last.t
        if age > o.max_coast_s:
            return Prediction(last.u, last.v, 0.0, math.inf)
        base = o.gate_radius_factor * self.radius()
        if len(self.fixes) == 2 and 0 < last.t - self.fixes[0].t <= o.velocity_max_gap_s:
            prev = self.fixes[0]
            dt = last.t - prev.t
            du, dv = (last.u - prev.u) / dt * age, (last.v - prev.v) / dt * age
            step = math.hypot(du, dv)
            gate = max(base, o.gate_step_factor * step) + 0.5 * o.max_acceleration_px_s2 * age * age
            moved = math.hypot(last.u - prev.u, last.v - prev.v)
            return Prediction(last.u + du, last.v + dv, step, gate, moved)
        return Prediction(last.u, last.v, 0.0, base + o.max_speed_px_s * age)

    def _smear(self, pred: Prediction) -> float:
        """Area factor of a motion-blurred streak: longer by up to the distance moved in a frame."""
        return 1.0 + pred.frame_step_px / max(2.0 * self.radius(), 1.0)

    def _area_ok(self, b: Blob, pred: Prediction) -> bool:
        """Within area_ratio_max of the learned area (× the smear of a streak), the learned disc's radius taken
        ± half a pixel first: a ball a few pixels across changes its area by pixelation alone by more than that."""
        r = self.radius()
        ratio = self.options.area_ratio_max
        low, high = math.pi * max(r - 0.5, 0.0) ** 2 / ratio, math.pi * (r + 0.5) ** 2 * ratio * self._smear(pred)
        return low <= b.area_px <= high

    def _saturation_ok(self, b: Blob, pred: Prediction) -> bool:
        """The blob's peak saturation is the ball's, allowing for motion blur (the colour mixed with the
        background over a streak up to a frame's displacement long): a paler object of the same hue that the
        ball merged with or hid behind (a hand) is not taken for it."""
        peak = self._peak()
        if peak is None or not math.isfinite(b.saturation):
            return True
        coverage = min(1.0, 2.0 * self.radius() / max(pred.frame_step_px, 1e-9))
        return b.saturation >= self.options.learned_saturation_factor * coverage * peak

    def choose(self, blobs: list[Blob], pred: Prediction) -> Blob | None:
        """The blob nearest the prediction inside the gate and of a plausible area; counts area-only rejections."""
        inside = sorted(((math.hypot(b.u - pred.u, b.v - pred.v), b) for b in blobs), key=lambda db: db[0])
        inside = [(d, b) for d, b in inside if d <= pred.gate_px]
        for _, b in inside:
            if self._area_ok(b, pred) and self._saturation_ok(b, pred):
                return b
        g = self.options.gates
        round_ = [
            b
            for _, b in inside
            if b.circularity >= g.min_circularity
            and b.ellipse_fit >= g.min_ellipse_fit
            and self._saturation_ok(b, pred)
        ]
        if round_:  # as round as a ball and where the ball should be, only its area is off
            self.area_misses += 1
            if self.area_misses >= self.options.area_reset_misses:  # the learned area was wrong: relearn
                self.areas.clear()
                self.areas.append(round_[0].area_px)
                self._area = None
                self.area_misses = 0
                return round_[0]
        return None

    def note(self, t: float, u: float, v: float, index: int, keep_s: float) -> None:
        """Remember a fix for the rest test (the last keep_s seconds)."""
        self.recent.append((t, u, v, index))
        while self.recent and self.recent[0][0] < t - keep_s:
            self.recent.popleft()

    def at_rest(self, span_s: float) -> bool:
        """The fixes of the last span_s seconds (covering most of it) stay within a radius' share of their median."""
        if len(self.recent) < 3 or self.recent[-1][0] - self.recent[0][0] < 0.8 * span_s:
            return False
        limit = max(1.5, 0.3 * self.radius())
        (_, u0, v0, _), (_, u1, v1, _) = self.recent[0], self.recent[-1]
        if math.hypot(u1 - u0, v1 - v0) > 2.0 * limit:  # both within the limit of the median: not at rest (cheap)
            return False
        p = np.array([(u, v) for _, u, v, _ in self.recent])
        return float(np.max(np.linalg.norm(p - np.median(p, axis=0), axis=1))) <= limit

    def moving(self, min_px: float) -> bool:
        """Moved at least min_px [px] from where the lock began, steadily: each of the last 3 frame steps longer
        than centroid noise (a fragment flickering in a dark frame hops once)."""
        if (
            math.hypot(self.fixes[-1].u - self.origin[0], self.fixes[-1].v - self.origin[1]) < min_px
            or len(self.recent) < 4
        ):
            return False
        p = np.array([(u, v) for _, u, v, _ in list(self.recent)[-4:]])
        return bool(np.all(np.linalg.norm(np.diff(p, axis=0), axis=1) > 0.3))

    def window(self, pred: Prediction, w: int, h: int) -> tuple[int, int, int, int] | None:
        o = self.options
        r = self.radius()
        reach = o.window_radius_factor * r + min(o.window_streak_radii * r, pred.frame_step_px)
        half = int(max(o.window_min_half_px, reach + pred.gate_px))
        x0, y0 = max(int(pred.u) - half, 0), max(int(pred.v) - half, 0)
        x1, y1 = min(int(pred.u) + half + 1, w), min(int(pred.v) + half + 1, h)
        if x1 - x0 > 4 and y1 - y0 > 4 and (x1 - x0) * (y1 - y0) < w * h // 2:
            return x0, y0, x1, y1
        return None

    def search_window(self, frame: np.ndarray, pred: Prediction) -> tuple[Blob | None, bool]:
        """(blob, settled): the ball in the window around a finite prediction (the window covers the whole
        gate). settled False when the window is too large, or the blob is cut by its edge: the caller then
        searches the whole frame; a settled None means the ball is not within the gate."""
        h, w = frame.shape[:2]
        o = self.options
        box = self.window(pred, w, h)
        streak = pred.frame_step_px > 2.0 * self.radius()  # blurred over more than its own size: ragged
        gates = BlobGates(  # (all four fields: cheaper than dataclasses.replace, once a frame)
            min_circularity=min(
                o.gates.min_circularity, o.streak_min_circularity if streak else o.locked_min_circularity
            ),
            min_ellipse_fit=min(
                o.gates.min_ellipse_fit, o.streak_min_ellipse_fit if streak else o.locked_min_ellipse_fit
            ),
            max_area_px=o.gates.max_area_px * self._smear(pred),
            # a ball of a few pixels, sharp for a moment (a turning point), may outline less than the general floor
            min_area_px=min(o.gates.min_area_px, max(4.0, self.area / o.area_ratio_max)),
        )
        scale = detail_scale(self.min_radius())  # a large ball is measured on a shrunk image
        large = box is None or (box[2] - box[0]) * (box[3] - box[1]) > COARSE_WINDOW_PX
        if not self.tiny and (scale > 1 or not large):  # (a fast small ball's large window: the coarse pass is cheaper)
            blob = self._search_near(frame, pred, gates, scale)
            if blob is not None:
                return blob, True
        if box is None:
            return None, False
        x0, y0, x1, y1 = box
        sub = frame[y0:y1, x0:x1]
        if self.tiny:  # a few pixels across: no blur, no morphology, no shape
            found = find_tiny(sub, self.spec, (x0, y0), (w, h), max_area_px=max(TINY_MAX_AREA_PX, 4.0 * self.area))
            blob = self.choose(found, pred)
            if blob is not None and blob.clipped:
                return None, False
            return blob, True
        factor = coarse_factor(w, self.min_radius()) if large else 1
        hsv = (to_hsv(sub) if scale == 1 else None) if factor == 1 else coarse_hsv(sub, factor)
        for spec in self._specs(pred):
            if factor > 1:  # a large window (a fast ball, or the first frames after a fix): coarse pass first
                found = find_blobs_coarse(sub, spec, gates, factor, (x0, y0), (w, h), hsv, scale)
            elif scale > 1:
                found = find_blobs_scaled(sub, spec, gates, scale, (x0, y0), (w, h))
            else:
                found = find_blobs(sub, spec, gates, (x0, y0), (w, h), hsv)
            blob = self.choose(found, pred)
            if blob is not None:
                return (None, False) if blob.clipped else (blob, True)  # clipped: measure it on the whole frame
        return None, True

    def _search_near(self, frame: np.ndarray, pred: Prediction, gates: BlobGates, scale: int) -> Blob | None:
        """The ball in a small window around the prediction — what the whole window would choose (the blob nearest
        the prediction of the ball's area and saturation), found on a fraction of its pixels — or None: nothing
        there, or a blob cut by the small window's edge (the caller then searches the whole window). scale: a large
        ball is measured on the window shrunk by this (:func:`tracking.detect.detail_scale`)."""
        h, w = frame.shape[:2]
        o = self.options
        r = self.radius()
        half = int(o.near_radius_factor * r + min(o.window_streak_radii * r, pred.frame_step_px) + o.near_margin_px)
        x0, y0 = max(int(pred.u) - half, 0), max(int(pred.v) - half, 0)
        x1, y1 = min(int(pred.u) + half + 1, w), min(int(pred.v) + half + 1, h)
        if x1 - x0 <= 4 or y1 - y0 <= 4:
            return None
        found = find_blobs_scaled(frame[y0:y1, x0:x1], self._specs(pred)[0], gates, scale, (x0, y0), (w, h))
        if any(b.clipped for b in found):  # a blob's centre cut off: only the whole window measures it
            return None
        reach = min(pred.gate_px, half - 2.0)  # a blob nearer than this to the prediction lies inside (not clipped)
        for d, b in sorted(((math.hypot(b.u - pred.u, b.v - pred.v), b) for b in found), key=lambda db: db[0]):
            if d > reach:
                return None
            if self._area_ok(b, pred) and self._saturation_ok(b, pred):
                return b
        return None

    def restart(self, blob: Blob, t: float) -> None:
        """Tentative again from this fix (what it learned of the ball is kept): confirmed anew as a new lock is."""
        self.fixes = [_Fix(t, blob.u, blob.v)]  # (no velocity across the gap: the jump would be taken for one)
        self.confirmed = False
        self.pending = []
        self.hits = 1
        self.origin, self.origin_t = (blob.u, blob.v), t
        self.recent.clear()

    def accept(self, blob: Blob, t: float, pred: Prediction | None = None) -> None:
        """Take the blob as the ball at time t [s]; its area and saturation are learned only while it moves
        slowly (a motion-blurred streak is larger and paler than the ball)."""
        self.fixes = (self.fixes + [_Fix(t, blob.u, blob.v)])[-2:]
        self.area_misses = 0
        self.hits += 1
        if pred is not None and pred.frame_step_px > self.options.blur_min_step_radii * self.radius():
            return
        self.areas.append(blob.area_px)
        self._area = None
        self.sats.append(blob.saturation)
        self._peak_cache = None


def follower_from(tracker: "BallTracker", fixes: list[tuple[float, Blob]]) -> _Follower:
    """A confirmed lock of the tracker's ball made of (time [s], blob) fixes in time order (the last is the newest):
    the second look follows the confirmed ball from it (:mod:`tracking.second_look`)."""
    t0, b0 = fixes[0]
    f = _Follower(tracker.spec, tracker.options, b0, t0)
    for t, b in fixes[1:]:
        f.accept(b, t)
    f.confirmed = True
    return f


def _last_jump(centres: list[tuple[float, float]], radius_px: float) -> int:
    """Index where the last continuous stretch of a followed candidate's centres (NaN where not seen) begins: a fix
    farther than 4 radii + 3 px + the distance covered at the last velocity from where that velocity would have taken
    it (after a gap) starts a new stretch; judged once a velocity is known (0 when there is no such jump). A stretch's
    first fix is judged backwards, from the velocity of its second and third: a follower that started on an object
    and (after a gap) went on with the ball jumped there."""
    start, prev, step = 0, None, None  # prev: (frame, u, v); step: last velocity [px/frame]
    first: tuple[int, float, float] | None = None  # a stretch's first fix, until its third judges it
    for j, (u, v) in enumerate(centres):
        if not math.isfinite(u):
            continue
        if prev is not None:
            g = j - prev[0]
            if step is not None:
                miss = math.hypot(u - prev[1] - step[0] * g, v - prev[2] - step[1] * g)
                if miss > 4.0 * radius_px + 3.0 + math.hypot(*step) * g:
                    start, prev, step, first = j, (j, u, v), None, None
                    continue
            new = ((u - prev[1]) / g, (v - prev[2]) / g)
            if first is not None:  # (prev is the stretch's second fix: back from it to the first at this velocity)
                g0 = prev[0] - first[0]
                miss = math.hypot(first[1] - prev[1] + new[0] * g0, first[2] - prev[2] + new[1] * g0)
                if miss > 4.0 * radius_px + 3.0 + math.hypot(*new) * g0:
                    start = prev[0]
                first = None
            elif step is None:
                first = prev
            step = new
        prev = (j, u, v)
    return start


@dataclass
class _Hypotheses:
    """Candidates followed side by side until one is chosen."""

    followers: list[_Follower]
    t0: float  # [s] time of the free search that found them
    first: int  # update index of that frame
    centres: list[list[tuple[float, float]]]  # per follower, per frame since `first`
    blobs: list[list[Blob | None]]
    pivots: list[tuple[float, float]]
    times: list[float]  # [s] of the frames since `first`
    leader: int  # provisional choice (best ellipse fit)
    shown: list[Blob | None]  # what was returned for each frame meanwhile
    starts: list[tuple[float, float]]  # where every candidate was first seen [px]
    merged: bool = False  # some candidates' followers converged onto another's blob and were dropped
    incumbent_frames: list[int] = field(
        default_factory=list
    )  # frames of the lock (follower 0) at rest before: withdrawn if it loses


class BallTracker:
    """Stateful tracker of one coloured ball; call :meth:`update` once per frame in time order.

    Every returned blob comes with :attr:`confidence` (0–1): below ``min_confidence`` the tracker is unsure —
    a new lock not yet confirmed by a few frames of consistent motion, candidates still being judged, a fix on a
    place where the ball's colour has been static — and the caller must not report it as found. Tentative frames
    are revised once the doubt is settled (:meth:`pop_revision`).
    """

    def __init__(self, spec: ColorSpec, options: TrackerOptions | None = None) -> None:
        self.spec = spec
        self.options = options or TrackerOptions()
        self._follower: _Follower | None = None
        self._hyp: _Hypotheses | None = None
        self._n = 0  # updates so far
        self._revision: list[tuple[int, Blob | None, float]] = []
        self.full_frame_searches = 0  # how often the window failed and the whole frame was searched
        self._coarse: tuple[np.ndarray, int, np.ndarray] | None = None  # (frame, factor, coarse HSV) last searched
        self.notes: list[str] = []  # ambiguities met and how they were resolved (for the user)
        self._started = False  # a first fix was made (start_uv only applies before it)
        self._acquire_spec = with_min_saturation(spec, self.options.acquire_min_saturation)
        self._min_value = min(b.lower[2] for sp in (spec, self._acquire_spec) for b in sp.bands)  # HSV V = max(B,G,R)
        self._static = StaticMap(spec, self.options.static_time_constant_s)
        self._excluded: list[tuple[float, float, float]] = []  # (u, v, radius) [px] of objects found not to be the ball
        self._string: deque[float] = deque(maxlen=300)  # distances [px] of confident fixes from the pivot
        self._string_cache: float | None = None
        self._string_added = 0
        self._sized = False
        self.confidence = 0.0  # of the blob returned by the last update (0 when none)
        self.rejected_string = 0  # fixes rejected for lying beyond the string's reach

    # ------------------------------------------------------------------ public

    def predict(self, t: float) -> Prediction | None:
        """The prediction for a frame at time t [s]; None before the first fix."""
        f = self._current()
        return f.predict(t) if f is not None else None

    def pop_revision(self) -> list[tuple[int, Blob | None, float]]:
        """Frames (update index, blob or None, confidence) whose result changed since returned — after choosing
        among candidates, confirming a tentative lock, or finding that a lock sat on a static object; cleared by
        the call."""
        out, self._revision = self._revision, []
        return out

    @property
    def resolving(self) -> bool:
        """Several candidates are being followed; results returned meanwhile may be revised."""
        return self._hyp is not None

    @property
    def string_px(self) -> float | None:
        """The string length learned from confident fixes [px] (their 95th percentile distance from the pivot;
        recomputed every 10 fixes)."""
        if len(self._string) < self.options.string_min_fixes:
            return None
        if self._string_cache is None or self._string_added >= 10:
            self._string_cache = float(np.percentile(np.fromiter(self._string, float), 95))
            self._string_added = 0
        return self._string_cache

    def finish(self) -> None:
        """End of the video: choose among candidates still open (revisions via :meth:`pop_revision`)."""
        if self._hyp is not None:
            self._resolve(final=True)

    def update(self, frame: np.ndarray, t: float, pivot_uv: tuple[float, float] | None = None) -> Blob | None:
        """Find the ball in a BGR frame taken at time t [s]; None when it is not found (see :attr:`confidence`).

        pivot_uv: the pivot in this frame [px] when known (bounds where the ball can be, helps choosing among
        candidates).
        """
        index = self._n
        self._n += 1
        self._coarse = None  # (a frame's buffer may be decoded into again: its coarse image is not kept past it)
        if not self._sized:
            self._size_gates(frame)
        self.confidence = 0.0
        if self._hyp is not None:
            blob = self._update_hypotheses(frame, t, pivot_uv, index)
            if blob is not None:
                settled = self._hyp is None and self._follower is not None and self._follower.confirmed
                self.confidence = CONFIRMED if settled else TENTATIVE
                if self._hyp is None and self._follower is not None and not self._follower.confirmed:
                    self._follower.pending.append((index, blob))
        else:
            f = self._follower
            pred = f.predict(t) if f is not None else None
            if (
                f is not None
                and not f.confirmed
                and (f.tiny or not f.round)
                and self._candidates(self._whole(frame, self.spec), t)
            ):  # a tentative lock on a ragged or tiny blob gives way to a ball-shaped blob anywhere
                f = pred = None
            if f is not None and pred is not None and math.isfinite(pred.gate_px):
                blob, settled = f.search_window(frame, pred)
                if not settled:
                    self.full_frame_searches += 1
                    blob = f.choose(self._whole(frame, self.spec, min_radius_px=f.min_radius()), pred)
                if blob is not None and not self._within_string(f, blob, pivot_uv):
                    blob = None
                if blob is None and not f.confirmed and not f.named and f.round:
                    # a tentative lock that lost its blob is not coasted on: it may have been a codec's speck whose
                    # learned area would reject the ball wherever the growing gate meets it — search afresh
                    blob = self._acquire(frame, t, pivot_uv, index)
                elif blob is not None:
                    regained = self._regained_far(f, blob, t, pred, index)
                    f.accept(blob, t, pred)
                    if regained:  # a codec's ghost of the ball's past place can lie where a runaway prediction points
                        f.restart(blob, t)
                    blob = self._judge(f, blob, t, pivot_uv, index)
                if self._follower is f and blob is not None:
                    blob = self._watch_rest(frame, f, blob, t, pivot_uv, index)
            else:
                blob = self._acquire(frame, t, pivot_uv, index)
        self._learn(frame, t, blob, pivot_uv)
        return blob

    def could_be_ball(self, blob: Blob, pivot_uv: tuple[float, float] | None) -> bool:
        """Not on an object found not to be the ball, nor on a place static in its colour, nor beyond the string's
        reach from the pivot (when known): what the second look asks of a fix (no state changes)."""
        if not self._candidates([blob], 0.0):
            return False
        return self._in_reach(blob, pivot_uv)

    def _in_reach(self, blob: Blob, pivot_uv) -> bool:
        """Within (1 + string_tolerance) × the learned string length of the pivot (True while either is unknown)."""
        L = self.string_px
        if L is None or pivot_uv is None:
            return True
        return (
            math.hypot(blob.u - pivot_uv[0], blob.v - pivot_uv[1])
            <= (1.0 + self.options.string_tolerance) * L + 2.0 * blob.radius_px
        )

    # ------------------------------------------------------------------ internals

    def _size_gates(self, frame: np.ndarray) -> None:
        """Once the frame size is known: let the largest ball be max_radius_share of the frame height."""
        self._sized = True
        share = self.options.max_radius_share
        if share is None:
            return
        largest = math.pi * (share * frame.shape[0]) ** 2
        if largest > self.options.gates.max_area_px:
            self.options = replace(self.options, gates=replace(self.options.gates, max_area_px=largest))

    def _learn(self, frame: np.ndarray, t: float, blob: Blob | None, pivot_uv) -> None:
        """The static map (the confident ball left out) and the string length."""
        ok = blob is not None and self.confidence >= self.options.min_confidence
        keep = [(blob.u, blob.v, 1.5 * blob.radius_px + 2.0)] if ok else []
        if self._follower is not None and self._follower.confirmed and not ok:  # a confirmed ball briefly missed
            last = self._follower.fixes[-1]
            keep.append((last.u, last.v, 2.0 * self._follower.radius() + 4.0))
        self._static.update(frame, t, keep)
        if ok and pivot_uv is not None and self._hyp is None:
            self._string.append(math.hypot(blob.u - pivot_uv[0], blob.v - pivot_uv[1]))
            self._string_added += 1

    def _within_string(self, f: _Follower, blob: Blob, pivot_uv) -> bool:
        """False for a fix farther from the pivot than the string reaches; after 3 in a row the lock is dropped."""
        if self._in_reach(blob, pivot_uv):
            f.string_misses = 0
            return True
        self.rejected_string += 1
        f.string_misses += 1
        if f.string_misses >= 3:
            self._follower = None
        return False

    def _regained_far(self, f: _Follower, blob: Blob, t: float, pred: Prediction, index: int) -> bool:
        """A confirmed lock (not named by the user) that missed ``regain_missed_frames`` or more frames and finds a blob
        off its prediction by more than ``regain_radii`` radii (at least 3 px each) plus a quarter of the gate's
        growth for acceleration: the blob must earn the confirmation again."""
        o = self.options
        if not f.confirmed or f.named:
            return False
        if f.recent and index - f.recent[-1][3] - 1 < o.regain_missed_frames:
            return False
        age = t - f.fixes[-1].t
        reach = o.regain_radii * max(f.radius(), 3.0) + 0.125 * o.max_acceleration_px_s2 * age * age
        return math.hypot(blob.u - pred.u, blob.v - pred.v) > reach

    def _judge(self, f: _Follower, blob: Blob, t: float, pivot_uv, index: int) -> Blob:
        """Set the confidence of a fix on the lock; confirm a tentative lock (revising its frames)."""
        o = self.options
        f.note(t, blob.u, blob.v, index, max(o.static_lock_s, o.recheck_s) + 0.1)
        conf = 1.0
        if not f.confirmed and len(f.recent) >= 2:  # a tentative lock that jumped (after a gap) starts afresh there
            p = [(u, v) for _, u, v, _ in list(f.recent)[-3:]]
            step = math.hypot(p[-2][0] - p[-3][0], p[-2][1] - p[-3][1]) if len(p) == 3 else 0.0
            if math.hypot(p[-1][0] - p[-2][0], p[-1][1] - p[-2][1]) > 4.0 * f.radius() + 2.0 * step:
                f.pending, f.hits, f.origin, f.origin_t = [], 1, (blob.u, blob.v), t
                f.recent = deque([f.recent[-1]])
        if not f.confirmed:
            moved = f.moving(max(3.0, o.confirm_move_radii * f.radius()))
            at_rest_ok = (
                f.round and (pivot_uv is None or self._plumb(blob, pivot_uv)) and t - f.origin_t >= o.rest_confirm_s
            )
            if f.hits >= o.confirm_frames and (moved or at_rest_ok):
                f.confirmed = True
                self._revision.extend((k, b, CONFIRMED) for k, b in f.pending)
                f.pending = []
            else:
                f.pending.append((index, blob))
                conf = TENTATIVE
        if self._static.static_share(blob.u, blob.v, blob.radius_px) >= 0.5:
            conf *= _ON_STATIC
        g = o.gates
        if not f.tiny and (blob.ellipse_fit < g.min_ellipse_fit - 0.05 or blob.circularity < g.min_circularity - 0.1):
            pred_step = (
                math.hypot(f.fixes[-1].u - f.fixes[0].u, f.fixes[-1].v - f.fixes[0].v) if len(f.fixes) == 2 else 0.0
            )
            if pred_step < 2.0 * f.radius():  # not a motion-blurred streak: just a ragged blob
                conf *= _WEAK_SHAPE
        self.confidence = conf
        return blob

    def _plumb(self, blob: Blob, pivot_uv) -> bool:
        du, dv = blob.u - pivot_uv[0], blob.v - pivot_uv[1]
        return dv > 0 and abs(math.degrees(math.atan2(du, dv))) <= self.options.plumb_deg

    def _watch_rest(self, frame: np.ndarray, f: _Follower, blob: Blob, t: float, pivot_uv, index: int) -> Blob | None:
        """A lock that sits still may be a static object of the ball's colour rather than the ball (at rest, or
        held): every recheck_s look for other candidates; if there are any, follow them all and keep the one that
        moves like a pendulum — and if that is another, the still frames of this lock are withdrawn and the
        object excluded."""
        o = self.options
        every = o.recheck_s if f.confirmed else min(o.recheck_s, 0.1)  # a tentative lock at rest is doubted more often
        if f.named or t - f.last_recheck < every or not f.at_rest(o.static_lock_s):
            return blob
        f.last_recheck = t
        r = f.radius()
        away = (blob.u, blob.v, 2.0 * r + 2.0)
        if f.confirmed:
            others = [
                b
                for b in self._candidates(self._whole(frame, self.spec), t)
                if math.hypot(b.u - blob.u, b.v - blob.v) > away[2]
            ]
        else:  # a tentative lock: whatever could be the ball instead
            others = self._find_candidates(frame, t, away)[0]
        if others:
            others = others[: o.max_candidates - 1]  # (followers and their blobs alike: one list per follower)
            self._start_hypotheses(
                [f] + [_Follower(self.spec, o, b, t) for b in others],
                [blob] + others,
                t,
                index,
                pivot_uv,
            )
            self._hyp.incumbent_frames = [k for _, _, _, k in f.recent if k != index]
            self.confidence = TENTATIVE
        return blob

    def _whole(
        self, frame: np.ndarray, spec: ColorSpec, gates: BlobGates | None = None, min_radius_px: float | None = None
    ) -> list[Blob]:
        """Blobs passing the strict gates on the whole frame (a coarse pass first on large frames — shrunk more when
        the ball sought is known to be large, min_radius_px [px] — its shrunk image kept for further colour
        thresholds on the same frame)."""
        factor = coarse_factor(frame.shape[1], min_radius_px)
        if factor > 1 and (self._coarse is None or self._coarse[0] is not frame or self._coarse[1] != factor):
            self._coarse = (frame, factor, coarse_hsv(frame, factor))
        small = self._coarse[2] if factor > 1 else None
        refine = detail_scale(min_radius_px)
        return find_blobs_coarse(frame, spec, gates or self.options.gates, factor, small_hsv=small, refine=refine)

    def _current(self) -> _Follower | None:
        if self._hyp is not None:
            return self._hyp.followers[self._hyp.leader]
        return self._follower

    def _candidates(self, blobs: list[Blob], t: float) -> list[Blob]:
        """Blobs that may be the ball: not an object found not to be, not on a static place, not elongated."""
        out = []
        for b in blobs:
            if any(math.hypot(b.u - u, b.v - v) <= r for u, v, r in self._excluded):
                continue
            if self._static.static_share(b.u, b.v, b.radius_px) >= 0.5 or b.aspect > self.options.max_aspect:
                continue
            out.append(b)
        return out

    def _find_candidates(
        self, frame: np.ndarray, t: float, away: tuple[float, float, float] | None = None
    ) -> tuple[list[Blob], bool]:
        """(candidates on the whole frame, found by the strict gates): the strict gates first, else blobs only
        roughly round (a ball turned into blocks by a low-bitrate codec) and after them balls a few pixels across;
        the roundest first (blobs too small for their shape to tell after the others), tiny ones by saturation.
        away: (u, v, distance) [px] — only candidates farther than that from (u, v) count."""
        o = self.options
        if too_dark(frame, self._min_value):  # no pixel bright enough for the colour: nothing of it anywhere
            return [], o.start_uv is not None

        def keep(blobs: list[Blob]) -> list[Blob]:
            blobs = self._candidates(blobs, t)
            if away is None:
                return blobs
            return [b for b in blobs if math.hypot(b.u - away[0], b.v - away[1]) > away[2]]

        def roundest(blobs: list[Blob]) -> list[Blob]:  # blobs too small for a shape to tell last (a codec's fragments)
            return sorted(blobs, key=lambda b: (b.area_px < SHAPE_MIN_AREA_PX, -b.ellipse_fit))

        blobs = roundest(keep(self._whole(frame, self.spec)))
        if not blobs and o.acquire_min_saturation > min(b.lower[1] for b in self.spec.bands):
            # a ball touching a paler object of its hue (a hand) merges with it; its saturated core does not
            blobs = roundest(keep(self._whole(frame, self._acquire_spec)))
        if blobs or o.start_uv is not None:
            return blobs, True
        loose = replace(
            o.gates,
            min_circularity=min(o.gates.min_circularity, o.loose_circularity),
            min_ellipse_fit=min(o.gates.min_ellipse_fit, o.loose_ellipse_fit),
        )
        blobs = roundest(keep(self._whole(frame, self.spec, loose)))
        if o.tiny_search and o.gates.min_area_px <= TINY_MAX_AREA_PX:  # and, side by side, balls a few pixels across
            tiny = [
                b
                for b in keep(find_tiny(frame, self.spec))
                if all(math.hypot(b.u - c.u, b.v - c.v) > c.radius_px + 2.0 for c in blobs)
            ]
            blobs += sorted(tiny, key=lambda b: -b.saturation)
        return blobs, False

    def _acquire(self, frame: np.ndarray, t: float, pivot_uv, index: int) -> Blob | None:
        """Free search of the whole frame; forgets what was learned about the ball. The strict gates first, then
        (tentatively) blobs only roughly round, then balls a few pixels across."""
        o = self.options
        self.full_frame_searches += 1
        self._follower = None
        blobs, strict = self._find_candidates(frame, t)
        if o.start_uv is not None and not self._started:
            su, sv = o.start_uv
            near = [b for b in blobs if math.hypot(b.u - su, b.v - sv) <= o.start_radius_px]
            if not near:
                return None
            blob = min(near, key=lambda b: math.hypot(b.u - su, b.v - sv))
            self._started = True
            self._follower = _Follower(self.spec, o, blob, t)
            self._follower.confirmed = self._follower.named = True  # named by the user: not second-guessed
            self.confidence = CONFIRMED
            return blob
        if not blobs:
            return None
        self._started = True
        if len(blobs) == 1:
            f = _Follower(self.spec, o, blobs[0], t)
            f.round = strict
            self._follower = f
            return self._judge(f, blobs[0], t, pivot_uv, index)
        cands = blobs[: o.max_candidates]  # in the order found: strict, loose, tiny; the roundest first
        self._start_hypotheses([_Follower(self.spec, o, b, t) for b in cands], cands, t, index, pivot_uv)
        self.confidence = TENTATIVE
        return cands[0]

    def _start_hypotheses(self, followers: list[_Follower], blobs: list[Blob], t: float, index: int, pivot_uv) -> None:
        if len(followers) != len(blobs):
            raise ValueError(f"{len(followers)} followers for {len(blobs)} candidates")
        self._follower = None
        self._hyp = _Hypotheses(
            followers=followers,
            t0=t,
            first=index,
            centres=[[(b.u, b.v)] for b in blobs],
            blobs=[[b] for b in blobs],
            pivots=[pivot_uv if pivot_uv is not None else (math.nan, math.nan)],
            times=[t],
            leader=0,
            shown=[blobs[0]],
            starts=[(b.u, b.v) for b in blobs],
        )

    def _update_hypotheses(self, frame: np.ndarray, t: float, pivot_uv, index: int) -> Blob | None:
        hyp = self._hyp
        assert hyp is not None
        for k, f in enumerate(hyp.followers):
            pred = f.predict(t)
            blob = None
            if math.isfinite(pred.gate_px):
                blob, _ = f.search_window(frame, pred)
                if blob is not None:
                    f.accept(blob, t, pred)
            hyp.centres[k].append((blob.u, blob.v) if blob is not None else (math.nan, math.nan))
            hyp.blobs[k].append(blob)
        hyp.pivots.append(pivot_uv if pivot_uv is not None else (math.nan, math.nan))
        hyp.times.append(t)
        self._merge_converged()
        if len(hyp.followers) == 1:
            chosen = self._resolve(final=True)
            return chosen[-1] if chosen else None
        if all(not math.isfinite(f.predict(t).gate_px) for f in hyp.followers):  # all lost: none was the ball
            self._abandon()
            return None
        if t - hyp.t0 >= self.options.resolve_s:
            chosen = self._resolve(final=t - hyp.t0 >= self.options.max_resolve_s)
            if chosen is not None:
                return chosen[-1]
            if self._hyp is None:  # abandoned
                return None
        hyp.shown.append(hyp.blobs[hyp.leader][-1])
        return hyp.shown[-1]

    def _merge_converged(self) -> None:
        """Two candidates followed onto the same blob: drop the one that jumped there (it lost its own)."""
        hyp = self._hyp
        assert hyp is not None

        def jump(k: int) -> float:
            c = hyp.centres[k]
            prev = next((p for p in reversed(c[:-1]) if math.isfinite(p[0])), None)
            return math.hypot(c[-1][0] - prev[0], c[-1][1] - prev[1]) if prev is not None else math.inf

        drop: set[int] = set()
        n = len(hyp.followers)
        for i in range(n):
            for j in range(i + 1, n):
                a, b = hyp.centres[i][-1], hyp.centres[j][-1]
                if i in drop or j in drop or not (math.isfinite(a[0]) and math.isfinite(b[0])):
                    continue
                if math.hypot(a[0] - b[0], a[1] - b[1]) < 1.0:
                    drop.add(i if jump(i) > jump(j) else j)
        if not drop:
            return
        keep = [k for k in range(n) if k not in drop]
        leader = hyp.followers[hyp.leader]
        for name in ("followers", "centres", "blobs"):
            setattr(hyp, name, [getattr(hyp, name)[k] for k in keep])
        hyp.merged = True
        hyp.leader = hyp.followers.index(leader) if leader in hyp.followers else 0

    def _abandon(self) -> None:
        """No candidate lasted: what was returned for them is withdrawn (revised to not found)."""
        hyp = self._hyp
        assert hyp is not None
        self.notes.append(f"t = {hyp.t0:.3f} s: {len(hyp.followers)} ball-like candidates, all lost again; none kept")
        self._revision.extend((hyp.first + j, None, 0.0) for j in range(len(hyp.pivots) - 1))
        self._hyp = None
        self._follower = None

    def _resolve(self, final: bool) -> list[Blob | None] | None:
        hyp = self._hyp
        assert hyp is not None
        times = np.array(hyp.times)
        recent = times >= times[-1] - self.options.resolve_s - 1e-9  # motion judged over the last resolve_s
        centres = [np.array(c, float)[recent] for c in hyp.centres]
        pivots = np.array(hyp.pivots, float)[recent]
        radius = float(median(f.radius() for f in hyp.followers))
        fits = [f.fit for f in hyp.followers]
        sats = [float(np.nanmedian(np.array(f.sats, float))) for f in hyp.followers]
        choice = choose_pendulum(centres, pivots, radius, fits, sats, final=final)
        if choice.index is None:
            return None
        k = choice.index
        reason = choice.reason
        if len(hyp.followers) == 1 and hyp.merged:
            reason = "the others were lost, their followers drifted onto it"
        start = hyp.centres[k][0]
        others = ", ".join(f"({u:.0f}, {v:.0f})" for u, v in hyp.starts if (u, v) != tuple(start))
        self.notes.append(
            f"t = {hyp.t0:.3f} s: {len(hyp.starts)} ball-like candidates; took the one at "
            f"({start[0]:.0f}, {start[1]:.0f}) px, not {others}: {reason}"
        )
        for j, f in enumerate(
            hyp.followers
        ):  # a candidate that lost and never moved is an object to ignore from now on
            c = np.array(hyp.centres[j], float)
            c = c[np.all(np.isfinite(c), axis=1)]
            if (
                j != k
                and len(c)
                and float(np.max(np.linalg.norm(c - np.median(c, axis=0), axis=1))) <= max(1.5, 0.3 * f.radius())
            ):
                u, v = np.median(c, axis=0)
                self._excluded.append((float(u), float(v), 1.5 * f.radius() + 3.0))
        if k != 0 and hyp.incumbent_frames:  # the lock sat on an object, not the ball
            self._revision.extend((j, None, 0.0) for j in hyp.incumbent_frames)
        blobs = hyp.blobs[k]
        f = hyp.followers[k]
        # every frame meanwhile was tentative: the chosen candidate's fixes become confident — unless it never moved
        # and hangs off the pivot's vertical (a held ball, or an object): then they stay tentative until it moves
        c = np.array(hyp.centres[k], float)
        c = c[np.all(np.isfinite(c), axis=1)]
        still = len(c) == 0 or float(np.max(np.linalg.norm(c - np.median(c, axis=0), axis=1))) <= max(3.0, f.radius())
        piv = np.array(hyp.pivots, float)
        piv = piv[np.all(np.isfinite(piv), axis=1)]
        last = blobs[-1] if blobs[-1] is not None else next((b for b in reversed(blobs) if b is not None), None)
        hangs = last is not None and len(piv) > 0 and self._plumb(last, tuple(piv[-1]))
        # confirmed when it moved like a pendulum, or hangs still below the pivot; else (a held ball, an object) it
        # stays tentative until it moves
        # hanging still counts once followed for rest_confirm_s (an encoder's ghost of a ball that left stays a few frames)
        young = still and hangs and hyp.times[-1] - hyp.t0 < self.options.rest_confirm_s
        doubtful = not choice.moving and not (still and hangs and not young) and not (still and len(piv) == 0 and final)
        if (
            doubtful and final and len(piv) > 0 and not young
        ):  # nothing moved and nothing hangs below the pivot: none of them is the ball
            self._abandon()
            return None
        f.confirmed = not doubtful
        if not doubtful and f.pending:  # the incumbent lock's tentative frames from before are settled too
            self._revision.extend((j, b, CONFIRMED) for j, b in f.pending)
        # what it followed before its last jump (an encoder's ghost left where the ball was) is not settled with it
        s = _last_jump(hyp.centres[k], f.radius())
        f.pending = (
            f.pending + [(hyp.first + j, b) for j, b in enumerate(blobs[:-1]) if b is not None and j >= s]
            if doubtful
            else []
        )
        level = TENTATIVE if doubtful else CONFIRMED
        self._revision.extend(
            (hyp.first + j, b, (level if j >= s else TENTATIVE) if b is not None else 0.0)
            for j, b in enumerate(blobs[:-1])
        )
        self._follower = f
        self._hyp = None
        return blobs
