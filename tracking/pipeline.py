"""A whole video → per-frame ball centre, found flag, decoder time, and θ when the pivot is known.

The pivot is a fixed pixel or a second coloured marker tracked like the ball. With a camera calibration
the ball and pivot are undistorted before θ is taken, and a plane calibration adds plane metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from trajectories.errors import InputError

from .angle import string_angle
from .calibration import CameraCalibration, to_plane, undistort_points
from .color import ColorSpec
from .detect import Blob
from .tracker import BallTracker, TrackerOptions
from .video import VideoInfo, iter_frames, probe_video


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

    @property
    def found_fraction(self) -> float:
        return float(self.found.mean()) if len(self.found) else 0.0


def track_video(
    path: str | Path,
    ball: ColorSpec,
    *,
    options: TrackerOptions | None = None,
    pivot_uv: tuple[float, float] | None = None,
    pivot_color: ColorSpec | None = None,
    pivot_options: TrackerOptions | None = None,
    calibration: CameraCalibration | None = None,
    progress: Callable[[int], None] | None = None,
    on_frame: Callable[[np.ndarray, FrameResult], None] | None = None,
) -> Track:
    """Track the ball through every frame of a video.

    pivot_uv: fixed pivot [px] in the raw image, or pivot_color: colour of a pivot marker to track (not
    both). progress(frames_done) and on_frame(bgr, result) are called after each frame (e.g. to draw a
    preview). Raises InputError for unreadable videos or a calibration made for another image size.
    """
    if pivot_uv is not None and pivot_color is not None:
        raise ValueError("give a fixed pivot or a pivot colour, not both")
    info = probe_video(path)
    if calibration is not None and tuple(calibration.image_size) != info.size:
        raise InputError(
            f"calibration is for {calibration.image_size[0]}x{calibration.image_size[1]} images, "
            f"the video is {info.width}x{info.height}",
            file=str(path),
        )
    ball_tracker = BallTracker(ball, options)
    pivot_tracker = BallTracker(pivot_color, pivot_options or options) if pivot_color is not None else None
    fixed = None
    if pivot_uv is not None:
        fixed = np.asarray(pivot_uv, float)
        fixed_und = undistort_points(calibration, fixed) if calibration is not None else fixed

    ts: list[float] = []
    uv: list[tuple[float, float]] = []
    radius: list[float] = []
    piv: list[tuple[float, float]] = []
    theta: list[float] = []
    nan2 = (math.nan, math.nan)
    for k, t, frame in iter_frames(path):
        b = ball_tracker.update(frame, t)
        p: tuple[float, float] | None = None
        if pivot_tracker is not None:
            pb = pivot_tracker.update(frame, t)
            p = (pb.u, pb.v) if pb is not None else None
            piv.append(p if p is not None else nan2)
        elif fixed is not None:
            p = (float(fixed[0]), float(fixed[1]))
        th = math.nan
        if b is not None and p is not None:
            bu = np.array([b.u, b.v])
            if calibration is not None:
                bu = undistort_points(calibration, bu)
                pu = fixed_und if pivot_tracker is None else undistort_points(calibration, np.array(p))
            else:
                pu = np.array(p)
            th = float(string_angle(bu, pu))
        ts.append(t)
        uv.append((b.u, b.v) if b is not None else nan2)
        radius.append(b.radius_px if b is not None else math.nan)
        theta.append(th)
        if on_frame is not None:
            on_frame(frame, FrameResult(k, t, b, p, th))
        if progress is not None:
            progress(k + 1)

    uv_a = np.array(uv, float).reshape(-1, 2)
    xy = None
    if calibration is not None and calibration.plane is not None:
        xy = to_plane(calibration, uv_a)
    has_pivot = pivot_tracker is not None or fixed is not None
    return Track(
        t=np.array(ts),
        frame=np.arange(len(ts)),
        uv=uv_a,
        found=np.all(np.isfinite(uv_a), axis=1),
        theta=np.array(theta) if has_pivot else None,
        pivot_uv=np.array(piv, float).reshape(-1, 2) if pivot_tracker is not None else None,
        xy_m=xy,
        radius_px=np.array(radius),
        info=info,
        full_frame_searches=ball_tracker.full_frame_searches,
    )
