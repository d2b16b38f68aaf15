"""A second look, for video files only: the frames before a confirmed stretch of the track, where the ball was not
found, searched again going back in time from the confirmed ball.

The first pass cannot take a ball it has not confirmed: at the start of a low-bitrate video the ball hangs still and
blocky, passes no shape check, and nothing moves that a motion check could confirm. Once the track is confirmed, its
ball — area, saturation, position and velocity — is followed backwards frame by frame with the same window search
and gates as forwards (a blob inside the gate around the backward prediction, of the ball's area and saturation),
never on a place found static in the ball's colour, an object excluded, or beyond the string's reach. The chain
stops after ``max_coast_s`` without a fix. The live sensor never does this (a live result is final).

The ball's area on the track is the median over its fixes — in a fast video mostly motion-blurred streaks, larger
than the ball. A ball the chain finds nearly still (a string re-tensioning stops it within a frame) has the area of
the sharp ball instead (:func:`sharp_area`): such a fix is held in reserve and reported only where no later stage
(the model look) placed the ball.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Iterable

import numpy as np

from .detect import Blob
from .subpixel import refine_centre
from .tracker import CONFIRMED, BallTracker, Prediction, follower_from

SECOND_LOOK = 0.75  # confidence of a frame recovered by the second look
GATE_RADII = 1.5  # a fix lies within this many ball radii of the backward prediction (constant velocity) ...
GATE_MIN_PX = 6.0  # [px] ... or this (a pendulum departs from a straight line by ½·a·Δt², a few pixels per frame)
MAX_MISSES = 2  # the chain ends after this many frames in a row without a fix (a ghost of the ball lingers there)
SATURATION_SHARE = 0.85  # a fix reported by the second look is this saturated relative to the ball's last fixes,
AREA_RANGE = (0.75, 1.5)  # ... has this share of the confirmed ball's area ...
MAX_ASPECT = 1.4  # ... and is this round (length / width) — or hangs still:
STILL_PX = 1.0  # [px] moved at most this from the frame after it, ...
PLUMB_DEG = 2.0  # ... within this of the vertical below the pivot (a turning point of a swing is farther off)
MEMORY_BUDGET_BYTES = 256 * 2**20  # frames kept in memory for one second look at most


@dataclass(frozen=True)
class Gap:
    """Frames ``first`` … ``anchor - 1`` not found, right before the confirmed stretch starting at ``anchor``."""

    first: int
    anchor: int


def gaps(found: np.ndarray, confidence: np.ndarray, sure: float, min_run: int = 3) -> list[Gap]:
    """The runs of frames not found that end right before ``min_run`` confident fixes in a row."""
    n = len(found)
    ok = found & (confidence >= sure)
    out: list[Gap] = []
    k = 0
    while k < n:
        if found[k]:
            k += 1
            continue
        j = k
        while j < n and not found[j]:
            j += 1
        if j + min_run <= n and bool(np.all(ok[j : j + min_run])):
            out.append(Gap(k, j))
        k = j
    return out


def frames_needed(found_gaps: list[Gap], frame_bytes: int) -> dict[int, list[int]]:
    """Per gap's anchor, the frames to look at again (the nearest to the anchor first) within the memory budget."""
    budget = max(1, MEMORY_BUDGET_BYTES // max(frame_bytes, 1))
    out: dict[int, list[int]] = {}
    for g in sorted(found_gaps, key=lambda g: g.anchor - g.first):
        take = min(g.anchor - g.first, budget)
        if take <= 0:
            break
        out[g.anchor] = list(range(g.anchor - 1, g.anchor - 1 - take, -1))
        budget -= take
    return out


def look_back(
    tracker: BallTracker,
    anchor_blobs: list[tuple[float, Blob]],
    frames: Iterable[tuple[int, float, np.ndarray, tuple[float, float] | None]],
    area_px: float,
    sharp_px: float | None = None,
    reserve: list[tuple[int, Blob]] | None = None,
) -> list[tuple[int, Blob]]:
    """Follow the confirmed ball backwards. anchor_blobs: (time [s], blob) of the confirmed stretch, first the
    anchor; frames: (index, time [s], BGR frame, pivot [px] or None) going back from the anchor; area_px: the ball's
    area [px²] on the confirmed track (a fix reported must have AREA_RANGE of it). Returns the
    (index, blob) recovered, until the chain is lost for ``max_coast_s``. With ``sharp_px`` [px²] (:func:`sharp_area`)
    the fixes that fail only on area but moved less than the sharp ball's radius from the next one and have
    AREA_RANGE of ``sharp_px`` are appended to ``reserve``."""
    f = follower_from(tracker, [(-t, b) for t, b in reversed(anchor_blobs)])
    out: list[tuple[int, Blob]] = []
    misses = 0
    for k, t, frame, pivot in frames:
        pred = f.predict(-t)
        if not math.isfinite(pred.gate_px) or misses > MAX_MISSES:
            break
        gate = min(pred.gate_px, max(GATE_RADII * f.radius(), GATE_MIN_PX))
        blob = _search(tracker, f, frame, replace(pred, gate_px=gate), pivot)
        if blob is None:  # or at rest there (a ball released, going back in time: held still before)
            last = f.fixes[-1]
            blob = _search(tracker, f, frame, Prediction(last.u, last.v, 0.0, gate), pivot)
        if blob is None:
            misses += 1
            continue
        misses = 0
        last = f.fixes[-1]
        still = math.hypot(blob.u - last.u, blob.v - last.v) <= STILL_PX
        peak = f.learned_saturation()
        vivid = peak is None or not math.isfinite(blob.saturation) or blob.saturation >= SATURATION_SHARE * peak
        f.accept(blob, -t, pred)  # followed on, but reported only when as saturated as the ball has been and round
        # and of its area (a ball the codec updated only in part, smeared, or merged with its ghost, is centred off),
        # or hanging still below the pivot
        round_ = blob.aspect <= MAX_ASPECT
        whole = round_ and AREA_RANGE[0] * area_px <= blob.area_px <= AREA_RANGE[1] * area_px
        if (vivid and whole) or (still and _hangs(blob, pivot)):
            out.append((k, blob))
        elif vivid and round_ and reserve is not None and sharp_px is not None and _sharp(blob, last, sharp_px):
            reserve.append((k, blob))
    return out


def _sharp(blob: Blob, last, sharp_px: float) -> bool:
    """``blob`` moved less than the sharp ball's radius from ``last`` (the chain's next fix) and has AREA_RANGE of
    ``sharp_px`` [px²]: the ball without motion blur."""
    slow = math.hypot(blob.u - last.u, blob.v - last.v) <= math.sqrt(sharp_px / math.pi)
    return slow and AREA_RANGE[0] * sharp_px <= blob.area_px <= AREA_RANGE[1] * sharp_px


def sharp_area(blobs: list[Blob | None], confidence: np.ndarray) -> float | None:
    """The ball's area without motion blur [px²]: the median over the confirmed fixes that moved less than half their
    own radius since the confirmed fix before them (None when there are none)."""
    areas, prev = [], None
    for b, c in zip(blobs, confidence):
        ok = b is not None and c >= CONFIRMED
        if ok and prev is not None and math.hypot(b.u - prev.u, b.v - prev.v) < 0.5 * b.radius_px:  # type: ignore[union-attr]
            areas.append(b.area_px)  # type: ignore[union-attr]
        prev = b if ok else None
    return float(np.median(areas)) if areas else None


def _search(tracker: BallTracker, f, frame: np.ndarray, pred: Prediction, pivot) -> Blob | None:
    """The blob the follower finds in the window around pred, if the tracker lets it be the ball."""
    blob, settled = f.search_window(frame, pred)
    return blob if blob is not None and settled and tracker.could_be_ball(blob, pivot) else None


def recover(
    tracker: BallTracker,
    path: str,
    fps: float | None,
    blobs: list[Blob | None],
    times: list[float],
    pivots: list[tuple[float, float]],
    confidence: list[float],
    kept: dict[int, np.ndarray] | None = None,
    frame_bytes: int = 0,
) -> tuple[list[tuple[int, Blob, tuple[float, float]]], list[tuple[int, Blob, tuple[float, float]]]]:
    """The second look over a tracked video (``path``, ``fps`` as first; the frames ``kept`` since the first pass
    used, the rest decoded again): the (frame index, blob) recovered before each confirmed stretch that follows frames
    not found. blobs, times [s], pivots [px] (NaN when unknown) and confidence are the first pass's, per frame;
    frame_bytes the size of a frame. Each blob comes with its refined centre [px]
    (:func:`tracking.subpixel.refine_centre`). Returns those and the sharp fixes held in reserve (:func:`look_back`)."""
    from .video import frames_at

    sure = tracker.options.min_confidence
    conf = np.array(confidence, float)
    found = np.array([b is not None for b in blobs], bool) & (conf >= sure)
    todo = gaps(found, conf, sure)
    if not todo:
        return [], []
    needed = frames_needed(todo, frame_bytes)
    frames = frames_at(path, fps, (j for ks in needed.values() for j in ks), kept)
    area = float(np.median([b.area_px for b, c in zip(blobs, conf) if b is not None and c >= CONFIRMED]))
    sharp = sharp_area(blobs, conf)
    out: list[tuple[int, Blob, tuple[float, float]]] = []
    held: list[tuple[int, Blob]] = []
    for anchor, ks in needed.items():
        stretch = [(times[anchor + i], blobs[anchor + i]) for i in range(3)]
        back = ((k, times[k], frames[k], _pivot(pivots[k])) for k in ks if k in frames)
        got = look_back(tracker, stretch, back, area, sharp, held)
        out += [(k, b, refine_centre(frames[k], tracker.spec, b)) for k, b in got]
    return out, [(k, b, refine_centre(frames[k], tracker.spec, b)) for k, b in held]


def _hangs(blob: Blob, pivot: tuple[float, float] | None) -> bool:
    """The blob lies below the pivot within PLUMB_DEG of the vertical (False when the pivot is unknown)."""
    if pivot is None:
        return False
    du, dv = blob.u - pivot[0], blob.v - pivot[1]
    return dv > 0 and abs(math.degrees(math.atan2(du, dv))) <= PLUMB_DEG


def _pivot(p: tuple[float, float]) -> tuple[float, float] | None:
    return p if math.isfinite(p[0]) and math.isfinite(p[1]) else None
