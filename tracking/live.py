"""The camera as a live sensor: the ball tracked in a camera's stream at the camera's rate, results to a callback
and to a controller that polls :meth:`LiveTracker.latest`.

Two threads: one reads the source as fast as frames come (OpenCV VideoCapture: a V4L2 device index or path, a
GigE/IP camera URL such as MJPEG over HTTP or RTSP, or a video file played at its frame rate) and keeps only the
newest frame; the other tracks it with the same :class:`tracking.tracker.BallTracker` as ``lbr track video``. When
tracking falls behind, the frames it had no time for are dropped (counted), never queued: every result is about
the newest frame. Each result carries the frame's capture time (``time.monotonic()`` when the frame was read) and
the latency from then to the result.

Results: image position, found and confidence (an unsure fix is reported not found), the string angle θ from
the pivot (a fixed pixel, a tracked marker, or the pivot projected through a :class:`CameraGeometry`), and with a
camera geometry, the pivot's position and the string length, the two tilt components θx, θy in the base frame.
The frames' tracker revisions (offline only) are not applied: a live result is final.
"""

from __future__ import annotations

import math
import os
import threading
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable

import numpy as np

from trajectories.errors import InputError

from .calibration import CameraCalibration
from .camera_geometry import CameraGeometry, tilt_from_pixel
from .color import ColorSpec
from .pipeline import ImageAngles
from .tracker import BallTracker, TrackerOptions


@dataclass(frozen=True)
class LiveResult:
    """One frame's result. Times on the ``time.monotonic()`` clock [s]; angles [rad]; image positions [px]."""

    seq: int  # index of the frame among those read from the source (dropped ones included)
    t_capture: float  # when the frame was read from the source [s, monotonic]
    t_source: float  # the source's own timestamp of the frame [s] (files: position in the video; NaN if none)
    t_result: float  # when this result was made [s, monotonic]
    found: bool  # the ball was found and the tracker is sure of it
    confidence: float  # 0–1 (below the tracker's min_confidence: unsure, found False)
    u: float  # ball centre [px] (NaN when not found)
    v: float
    radius_px: float  # [px] (NaN when not found)
    theta: float  # string angle in the image (or the calibrated plane) from the pivot [rad]; NaN when unknown
    theta_x: float  # tilt toward base +x [rad] (NaN without a camera geometry, pivot and string length)
    theta_y: float  # tilt toward base +y [rad]
    tilt_ambiguous: bool  # the depth part of the tilt is not observable from this view (see camera_geometry)
    dropped: int  # frames dropped so far because tracking was busy
    track_s: float  # time spent tracking this frame [s]

    @property
    def latency_s(self) -> float:
        """From the frame's capture to this result [s]."""
        return self.t_result - self.t_capture


@dataclass(frozen=True)
class TiltSetup:
    """What the tilt components need besides the pixel: the camera, the pivot and the string length."""

    geometry: CameraGeometry
    pivot_m: tuple[float, float, float]  # [m] in the base frame (update with LiveTracker.set_pivot as the robot moves)
    string_m: float  # pivot to ball centre [m]


@dataclass
class LiveStats:
    """Counts and timings of a run (read at any time; lists grow by one per tracked frame)."""

    read: int = 0  # frames read from the source
    tracked: int = 0
    dropped: int = 0  # read but never tracked (tracking was busy with an older frame)
    found: int = 0
    latency_s: list[float] = field(default_factory=list)
    track_s: list[float] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)


def open_source(source: str | int, buffer_frames: int = 1):
    """An opened cv2.VideoCapture for a device index ('0'), a device path (/dev/video0), a URL (http://, rtsp://,
    …) or a video file; InputError (naming the source) when it cannot be opened."""
    import cv2

    os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")
    text = str(source)
    if text.isdigit():
        cap = cv2.VideoCapture(int(text), cv2.CAP_V4L2) if hasattr(cv2, "CAP_V4L2") else cv2.VideoCapture(int(text))
    elif text.startswith("/dev/"):
        cap = cv2.VideoCapture(text, cv2.CAP_V4L2)
    elif "://" in text:
        # no demuxer buffering: a live stream must hand over each frame as soon as it arrived (read by OpenCV when
        # the capture opens; restored after, so that files opened later decode every frame)
        key = "OPENCV_FFMPEG_CAPTURE_OPTIONS"
        before = os.environ.get(key)
        os.environ[key] = before or "fflags;nobuffer|flags;low_delay"
        try:
            cap = cv2.VideoCapture(text, cv2.CAP_FFMPEG)
        finally:
            if before is None:
                del os.environ[key]
    else:
        if not Path(text).exists():
            raise InputError("file not found (and not a device index, /dev/video* path or URL)", file=text)
        cap = cv2.VideoCapture(text)
    if not cap.isOpened():
        cap.release()
        raise InputError("cannot open this camera or stream (OpenCV VideoCapture)", file=text)
    cap.set(cv2.CAP_PROP_BUFFERSIZE, buffer_frames)  # devices that honour it keep no backlog
    return cap


def is_file_source(source: str | int) -> bool:
    text = str(source)
    return not text.isdigit() and not text.startswith("/dev/") and "://" not in text


class LiveTracker:
    """Tracks the ball in a live source; see the module docstring.

    source: device index or path, URL, or video file (played at its frame rate, or at ``file_fps``).
    ball: the ball's colour. options: the tracker's (as ``lbr track video``). pivot_uv: a fixed pivot [px];
    pivot_color: a marker tracked as the pivot; tilt: camera geometry + pivot [m] + string length for θx, θy (its
    projected pivot is the pivot pixel when neither of the others is given). calibration: as ``lbr track video``
    (undistortion, θ in the plane). on_result(result) is called from the tracking thread after each frame, and
    on_frame(seq, bgr) before it is tracked (a preview, a recording, a camera's embedded frame counter); keep both
    short: they delay the next frame.
    """

    def __init__(
        self,
        source: str | int,
        ball: ColorSpec,
        *,
        options: TrackerOptions | None = None,
        pivot_uv: tuple[float, float] | None = None,
        pivot_color: ColorSpec | None = None,
        tilt: TiltSetup | None = None,
        calibration: CameraCalibration | None = None,
        on_result: Callable[[LiveResult], None] | None = None,
        on_frame: Callable[[int, np.ndarray], None] | None = None,
        file_fps: float | None = None,
    ) -> None:
        if pivot_uv is not None and pivot_color is not None:
            raise ValueError("give a fixed pivot or a pivot colour, not both")
        self.source = source
        self.ball = ball
        self.options = options or TrackerOptions()
        self.pivot_uv = None if pivot_uv is None else (float(pivot_uv[0]), float(pivot_uv[1]))
        self.pivot_color = pivot_color
        self.tilt = tilt
        self.calibration = calibration
        self.on_result = on_result
        self.on_frame = on_frame
        self.file_fps = file_fps
        self.stats = LiveStats()
        self.size: tuple[int, int] | None = None  # (width, height) [px] once open
        self.fps_nominal = math.nan
        self._cap = None
        self._slot: tuple[int, float, float, np.ndarray] | None = None  # newest frame not yet tracked
        self._slot_cond = threading.Condition()
        self._latest: LiveResult | None = None
        self._latest_cond = threading.Condition()
        self._stop = threading.Event()
        self._eof = threading.Event()
        self._threads: list[threading.Thread] = []
        self._pivot_m = None if tilt is None else np.asarray(tilt.pivot_m, float)
        self._prev_ball_m: np.ndarray | None = None

    # ------------------------------------------------------------------ public

    def start(self) -> "LiveTracker":
        """Open the source and start the reading and tracking threads (InputError if the source does not open)."""
        import cv2

        self._cap = open_source(self.source)
        self.size = (int(self._cap.get(cv2.CAP_PROP_FRAME_WIDTH)), int(self._cap.get(cv2.CAP_PROP_FRAME_HEIGHT)))
        self.fps_nominal = float(self._cap.get(cv2.CAP_PROP_FPS) or math.nan)
        for target, name in ((self._read_loop, "live-read"), (self._track_loop, "live-track")):
            th = threading.Thread(target=target, name=name, daemon=True)
            th.start()
            self._threads.append(th)
        return self

    def stop(self, timeout: float = 2.0) -> None:
        """Stop both threads and release the source."""
        self._stop.set()
        with self._slot_cond:
            self._slot_cond.notify_all()
        for th in self._threads:
            th.join(timeout=timeout)
        self._threads = []
        if self._cap is not None:
            self._cap.release()
            self._cap = None

    def __enter__(self) -> "LiveTracker":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    @property
    def running(self) -> bool:
        """The source still delivers (False after the end of a file, a lost stream, or stop())."""
        return bool(self._threads) and not self._stop.is_set() and any(th.is_alive() for th in self._threads)

    def latest(self) -> LiveResult | None:
        """The newest result (None before the first); never blocks — for a controller's cycle."""
        return self._latest

    def wait(self, after_seq: int = -1, timeout: float = 1.0) -> LiveResult | None:
        """Block until a result newer than frame after_seq exists (or timeout [s]); the newest result then."""
        with self._latest_cond:
            self._latest_cond.wait_for(
                lambda: (self._latest is not None and self._latest.seq > after_seq) or not self.running, timeout=timeout
            )
            return self._latest

    def set_pivot(self, pivot_m) -> None:
        """The pivot moved (the robot's flange) [m], base frame: used for the next frames' tilt."""
        self._pivot_m = np.asarray(pivot_m, float)

    # ------------------------------------------------------------------ threads

    def _read_loop(self) -> None:
        import cv2

        cap = self._cap
        pace = None
        if is_file_source(self.source):  # a file plays at its frame rate
            fps = self.file_fps or (self.fps_nominal if self.fps_nominal and self.fps_nominal > 0 else 30.0)
            pace = 1.0 / fps
        t0 = time.monotonic()
        k = 0
        try:
            while not self._stop.is_set():
                if pace is not None:
                    wait = t0 + k * pace - time.monotonic()
                    if wait > 0 and self._stop.wait(wait):
                        break
                ok, frame = cap.read()
                t_cap = time.monotonic()
                if not ok or frame is None:
                    break
                ms = cap.get(cv2.CAP_PROP_POS_MSEC)
                t_src = ms / 1000.0 if ms is not None and math.isfinite(ms) and ms > 0 else math.nan
                with self._slot_cond:
                    if self._slot is not None:  # the tracker did not take the previous one: dropped, not queued
                        self.stats.dropped += 1
                    self._slot = (k, t_cap, t_src, frame)
                    self.stats.read += 1
                    self._slot_cond.notify()
                k += 1
        except Exception as exc:  # a backend error ends the stream; said in stats
            self.stats.errors.append(f"reading: {exc}")
        finally:
            self._eof.set()
            with self._slot_cond:
                self._slot_cond.notify_all()

    def _track_loop(self) -> None:
        ball_tracker = BallTracker(self.ball, self.options)
        pivot_tracker = (
            BallTracker(self.pivot_color, replace(self.options, start_uv=None)) if self.pivot_color else None
        )
        angle = None
        sure = self.options.min_confidence
        try:
            while not self._stop.is_set():
                with self._slot_cond:
                    self._slot_cond.wait_for(
                        lambda: self._slot is not None or self._stop.is_set() or self._eof.is_set()
                    )
                    if self._slot is None:
                        if self._eof.is_set() or self._stop.is_set():
                            break
                        continue
                    seq, t_cap, t_src, frame = self._slot
                    self._slot = None
                if self.on_frame is not None:
                    self.on_frame(seq, frame)
                t0 = time.perf_counter()
                if angle is None:
                    angle = ImageAngles(self.calibration, (frame.shape[1], frame.shape[0]))
                pivot = self._pivot_pixel(pivot_tracker, frame, t_cap, sure)
                blob = ball_tracker.update(frame, t_cap, pivot)
                ball_tracker.pop_revision()  # live results are final
                conf = ball_tracker.confidence if blob is not None else 0.0
                found = blob is not None and conf >= sure
                theta = tx = ty = math.nan
                ambiguous = False
                if found and pivot is not None:
                    theta = float(angle(np.array([blob.u, blob.v]), np.array(pivot)))
                if found and self.tilt is not None and self._pivot_m is not None:
                    est = tilt_from_pixel(
                        self.tilt.geometry, (blob.u, blob.v), self._pivot_m, self.tilt.string_m, self._prev_ball_m
                    )
                    tx, ty, ambiguous = est.theta_x, est.theta_y, est.ambiguous
                    self._prev_ball_m = est.ball
                dt = time.perf_counter() - t0
                res = LiveResult(
                    seq=seq,
                    t_capture=t_cap,
                    t_source=t_src,
                    t_result=time.monotonic(),
                    found=found,
                    confidence=conf,
                    u=blob.u if found else math.nan,
                    v=blob.v if found else math.nan,
                    radius_px=blob.radius_px if found else math.nan,
                    theta=theta,
                    theta_x=tx,
                    theta_y=ty,
                    tilt_ambiguous=ambiguous,
                    dropped=self.stats.dropped,
                    track_s=dt,
                )
                self.stats.tracked += 1
                self.stats.found += int(found)
                self.stats.latency_s.append(res.latency_s)
                self.stats.track_s.append(dt)
                with self._latest_cond:
                    self._latest = res
                    self._latest_cond.notify_all()
                if self.on_result is not None:
                    self.on_result(res)
        except Exception as exc:
            self.stats.errors.append(f"tracking: {type(exc).__name__}: {exc}")
        finally:
            self._stop.set()
            with self._latest_cond:
                self._latest_cond.notify_all()

    def _pivot_pixel(self, pivot_tracker: BallTracker | None, frame: np.ndarray, t: float, sure: float):
        if pivot_tracker is not None:
            pb = pivot_tracker.update(frame, t)
            pivot_tracker.pop_revision()
            return (pb.u, pb.v) if pb is not None and pivot_tracker.confidence >= sure else None
        if self.pivot_uv is not None:
            return self.pivot_uv
        if self.tilt is not None and self._pivot_m is not None:
            p = self.tilt.geometry.project(self._pivot_m)[0]
            return (float(p[0]), float(p[1])) if np.all(np.isfinite(p)) else None
        return None


def track_from_results(results: list[LiveResult], source: str, size: tuple[int, int], fps: float, has_pivot: bool):
    """A :class:`tracking.pipeline.Track` of live results (t from the first frame's capture [s], frame = seq), with
    the columns theta_x, theta_y [rad], latency_s [s] and t_source [s] after the usual ones — for the track CSV."""
    from .pipeline import Track
    from .video import VideoInfo

    if not results:
        raise ValueError("no results")
    t_cap = np.array([r.t_capture for r in results])
    t = t_cap - t_cap[0]
    keep = np.concatenate([[True], np.diff(t) > 0])  # strictly increasing times (a repeated capture time is dropped)
    rs = [r for r, k in zip(results, keep) if k]
    arr = lambda name: np.array([getattr(r, name) for r in rs], float)  # noqa: E731
    return Track(
        t=t[keep],
        frame=np.array([r.seq for r in rs]),
        uv=np.column_stack([arr("u"), arr("v")]),
        found=np.array([r.found for r in rs]),
        theta=arr("theta") if has_pivot else None,
        pivot_uv=None,
        xy_m=None,
        radius_px=arr("radius_px"),
        info=VideoInfo(str(source), size[0], size[1], fps, len(rs)),
        full_frame_searches=0,
        confidence=arr("confidence"),
        unsure=np.array([(not r.found) and r.confidence > 0 for r in rs]),
        extra=(
            ("theta_x", arr("theta_x")),
            ("theta_y", arr("theta_y")),
            ("latency_s", arr("latency_s")),
            ("t_source", arr("t_source")),
        ),
    )
