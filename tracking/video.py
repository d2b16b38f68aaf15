"""Video reading: frames with their decoder timestamps [s] (OpenCV VideoCapture).

Timestamps come from CAP_PROP_POS_MSEC after each read (presentation time of the frame just decoded), so
variable-frame-rate videos keep their real timing; CAP_PROP_FPS is nominal only. Times start at 0 at the
first frame and strictly increase (a backend that repeats or lacks a timestamp falls back to the nominal
frame interval for that frame).
"""

from __future__ import annotations

import contextlib
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Iterator

import numpy as np

from trajectories.errors import InputError

_DEFAULT_FPS = 30.0  # [1/s] when the container does not state a frame rate


@contextlib.contextmanager
def opencv_threads(n: int = 1) -> Iterator[None]:
    """OpenCV's own worker threads (``cv2.setNumThreads``, process-wide) set to ``n`` for the block, then as before.

    The tracker's calls work on windows of a few thousand pixels, where handing each call to OpenCV's thread pool
    costs more than it saves: per frame of the 720p benchmark the pool added ≈ 0.5 of the decoding CPU (tracking
    2.0× against 1.4–1.8× decoding with one thread; benchmarks/bench_tracking.py). FFmpeg's decoder threads are
    FFmpeg's own and not affected: decoding still overlaps the tracking."""
    import cv2

    before = cv2.getNumThreads()
    cv2.setNumThreads(n)
    try:
        yield
    finally:
        cv2.setNumThreads(before)


@dataclass(frozen=True)
class VideoInfo:
    """What the container says about a video: size [px], nominal frame rate [1/s], frame count (may be 0)."""

    path: str
    width: int
    height: int
    fps: float
    frame_count: int
    decoder_threads: int = 1  # FFmpeg's threads decoding ahead of the reader (its default: the CPU count)

    @property
    def size(self) -> tuple[int, int]:
        return (self.width, self.height)


def _open(path: str | Path):
    import cv2

    from trajectories.inputs import require_regular

    spath = str(path)
    require_regular(spath)  # a device or a FIFO would block the decoder or never end
    os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")  # FFmpeg's own messages (e.g. "moov atom not found") off
    cap = cv2.VideoCapture(spath)
    if not cap.isOpened():
        cap.release()
        raise InputError("not a readable video (OpenCV could not open it)", file=spath)
    return cap


def _info(cap, spath: str) -> VideoInfo:
    import cv2

    fps = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
    if not (math.isfinite(fps) and fps > 0):
        fps = _DEFAULT_FPS
    count = int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
    return VideoInfo(
        path=spath,
        width=int(cap.get(cv2.CAP_PROP_FRAME_WIDTH)),
        height=int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT)),
        fps=fps,
        frame_count=max(count, 0),
        decoder_threads=max(int(cap.get(cv2.CAP_PROP_N_THREADS) or 1), 1),
    )


VIDEO_SUFFIXES = (".mp4", ".m4v", ".mov", ".avi", ".mkv")  # containers the mp4v writer of OpenCV fills


def check_video_name(path: str | Path, option: str) -> None:
    """OptionError (exit 2) unless ``path`` names a video container lbr writes (by its suffix)."""
    from trajectories.errors import OptionError

    if Path(path).suffix.lower() not in VIDEO_SUFFIXES:
        raise OptionError(f"{option} {path}: a video name must end in {', '.join(VIDEO_SUFFIXES)}")


def open_writer(
    path: str | Path, fps: float, size: tuple[int, int], target: str | Path | None = None, codec: str = "mp4v"
):
    """A ``cv2.VideoWriter`` (FourCC ``codec``) on ``path``; OutputError (exit 1) naming ``target`` when it cannot be
    opened (a full disk, a quota, no encoder)."""
    import cv2

    from trajectories.errors import OutputError

    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*codec), float(fps), tuple(int(s) for s in size))
    if not writer.isOpened():
        writer.release()
        raise OutputError("cannot start writing the video (a full disk, a quota or no encoder); nothing was written "
                          "under this name", file=target if target is not None else path)  # fmt: skip
    return writer


def check_written(path: str | Path, frames: int, target: str | Path | None = None) -> None:
    """OutputError (exit 1, naming ``target``) unless the video just written at ``path`` opens and holds ``frames``
    frames: OpenCV's writer does not report a full disk or a failed encoder, it leaves a short or unreadable file."""
    import cv2

    from trajectories.errors import OutputError

    cap = cv2.VideoCapture(str(path))
    try:
        got = int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0) if cap.isOpened() else 0
    finally:
        cap.release()
    if got < frames:
        raise OutputError(f"the video could not be written ({got} of {frames} frames readable: a full disk, a quota "
                          "or a codec missing?); nothing was written under this name",
                          file=target if target is not None else path)  # fmt: skip


def probe_video(path: str | Path) -> VideoInfo:
    """Size, nominal fps and frame count of a video; InputError if OpenCV cannot open it."""
    cap = _open(path)
    try:
        return _info(cap, str(path))
    finally:
        cap.release()


class FrameBuffers:
    """Frames to decode into, allocated CHUNK_FRAMES at a time and handed back for reuse once looked at: a reader
    that keeps some frames for later (the tracker's looks) would otherwise fault in fresh 4 KiB pages for every frame
    (≈ 0.7k page faults a 720p frame); a chunk is one large array, which numpy backs with huge pages. Thread-safe for
    one taker and one giver (list append and pop under the GIL)."""

    CHUNK_FRAMES = 8

    def __init__(self) -> None:
        self._free: list[np.ndarray] = []
        self._shape: tuple[int, ...] | None = None

    def take(self, shape: tuple[int, ...] | None) -> np.ndarray | None:
        """A free frame of ``shape`` (h, w, 3) uint8 — its content undefined —, or None while the shape is unknown."""
        if shape is None:
            return None
        if shape != self._shape:
            self._free, self._shape = [], shape
        if not self._free:
            self._free.extend(np.empty((self.CHUNK_FRAMES, *shape), np.uint8))
        return self._free.pop()

    def give_back(self, frame: np.ndarray) -> None:
        """The frame is no longer used: it may be decoded into again."""
        if self._shape is None and frame.ndim == 3 and frame.dtype == np.uint8 and frame.flags.c_contiguous:
            self._shape = frame.shape  # (the first frame, decoded before the size was known)
        if frame.shape == self._shape:
            self._free.append(frame)


def iter_frames(
    path: str | Path, fps: float | None = None, buffers: FrameBuffers | None = None
) -> Iterator[tuple[int, float, np.ndarray]]:
    """Yield (frame index, time [s] from the first frame, BGR frame (h, w, 3) uint8) for every frame.

    fps: the capture rate [1/s] when the container's is wrong (slow-motion videos state their playback rate):
    times are then index / fps, ignoring the container's timestamps. buffers: frames are decoded into these (the
    caller hands each back once done with it); else each frame is a new array.

    Raises InputError when the file cannot be opened or yields no frame at all.
    """
    import cv2

    spath = str(path)
    cap = _open(spath)
    try:
        nominal = 1.0 / _info(cap, spath).fps
        t0: float | None = None
        last = -math.inf
        k = 0
        shape: tuple[int, ...] | None = None
        while True:
            buf = buffers.take(shape) if buffers is not None else None
            ok, frame = cap.read(buf) if buf is not None else cap.read()
            if not ok or frame is None:
                if buf is not None:
                    buffers.give_back(buf)
                break
            shape = frame.shape
            if fps is not None:
                yield k, k / fps, frame
                k += 1
                continue
            ms = cap.get(cv2.CAP_PROP_POS_MSEC)
            t = ms / 1000.0 if ms is not None and math.isfinite(ms) else math.nan
            if t0 is None:
                t0 = t if math.isfinite(t) else 0.0
            t = t - t0
            if not math.isfinite(t) or t <= last:
                t = (last + nominal) if k else 0.0
            last = t
            yield k, t, frame
            k += 1
        if k == 0:
            raise InputError("video has no decodable frames", file=spath)
    finally:
        cap.release()


def frames_at(
    path: str | Path, fps: float | None, wanted: Iterable[int], kept: dict[int, np.ndarray] | None = None
) -> dict[int, np.ndarray]:
    """The BGR frames of the indices wanted: those in ``kept`` (frames held since a first pass) as they are, the rest
    decoded again up to the last of them (none when all were kept)."""
    kept = kept or {}
    wanted = set(wanted)
    out = {k: kept[k] for k in wanted if k in kept}
    missing = wanted - set(out)
    if missing:
        last = max(missing)
        for k, _, frame in iter_frames(path, fps):
            if k in missing:
                out[k] = frame
            if k >= last:
                break
    return out


def prefetched(items: Iterator, depth: int = 8) -> Iterator:
    """The items of an iterator (frames from :func:`iter_frames`) produced by a background thread up to ``depth``
    ahead, so that decoding (OpenCV releases the GIL) overlaps the consumer's work on a second core. An
    exception of the producer is raised in the consumer; a consumer that stops early stops the producer and
    closes its iterator (the video file)."""
    import queue
    import threading

    q: queue.Queue = queue.Queue(maxsize=depth)
    stop = threading.Event()
    end = object()

    def put(entry) -> bool:
        while not stop.is_set():
            try:
                q.put(entry, timeout=0.05)
                return True
            except queue.Full:
                continue
        return False

    def produce() -> None:
        try:
            for item in items:
                if not put((None, item)):
                    return
            put((None, end))
        except BaseException as exc:  # handed to the consumer, which raises it
            put((exc, None))
        finally:
            close = getattr(items, "close", None)
            if close is not None:
                close()

    thread = threading.Thread(target=produce, name="frame-prefetch", daemon=True)
    thread.start()
    try:
        while True:
            exc, item = q.get()
            if exc is not None:
                raise exc
            if item is end:
                return
            yield item
    finally:
        stop.set()
        thread.join(timeout=5.0)


# PyAV (FFmpeg) encoders for codecs OpenCV's wheels cannot write, by the name a user gives
_AV_CODECS = {"h264": "libx264", "hevc": "libx265", "h265": "libx265", "vp9": "libvpx-vp9", "av1": "libsvtav1"}


class VideoSink:
    """Writes BGR frames to a video file: OpenCV's VideoWriter for a FourCC ('mp4v', 'MJPG', ...), PyAV (FFmpeg)
    for 'h264', 'hevc', 'vp9', 'av1' — optionally at a target bitrate [kbit/s] (a phone's or a webcam's
    low-bandwidth stream: encoder ghosts, blocking, smeared colour). A writer that cannot start (a full disk, a
    quota, no encoder) is an OutputError naming ``target`` (the user's name when ``path`` is a temporary)."""

    def __init__(
        self,
        path: str | Path,
        codec: str,
        fps: float,
        size: tuple[int, int],
        bitrate_kbps: float | None = None,
        target: str | Path | None = None,
    ) -> None:
        from trajectories.errors import OutputError

        self.path = str(path)
        self._cv = None
        self._av = None
        name = codec.lower()
        if name in _AV_CODECS:
            from fractions import Fraction

            try:
                import av
            except ImportError:
                raise InputError(f"writing {codec} needs PyAV (pip install av)", file=self.path) from None
            try:
                self._av = av.open(self.path, "w")
            except OSError as exc:  # PyAV's errors are OSErrors (ENOSPC, EACCES, ...)
                raise OutputError(f"cannot start writing a {codec!r} video: {exc.strerror or exc}",
                                  file=self.path if target is None else target) from None  # fmt: skip
            stream = self._av.add_stream(_AV_CODECS[name], rate=Fraction(fps).limit_denominator(1001))
            stream.width, stream.height = int(size[0]), int(size[1])
            stream.pix_fmt = "yuv420p"
            if bitrate_kbps is not None:
                stream.bit_rate = int(bitrate_kbps * 1000)
                if name == "h264":  # a real low-bandwidth stream: rate-controlled, no lookahead tricks
                    stream.options = {"preset": "veryfast", "bf": "0"}
            if _AV_CODECS[name] == "libx265":
                stream.options = {**dict(stream.options or {}), "x265-params": "log-level=error"}
            self._stream = stream
        else:
            if bitrate_kbps is not None:
                raise ValueError(f"a bitrate is supported for {', '.join(_AV_CODECS)}, not {codec!r}")
            self._cv = open_writer(self.path, fps, size, target, codec)

    def write(self, frame: np.ndarray) -> None:
        if self._cv is not None:
            self._cv.write(frame)
            return
        import av

        for packet in self._stream.encode(av.VideoFrame.from_ndarray(frame, format="bgr24")):
            self._av.mux(packet)

    def close(self) -> None:
        if self._cv is not None:
            self._cv.release()
        elif self._av is not None:
            for packet in self._stream.encode():
                self._av.mux(packet)
            self._av.close()
        self._cv = self._av = None

    def __enter__(self) -> "VideoSink":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
