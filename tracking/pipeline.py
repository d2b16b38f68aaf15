"""A whole video → per-frame ball centre, found flag, decoder time, and θ when the pivot is known.

The pivot is a fixed pixel or a second coloured marker tracked like the ball. With a camera calibration
the ball and pivot are undistorted before θ is taken; with a plane calibration θ is measured in the plane of
motion from metric coordinates (a camera that sees the plane obliquely does not distort it), and the track
gets plane metres. Frames revised by the tracker after it chose among several ball-like candidates are
rewritten (the on_frame preview shows what was known at the time).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable

import numpy as np

from trajectories.errors import InputError

from .angle import plane_axes, plane_string_angle, string_angle
from .calibration import CameraCalibration, to_plane, undistort_points
from .color import ColorSpec
from .detect import Blob
from .subpixel import refine_centre
from .second_look import SECOND_LOOK, recover
from .model_look import MODEL_LOOK
from .model_look import recover as model_recover
from .patches import Patch, patch_around
from .pendulum_check import check as pendulum_check
from .smoothing import on_circle, outliers, smooth_centres
from .tracker import BallTracker, TrackerOptions
from .video import FrameBuffers, VideoInfo, iter_frames, opencv_threads, prefetched, probe_video


@dataclass(frozen=True)
class FrameResult:
    """One frame's outcome: index, time [s], ball blob (None when lost), pivot [px] (None if unknown), θ [rad]."""

    index: int
    t: float
    ball: Blob | None
    pivot_uv: tuple[float, float] | None
    theta: float  # NaN when the ball or the pivot is missing


@dataclass(frozen=True)
class Track:
    """Per-frame track of a video. Lost frames have found = False and NaN positions and angles."""

    t: np.ndarray  # (n,) decoder timestamps from the first frame [s]
    frame: np.ndarray  # (n,) frame index
    uv: np.ndarray  # (n, 2) ball centre in the raw image [px]
    found: np.ndarray  # (n,) bool
    theta: np.ndarray | None  # (n,) [rad] when a pivot is known (undistorted coordinates with a calibration)
    pivot_uv: np.ndarray | None  # (n, 2) tracked pivot marker [px]; None with a fixed or no pivot
    xy_m: np.ndarray | None  # (n, 2) ball in the calibrated plane [m]
    radius_px: np.ndarray  # (n,) radius of the disc with the blob's area [px]
    info: VideoInfo
    full_frame_searches: int  # frames where the search window failed and the whole frame was searched
    notes: tuple[str, ...] = ()  # ambiguities met (several ball-like candidates) and how they were resolved
    theta_in_plane: bool = False  # θ measured in the calibrated plane of motion (else in the image)
    confidence: np.ndarray | None = None  # (n,) 0–1 of the frame's fix (0 when nothing was seen)
    unsure: np.ndarray | None = None  # (n,) bool: a candidate was seen but not trusted (reported not found)
    extra: tuple[
        tuple[str, np.ndarray], ...
    ] = ()  # more (name, (n,) values) columns, written last (live: tilt, latency)
    second_look_frames: int = 0  # frames found by the second look (tracking.second_look)
    model_look_frames: int = 0  # frames reported at a fitted pendulum's place (tracking.model_look)
    outlier_frames: int = 0  # fixes off their neighbours' motion, reported unsure (tracking.smoothing.outliers)
    smoothed_frames: int = 0  # frames whose centre was smoothed around the fixed pivot (tracking.smoothing)
    off_pendulum_frames: int = 0  # fixes off the pendulum fitted over their window, reported unsure
    on_pendulum_frames: int = (
        0  # noisy fixes moved onto the pendulum fitted over their window (tracking.pendulum_check)
    )

    @property
    def found_fraction(self) -> float:
        return float(self.found.mean()) if len(self.found) else 0.0


class ImageAngles:
    """θ [rad] from raw ball and pivot pixels: in the image (undistorted when calibrated) or in the plane."""

    def __init__(self, calibration: CameraCalibration | None, size: tuple[int, int]) -> None:
        self.cal = calibration
        self.axes = None
        if calibration is not None and calibration.plane is not None:
            centre = np.array([size[0] / 2.0, size[1] / 2.0])
            self.axes = plane_axes(calibration.plane.homography, undistort_points(calibration, centre))

    def __call__(self, ball_uv: np.ndarray, pivot_uv: np.ndarray) -> np.ndarray:
        b, p = np.asarray(ball_uv, float), np.asarray(pivot_uv, float)
        if self.cal is None:
            return string_angle(b, p)
        if self.axes is not None:
            xb = to_plane(self.cal, b).reshape(b.shape)
            xp = to_plane(self.cal, p).reshape(p.shape)
            return plane_string_angle(xb, xp, *self.axes)
        return string_angle(undistort_points(self.cal, b), undistort_points(self.cal, p))


def _check_inputs(
    path: str | Path,
    pivot_uv: tuple[float, float] | None,
    pivot_color: ColorSpec | None,
    calibration: CameraCalibration | None,
) -> VideoInfo:
    """The video's info; ValueError for both a fixed pivot and a pivot colour, InputError for an unreadable video or a
    calibration made for another image size."""
    if pivot_uv is not None and pivot_color is not None:
        raise ValueError("give a fixed pivot or a pivot colour, not both")
    info = probe_video(path)
    if calibration is not None and tuple(calibration.image_size) != info.size:
        raise InputError(
            f"calibration is for {calibration.image_size[0]}x{calibration.image_size[1]} images, "
            f"the video is {info.width}x{info.height}",
            file=str(path),
        )
    return info


_NAN2 = (math.nan, math.nan)
KEEP_BYTES = 256 * 2**20  # frames where the ball was not surely found are kept for the looks after, up to this
PATCH_BYTES = 64 * 2**20  # ... and patches around the other fixes (tracking.patches), up to this
OUTLIER = 0.3  # confidence of a fix found to lie off the motion of its neighbours (reported unsure)


class _Columns:
    """The per-frame results gathered while tracking — time, ball centre, radius and confidence, pivot — with the
    frames the trackers revise rewritten in place (the on_frame preview shows what was known at the time). A blob's
    centre is its refined one (:func:`tracking.subpixel.refine_centre`) when it was refined on its frame."""

    def __init__(self) -> None:
        self.t: list[float] = []
        self.uv: list[tuple[float, float]] = []
        self.radius: list[float] = []
        self.conf: list[float] = []
        self.piv: list[tuple[float, float]] = []
        self.blobs: list[Blob | None] = []
        self.refined: dict[int, tuple[Blob, tuple[float, float]]] = {}  # frame → (blob, its refined centre [px])
        self.refined_pivot: dict[int, tuple[Blob, tuple[float, float]]] = {}

    def add(self, t: float, ball: Blob | None, confidence: float) -> None:
        self.t.append(t)
        for column, empty in ((self.blobs, None), (self.uv, _NAN2), (self.radius, math.nan), (self.conf, 0.0)):
            column.append(empty)
        self.set_ball(len(self.t) - 1, ball, confidence)

    def revise_ball(self, tracker: BallTracker) -> None:
        for k, blob, c in tracker.pop_revision():
            self.set_ball(k, blob, c)

    def set_ball(self, k: int, blob: Blob | None, c: float) -> None:
        """Frame k's ball: its blob (None when not found) with confidence c."""
        self.blobs[k] = blob
        self.uv[k] = _centre(self.refined, k, blob)
        self.radius[k] = blob.radius_px if blob is not None else math.nan
        self.conf[k] = c if blob is not None else 0.0

    def revise_pivot(self, tracker: BallTracker) -> None:
        for k, blob, _ in tracker.pop_revision():
            self.piv[k] = _centre(self.refined_pivot, k, blob)


def _centre(refined: dict[int, tuple[Blob, tuple[float, float]]], k: int, blob: Blob | None) -> tuple[float, float]:
    """Frame k's centre [px] of the blob: refined when this blob was refined on that frame (NaN for no blob)."""
    if blob is None:
        return _NAN2
    got = refined.get(k)
    return got[1] if got is not None and got[0] is blob else (blob.u, blob.v)


class _Trackers:
    """The ball's tracker and the pivot's (a tracked marker, or a fixed pixel, or none), run frame by frame."""

    def __init__(
        self,
        ball: ColorSpec,
        options: TrackerOptions | None,
        pivot_uv: tuple[float, float] | None,
        pivot_color: ColorSpec | None,
        pivot_options: TrackerOptions | None,
    ) -> None:
        self.ball = BallTracker(ball, options)
        pivot_opts = pivot_options or (replace(options, start_uv=None) if options is not None else None)
        self.pivot = BallTracker(pivot_color, pivot_opts) if pivot_color is not None else None
        self.fixed = None if pivot_uv is None else (float(pivot_uv[0]), float(pivot_uv[1]))
        self.sure = self.ball.options.min_confidence
        self.columns = _Columns()
        self.recovered = 0  # frames found by the second look
        self.reserve: list[tuple[int, Blob, tuple[float, float]]] = []  # its sharp fixes, for frames left unfound
        self.modelled = 0  # frames reported by the model look
        self.outliers = 0  # fixes their neighbours placed elsewhere (reported unsure)
        self.off_pendulum = 0  # fixes off the pendulum over their window (reported unsure)
        self.on_pendulum: np.ndarray | None = None  # (n, 2) [px] the fixes' places on that pendulum (NaN: kept)
        self.kept: dict[int, np.ndarray] = {}  # frames where the ball was not (surely) found, for the looks after
        self.patches: dict[int, Patch] = {}  # ... and patches of the others around the fix (tracking.patches)
        self.kept_bytes = 0
        self.patch_bytes = 0
        self.frame_bytes = 0

    def step(self, frame: np.ndarray, t: float) -> tuple[Blob | None, tuple[float, float] | None]:
        """Track one frame: (the ball's blob or None, the pivot [px] or None)."""
        cols = self.columns
        k = len(cols.t)
        p: tuple[float, float] | None = self.fixed
        if self.pivot is not None:
            pb = self.pivot.update(frame, t)
            cols.revise_pivot(self.pivot)
            if pb is not None:
                cols.refined_pivot[k] = (pb, refine_centre(frame, self.pivot.spec, pb))
            p = _centre(cols.refined_pivot, k, pb) if pb is not None and self.pivot.confidence >= self.sure else None
        cols.piv.append(p if p is not None else _NAN2)
        b = self.ball.update(frame, t, p)
        if b is not None:
            cols.refined[k] = (b, refine_centre(frame, self.ball.spec, b))
        cols.revise_ball(self.ball)
        cols.add(t, b, self.ball.confidence)
        if (b is None or self.ball.confidence < self.sure) and self.kept_bytes + frame.nbytes <= KEEP_BYTES:
            self.kept[k] = frame  # (its buffer is not decoded into again: kept without a copy)
            self.kept_bytes += frame.nbytes
        elif b is not None and self.fixed is not None:  # (the model look's, which needs a fixed pivot)
            patch = patch_around(frame, *cols.uv[k], b.radius_px)
            if patch is not None and self.patch_bytes + patch.pixels.nbytes <= PATCH_BYTES:
                self.patches[k] = patch
                self.patch_bytes += patch.pixels.nbytes
        self.frame_bytes = frame.nbytes
        return b, p

    def finish(self) -> None:
        """End of the video: the trackers settle what they were still judging."""
        self.ball.finish()
        self.columns.revise_ball(self.ball)
        if self.pivot is not None:
            self.pivot.finish()
            self.columns.revise_pivot(self.pivot)

    def second_look(self, path: str, fps: float | None) -> None:
        """The ball's frames recovered by a second look (:func:`tracking.second_look.recover`), counted."""
        cols = self.columns
        got, self.reserve = recover(
            self.ball, path, fps, cols.blobs, cols.t, cols.piv, cols.conf, self.kept, self.frame_bytes
        )
        for k, blob, centre in got:
            cols.refined[k] = (blob, centre)
            cols.set_ball(k, blob, SECOND_LOOK)
        self.recovered = len(got)

    def sharp_reserve(self) -> None:
        """The second look's sharp fixes held in reserve, on the frames still without a trusted fix (after the model
        look)."""
        cols = self.columns
        _, trusted = self.trusted()
        for k, blob, centre in self.reserve:
            if not trusted[k]:
                cols.refined[k] = (blob, centre)
                cols.set_ball(k, blob, SECOND_LOOK)
                self.recovered += 1

    def trusted(self) -> tuple[np.ndarray, np.ndarray]:
        """The ball's centres [px] (n, 2) so far and which of them are trusted (confidence ≥ the tracker's minimum)."""
        uv = np.array(self.columns.uv, float).reshape(-1, 2)
        conf = np.array(self.columns.conf, float)
        return uv, np.all(np.isfinite(uv), axis=1) & (conf >= self.sure)

    def reject_outliers(self, fps: float) -> None:
        """With a fixed pivot and the ball on a circle about it (:func:`tracking.smoothing.on_circle`), the fixes their
        neighbours place elsewhere (:func:`tracking.smoothing.outliers`) are marked unsure (confidence OUTLIER)."""
        uv, trusted = self.trusted()
        if self.fixed is None or not on_circle(uv, trusted, self.fixed):
            return
        odd = np.flatnonzero(outliers(uv, trusted, self.fixed, fps))
        for k in odd:
            self.columns.conf[k] = OUTLIER
        self.outliers = len(odd)

    def check_pendulum(self, fps: float) -> None:
        """With a fixed pivot and the ball on a circle about it, the fixes off the pendulum fitted over their window
        marked unsure (confidence OUTLIER), and the places on it kept for the noisy ones
        (:func:`tracking.pendulum_check.check`)."""
        uv, trusted = self.trusted()
        if self.fixed is None or not on_circle(uv, trusted, self.fixed):
            return
        got = pendulum_check(uv, trusted, self.fixed, fps)
        for k in np.flatnonzero(got.off):
            self.columns.conf[k] = OUTLIER
        self.off_pendulum = int(got.off.sum())
        self.on_pendulum = got.uv

    def model_look(self, path: str, fps: float) -> None:
        """With a fixed pivot and the ball on a circle about it, the ball's frames reported by the model look
        (:func:`tracking.model_look.recover`)."""
        cols = self.columns
        uv, trusted = self.trusted()
        if self.fixed is None or not on_circle(uv, trusted, self.fixed):
            return
        radius = float(np.median(np.array(cols.radius, float)[trusted]))
        got = model_recover(self.ball, path, fps, uv, trusted, self.fixed, radius, self.kept, self.patches)
        for k, blob in got:
            cols.set_ball(k, blob, MODEL_LOOK)
        self.modelled = len(got)

    def notes(self) -> tuple[str, ...]:
        return tuple(self.ball.notes) + tuple(f"pivot marker: {n}" for n in (self.pivot.notes if self.pivot else ()))


def _shown(
    trackers: _Trackers, angle: ImageAngles, k: int, t: float, b: Blob | None, p: tuple[float, float] | None
) -> FrameResult:
    """What one frame shows at the time (for on_frame): the ball only when the tracker is sure of it, θ with a pivot."""
    shown = b if b is not None and trackers.ball.confidence >= trackers.sure else None
    th = float(angle(np.array([b.u, b.v]), np.array(p))) if shown is not None and p is not None else math.nan
    return FrameResult(k, t, shown, p, th)


def _make_track(
    trackers: _Trackers,
    angle: ImageAngles,
    calibration: CameraCalibration | None,
    info: VideoInfo,
    smooth_fps: float | None = None,
) -> Track:
    """The track from the gathered columns: unsure fixes (confidence below the tracker's minimum) reported not found;
    with smooth_fps [1/s] and a fixed pivot, the centres smoothed (:func:`tracking.smoothing.smooth_centres`)."""
    cols = trackers.columns
    conf_a = np.array(cols.conf, float)
    seen = np.all(np.isfinite(np.array(cols.uv, float).reshape(-1, 2)), axis=1)
    trusted = seen & (conf_a >= trackers.sure)
    uv = [c if ok else _NAN2 for c, ok in zip(cols.uv, trusted)]
    radius = [r if ok else math.nan for r, ok in zip(cols.radius, trusted)]
    uv_a = np.array(uv, float).reshape(-1, 2)
    smoothed = on_pendulum = 0
    if smooth_fps is not None and trackers.fixed is not None:
        raw, uv_a = uv_a, smooth_centres(uv_a, trusted, trackers.fixed, smooth_fps)
        smoothed = int(np.sum(np.any(np.abs(uv_a - raw) > 0.0, axis=1)))
        if trackers.on_pendulum is not None:
            moved = trusted & np.all(np.isfinite(trackers.on_pendulum), axis=1)
            uv_a[moved] = trackers.on_pendulum[moved]
            on_pendulum = int(moved.sum())
    piv_a = np.array(cols.piv, float).reshape(-1, 2)
    xy = None
    if calibration is not None and calibration.plane is not None:
        xy = to_plane(calibration, uv_a)
    has_pivot = trackers.pivot is not None or trackers.fixed is not None
    return Track(
        t=np.array(cols.t),
        frame=np.arange(len(cols.t)),
        uv=uv_a,
        found=np.all(np.isfinite(uv_a), axis=1),
        theta=angle(uv_a, piv_a) if has_pivot else None,
        pivot_uv=piv_a if trackers.pivot is not None else None,
        xy_m=xy,
        radius_px=np.array(radius),
        info=info,
        full_frame_searches=trackers.ball.full_frame_searches,
        notes=trackers.notes(),
        theta_in_plane=angle.axes is not None,
        confidence=np.where(seen, conf_a, 0.0),
        unsure=seen & ~trusted,
        second_look_frames=trackers.recovered,
        model_look_frames=trackers.modelled,
        outlier_frames=trackers.outliers,
        smoothed_frames=smoothed,
        off_pendulum_frames=trackers.off_pendulum,
        on_pendulum_frames=on_pendulum,
    )


def track_video(
    path: str | Path,
    ball: ColorSpec,
    *,
    options: TrackerOptions | None = None,
    pivot_uv: tuple[float, float] | None = None,
    pivot_color: ColorSpec | None = None,
    pivot_options: TrackerOptions | None = None,
    calibration: CameraCalibration | None = None,
    fps: float | None = None,
    progress: Callable[[int], None] | None = None,
    on_frame: Callable[[np.ndarray, FrameResult], None] | None = None,
    second_look: bool = True,
    smooth: bool = True,
) -> Track:
    """Track the ball through every frame of a video.

    pivot_uv: fixed pivot [px] in the raw image, or pivot_color: colour of a pivot marker to track (not
    both). fps [1/s] overrides the container's frame rate (times = index / fps). progress(frames_done) and
    on_frame(bgr, result) are called after each frame (e.g. to draw a preview). second_look: the frames before a
    confirmed stretch of the track where the ball was not found are searched again going back from it
    (:mod:`tracking.second_look`), and with a fixed pivot the frames a fitted pendulum places where the frame shows the
    ball (:mod:`tracking.model_look`). smooth: with a fixed pivot, fixes off their neighbours' motion are reported
    unsure, and the centres are smoothed over a few frames where the motion allows (:mod:`tracking.smoothing`; the
    on_frame preview shows neither). Raises InputError for unreadable videos or a calibration made for another image
    size.
    """
    with opencv_threads(1):  # OpenCV's pool costs more than it saves on the tracker's windows
        info = _check_inputs(path, pivot_uv, pivot_color, calibration)
        trackers = _Trackers(ball, options, pivot_uv, pivot_color, pivot_options)
        angle = ImageAngles(calibration, info.size)
        buffers = FrameBuffers()  # frames not kept for the looks are decoded into again
        frames = iter_frames(path, fps, buffers)
        # read ahead by a thread of ours: FFmpeg's frame threads decode ahead only while the reader waits in read(),
        # so without it they idled while the tracker worked (720p benchmark: wall 1.5-1.6x decoding -> 1.2-1.4x)
        frames = prefetched(frames)
        for k, t, frame in frames:
            b, p = trackers.step(frame, t)
            kept = k in trackers.kept
            if on_frame is not None:  # (a preview draws on its frame: not on one kept for the looks)
                on_frame(frame.copy() if kept else frame, _shown(trackers, angle, k, t, b, p))
            if not kept:
                buffers.give_back(frame)
            if progress is not None:
                progress(k + 1)
        trackers.finish()
        if second_look:
            trackers.second_look(str(path), fps)
        if smooth:
            trackers.reject_outliers(fps or info.fps)
            trackers.check_pendulum(fps or info.fps)
        if second_look:
            trackers.model_look(str(path), fps or info.fps)
            trackers.sharp_reserve()
        return _make_track(trackers, angle, calibration, info, (fps or info.fps) if smooth else None)
