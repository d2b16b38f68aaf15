"""The camera as the damper's sway sensor: the ball tracked live in a camera's frames, turned into the string's tilt
θx, θy in the robot's base frame.

The tracking runs in a process of its own (:func:`_tracker_main`: :class:`tracking.live.LiveTracker`, the tracker of
``lbr track live``), which sends every result as one datagram of ``lbr track live``'s UDP output
(:mod:`lbrcli.lab.camera_publish`) to a loopback socket this side reads without blocking: decoding and tracking
frames never hold the FRI loop's interpreter lock. Per result, in the FRI loop (about 50 µs): the moment the frame
shows is its capture time minus the camera's own delay (exposure and transfer, which the tracker cannot see:
``camera_delay_s``); the pivot at that moment is the TCP of the robot's measured joint positions (recorded from every
FRI message, :class:`~lbrcli.lab.timed_ring.TimedRing`, interpolated); the tilt is where the pixel's ray meets the string's sphere about
it (:func:`tracking.camera_geometry.tilt_from_pixel`). That sphere's radius is measured by the camera itself before
the first row: while the robot stands still, the ray through the hanging ball meets the vertical under the pivot at
the string's length (:func:`~tracking.camera_geometry.hanging_length`); without such a view the assumed length is
used (a wrong radius bends every tilt the camera reports).
"""

from __future__ import annotations

import math
import socket
import time
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from tracking.camera_geometry import hanging_length, tilt_from_pixel
from trajectories.errors import CheckFailed, InputError

from ..lab.camera_publish import decode  # (imported here: not in the FRI loop's first cycle)
from ..lab.timed_ring import TimedRing

STILL_Q = 1e-4  # [rad] the joints moved less than this over REST_S: the robot stands still
REST_S = 0.1  # [s]
HANGING_WINDOW_S = 1.0  # [s] the length is the median of the hanging views of the last second before the first row
MIN_HANGING_VIEWS = 5
MIN_RAY_ANGLE = math.radians(15.0)  # a ray closer to the vertical than this cannot tell the length
MAX_HANGING_GAP_M = 0.03  # [m] a ball seen farther than this off the vertical under the pivot is not hanging there
START_FOUND = 5  # results with the ball found before the camera counts as seeing it


@dataclass(frozen=True)
class TiltReading:
    """One frame's tilt: times on ``time.monotonic()`` [s], angles [rad]."""

    seq: int  # the frame's index in the stream
    moment: float  # the moment the frame shows (capture − the camera's delay) [s]
    arrived: float  # when the tracker's result was made [s]
    theta_x: float  # toward base +x [rad]
    theta_y: float  # toward base +y [rad]
    found: bool = True


CAMERA_NICENESS = 4  # the camera's processes yield the CPU to the FRI loop's: a late frame costs less than a late reply


def _yield_to_the_loop() -> None:
    """Lower this process's priority by CAMERA_NICENESS (where permitted): on a busy PC the FRI loop (and the
    simulator) keep their cycle, the camera's frames come later instead."""
    import os

    try:
        os.nice(CAMERA_NICENESS)
    except (AttributeError, OSError):
        pass


def _tracker_main(source: str, ball, options, file_fps: float | None, port: int, conn,  # noqa: ANN001
                  stamp: tuple[float, float] | None = None) -> None:  # fmt: skip
    """The tracking process: results to 127.0.0.1:port as datagrams; ("open", size, fps) or ("error", text) first,
    ("end", figures) last on ``conn``; runs until told to stop, the stream ends or its starter is gone. With
    ``stamp`` = (t0 [s, monotonic], fps): the frames carry their index (:func:`lbrcli.lab.camera_stream.write_stamp`,
    a camera's embedded frame counter) and each result's t_source is the moment its frame shows, t0 + index / fps."""
    import signal
    from dataclasses import replace

    from lbrcli.lab.camera_publish import UdpPublisher
    from lbrcli.lab.camera_stream import read_stamp
    from tracking.live import LiveTracker
    from tracking.subpixel import matte_centre

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the starter decides when it ends
    _yield_to_the_loop()
    pub = UdpPublisher("127.0.0.1", port)
    frames: dict[int, tuple] = {}  # frame seq → (the frame, the camera's frame index or None)

    def on_frame(seq: int, frame) -> None:  # noqa: ANN001
        frames.clear()  # (the tracker takes the newest frame; one skipped never gets a result)
        frames[seq] = (frame, read_stamp(frame) if stamp else None)

    def on_result(r) -> None:  # noqa: ANN001
        frame, k = frames.pop(r.seq, (None, None))
        if frame is not None and r.found:  # the centre to a fraction of a pixel (tracking.subpixel)
            u, v = matte_centre(frame, r.u, r.v, r.radius_px)
            r = replace(r, u=u, v=v)
        pub.publish(r if k is None else replace(r, t_source=stamp[0] + k / stamp[1]))

    tracker = LiveTracker(source, ball, options=options, on_result=on_result, on_frame=on_frame, file_fps=file_fps)
    try:
        tracker.start()
    except InputError as exc:
        conn.send(("error", str(exc)))
        return
    conn.send(("open", tracker.size, tracker.fps_nominal))
    try:
        while tracker.running and not conn.poll(0.05):
            pass
    except (EOFError, OSError):
        pass
    tracker.stop()
    st = tracker.stats
    lat = np.array(st.latency_s) * 1e3
    pct = lambda q: float(np.percentile(lat, q)) if len(lat) else None  # noqa: E731
    try:
        conn.send(("end", {"camera_frames_read": st.read, "camera_frames_tracked": st.tracked,
                           "camera_frames_dropped": st.dropped,
                           "camera_found_percent": 100.0 * st.found / st.tracked if st.tracked else 0.0,
                           "camera_latency_ms_p50": pct(50), "camera_latency_ms_p95": pct(95),
                           "camera_errors": list(st.errors), "camera_datagrams_dropped": pub.failed}))  # fmt: skip
    except (BrokenPipeError, OSError):
        pass


class CameraTilt:
    """Tilt readings of the ball from a camera (see the module).

    source: an OpenCV source (device index or path, URL — the simulated camera's too —, video file). geometry: the camera's
    :class:`~tracking.camera_geometry.CameraGeometry` (may be set after :meth:`start`). robot: a
    :class:`trajectories.robot.Robot` (its TCP is the pivot). ball: the ball's :class:`~tracking.color.ColorSpec`.
    string_m: the length assumed when the camera cannot measure it [m]. q_rest: where the robot stands before the
    session's first message [rad] (None: unknown; only views during the session count). stamp: (t0, fps) of a
    camera that writes each frame's index into it (the simulated one, ``CameraConfig.stamp``): the moment a frame
    shows is then t0 + index / fps [s, monotonic] rather than its arrival − ``camera_delay_s``.
    """

    def __init__(self, source: str, geometry, robot, ball, string_m: float, camera_delay_s: float, *,
                 q_rest: Sequence[float] | None = None, fps: float | None = None, options=None,
                 stamp: tuple[float, float] | None = None, start_timeout_s: float = 10.0) -> None:  # fmt: skip
        self.source = source
        self.geometry = geometry
        self.robot = robot
        self.ball = ball
        self.assumed_string_m = string_m
        self.camera_delay_s = camera_delay_s
        self.q_rest = None if q_rest is None else np.asarray(q_rest, float)
        self.fps = fps  # nominal frame rate [1/s] (None: the source's own, once open)
        self.size: tuple[int, int] | None = None  # (w, h) [px] once open
        self.options = options
        self.stamp = stamp  # (t0 [s, monotonic], fps): frames carry their index; their moment is t0 + index / fps
        self.start_timeout_s = start_timeout_s
        self.poses = TimedRing(4096, 7)  # the robot's measured joints [rad] at each message [s]
        self.string_m: float | None = None  # the length the tilt uses, fixed by freeze()
        self.string_source = ""  # "camera" (measured hanging) or "assumed"
        self.hanging_gap_m = math.nan  # [m] how far off the vertical under the pivot the hanging ball was seen
        self.view_px_per_deg: tuple[float, float] | None = None  # [px] a 1° tilt toward x, y moves the ball (at least)
        self.zero_px = (0.0, 0.0)  # [px] the hanging ball's centre off where the geometry puts it (see freeze())
        self._hanging: list[tuple] = []  # (moment, length, gap, u, v, pivot) while the robot stood still
        self._latest: TiltReading | None = None
        self._prev_ball: np.ndarray | None = None
        self._last_result = math.nan  # [s, monotonic] of the newest result, found or not
        self._last_found = math.nan
        self.results = self.found = self.readings = 0
        self.ambiguous = 0  # readings whose depth part was not observable
        self._sock: socket.socket | None = None
        self._proc = None
        self._conn = None
        self._end: dict[str, Any] | None = None  # the tracking process's figures once it ended

    # ------------------------------------------------------------------ life

    def start(self) -> "CameraTilt":
        """Open the source in the tracking process and wait until the ball has been seen (CheckFailed if the camera
        cannot be opened or does not show the ball within ``start_timeout_s``; InputError for a missing video file)."""
        import multiprocessing as mp

        from tracking.live import is_file_source

        if self._proc is not None:
            return self
        source = self.source
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)
        self._sock.bind(("127.0.0.1", 0))
        self._sock.setblocking(False)
        ctx = mp.get_context("spawn")
        self._conn, child = ctx.Pipe()
        self._proc = ctx.Process(target=_tracker_main, name="lbr-camera-tracker", daemon=True,
                                 args=(source, self.ball, self.options, self.fps if is_file_source(source) else None,
                                       self._sock.getsockname()[1], child, self.stamp))  # fmt: skip
        self._proc.start()
        child.close()
        t_end = time.monotonic() + self.start_timeout_s + 20.0  # (a spawned interpreter imports OpenCV first)
        if not self._conn.poll(max(0.0, t_end - time.monotonic())):
            self.stop()
            raise CheckFailed(f"camera {source}: the tracking process did not start")
        try:
            kind, *payload = self._conn.recv()
        except EOFError:
            kind, payload = "error", ["the tracking process ended"]
        if kind == "error":
            self.stop()
            if is_file_source(source) and "not found" in payload[0]:
                raise InputError("file not found (and not a device index, /dev/video* path or URL)", file=source)
            raise CheckFailed(f"camera {source}: cannot be opened (not reachable, or not a camera OpenCV reads)")
        self.size, fps = tuple(payload[0]), payload[1]
        if self.fps is None:
            self.fps = fps if fps and fps > 0 else 30.0
        t_end = time.monotonic() + self.start_timeout_s
        while time.monotonic() < t_end and self.found < START_FOUND and self._alive():
            self.drain()
            time.sleep(0.01)
        if self.found < START_FOUND:
            seen = self.results
            self.stop()
            why = ("delivered no frame" if seen == 0 else
                   f"delivered {seen} frames but the ball was found in {self.found} (is it in view, is its colour (CameraSensor.color) right?)")  # fmt: skip
            raise CheckFailed(f"camera {source}: {why} within {self.start_timeout_s:g} s")
        return self

    def _alive(self) -> bool:
        return self._proc is not None and self._proc.is_alive() and self._end is None and not self._ended()

    def _ended(self) -> bool:
        """The tracking process reported its end (the stream ended); its figures are kept."""
        if self._end is None and self._conn is not None:
            try:
                while self._conn.poll():
                    kind, *payload = self._conn.recv()
                    if kind == "end":
                        self._end = payload[0]
            except (EOFError, OSError):
                self._end = self._end or {}
        return self._end is not None

    def stop(self) -> None:
        if self._proc is not None:
            if self._end is None:
                try:
                    self._conn.send("stop")
                    if self._conn.poll(5.0):
                        self._ended()
                except (BrokenPipeError, EOFError, OSError):
                    pass
            self._proc.join(timeout=3.0)
            if self._proc.is_alive():
                self._proc.terminate()
                self._proc.join(timeout=2.0)
            self._proc = None
        if self._conn is not None:
            self._conn.close()
            self._conn = None
        if self._sock is not None:
            self._sock.close()
            self._sock = None

    def summary(self) -> dict[str, Any]:
        """Figures of the run (frames, latency capture → result, the string length used)."""
        d: dict[str, Any] = {
            "camera_source": str(self.source), "camera_fps": self.fps, "camera_size": list(self.size) if self.size else None,
            "camera_string_m": self.string_m, "camera_string_source": self.string_source or None,
            "camera_hanging_gap_mm": self.hanging_gap_m * 1e3 if math.isfinite(self.hanging_gap_m) else None,
            "camera_zero_px": list(self.zero_px),
            "camera_delay_ms": self.camera_delay_s * 1e3, "camera_results": self.results, "camera_readings": self.readings,
            "camera_readings_ambiguous": self.ambiguous,
            "camera_position_m": None if self.geometry is None else [float(v) for v in self.geometry.centre],
            "camera_px_per_deg": None if self.view_px_per_deg is None else list(self.view_px_per_deg),
        }  # fmt: skip
        d.update(self._end or {})
        return d

    # ------------------------------------------------------------------ the FRI loop's side

    def observe(self, t: float, q: Sequence[float]) -> None:
        """The robot's measured joint positions q [rad] at time t [s, monotonic] (every FRI message); then the
        results that arrived are taken in."""
        self.poses.push(t, q)
        self.drain()

    def drain(self) -> None:
        """Take in every result that arrived (never blocks)."""
        sock = self._sock
        if sock is None:
            return
        while True:
            try:
                data = sock.recv(256)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                return
            try:
                r = decode(data)
            except ValueError:
                continue
            self._take(r)

    def freeze(self) -> float:
        """Fix the string length [m] the tilt uses (at the first row): the median of the hanging views of the last
        second, or the assumed length without enough of them."""
        if self.string_m is not None:
            return self.string_m
        views = self._hanging
        if views:
            last = views[-1][0]
            views = [v for v in views if v[0] >= last - HANGING_WINDOW_S]
        if len(views) >= MIN_HANGING_VIEWS:
            self.string_m = float(np.median([v[1] for v in views]))
            self.hanging_gap_m = float(np.median([v[2] for v in views]))
            self.string_source = "camera"
            self.zero_px = self._zero(views, self.string_m)
        else:
            self.string_m = self.assumed_string_m
            self.string_source = "assumed"
        return self.string_m

    def _zero(self, views: list[tuple], length: float) -> tuple[float, float]:
        """The camera's zero [px]: the median offset of the hanging ball's centre from the projection of a ball
        ``length`` [m] straight below the pivot. At rest the ball hangs plumb, so what is left is the camera's own
        bias — the calibration's, the detector's (a string over the ball, the image's colour sampling) —, which
        every tilt reading would carry as a constant tilt of bias / (pixels per radian) and the damper would chase.
        (Along the vertical the bias went into the measured length; this is the part across it.)"""
        down = np.array([0.0, 0.0, -length])
        seen = np.array([(v[3], v[4]) for v in views])
        expected = self.geometry.project(np.array([v[5] + down for v in views]))
        du, dv = np.median(seen - expected, axis=0)
        return (float(du), float(dv)) if math.isfinite(du) and math.isfinite(dv) else (0.0, 0.0)

    def latest(self) -> TiltReading | None:
        return self._latest

    def failure(self, now: float) -> str | None:
        """Why the camera cannot be trusted now [s, monotonic] (the stream ended, no frame, the ball lost), or None."""
        if self._proc is None:
            return None
        if self._ended() or not self._proc.is_alive():
            errs = (self._end or {}).get("camera_errors") or []
            return f"the camera's stream ended{f' ({errs[-1]})' if errs else ''}"
        fps = self.fps or 30.0
        stale = max(0.5, 20.0 / fps)  # (a busy PC stalls a stream for a few frames; a dead one stays silent)
        if math.isfinite(self._last_result) and now - self._last_result > stale:
            return f"the camera delivered no frame for {now - self._last_result:.2f} s"
        lost = max(1.0, 40.0 / fps)
        if math.isfinite(self._last_found) and now - self._last_found > lost:
            return f"the camera lost the ball ({now - self._last_found:.2f} s without a sure fix)"
        return None

    # ------------------------------------------------------------------ one result

    def _pivot(self, q: np.ndarray) -> np.ndarray:
        return np.asarray(self.robot.fk(q).translation, float)

    def _still(self, moment: float) -> np.ndarray | None:
        """The joints [rad] at the moment if the robot stood still around it, else None."""
        if len(self.poses) == 0:
            return self.q_rest
        q1, q0 = self.poses.at(moment), self.poses.at(moment - REST_S)
        return q1 if float(np.max(np.abs(q1 - q0))) < STILL_Q else None

    def _take(self, r: dict) -> None:
        """One tracker result (a decoded datagram: seq, t_capture, latency_s, found, u, v, …)."""
        self.results += 1
        t_result = r["t_capture"] + r["latency_s"]
        self._last_result = t_result
        if not r["found"]:
            return
        self.found += 1
        self._last_found = t_result
        if self.geometry is None:  # (a real camera is opened before its geometry is known)
            return
        moment = r["t_source"] if self.stamp and math.isfinite(r["t_source"]) else r["t_capture"] - self.camera_delay_s
        uv = (r["u"], r["v"])
        length = self.string_m
        if length is None:  # before the first row: measure the string from the hanging ball
            q = self._still(moment)
            if q is not None:
                L, gap, angle = hanging_length(self.geometry, uv, self._pivot(q))
                if math.isfinite(L) and angle >= MIN_RAY_ANGLE and gap <= MAX_HANGING_GAP_M and 0.02 <= L <= 5.0:
                    self._hanging.append((moment, L, gap, uv[0], uv[1], self._pivot(q)))
                    if len(self._hanging) > 1000:
                        del self._hanging[:500]
            return
        q = self.poses.at(moment)
        if q is None:
            q = self.q_rest
        if q is None:
            return
        uv = (uv[0] - self.zero_px[0], uv[1] - self.zero_px[1])
        est = tilt_from_pixel(self.geometry, uv, self._pivot(q), length, self._prev_ball)
        self._prev_ball = est.ball
        self.ambiguous += int(est.ambiguous)
        self.readings += 1
        self._latest = TiltReading(r["seq"], moment, t_result, est.theta_x, est.theta_y)
