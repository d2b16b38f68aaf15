"""A simulated camera: frames of the ball on its string rendered from a 3-D scene and served as MJPEG over HTTP on
loopback, the way an IP camera streams — OpenCV's VideoCapture opens the URL like a real camera's.

The scene is a callable ``scene(t) -> (ball_m, pivot_m)`` giving the ball's centre and the pivot [m] in the robot's
base frame at time t [s] (the FRI simulator's ball plugs in here). A render thread makes frame k at scene time
k / fps (the shutter open for ``exposure_s`` around it: motion blur), encodes it as JPEG and hands it to the
clients ``latency_s`` later, on the camera's schedule: a client that reads late gets the newest frame, never a
queue. Rendering reuses :mod:`tracking.synthetic` (the same backdrop, ball and string as the test videos).
"""

from __future__ import annotations

import math
import socket
import threading
import time
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Callable

import numpy as np

from tracking.camera_geometry import CameraGeometry

Scene = Callable[[float], tuple[np.ndarray, np.ndarray]]  # t [s] → (ball centre (3,), pivot (3,)) [m], base frame
BOUNDARY = "lbrframe"


@dataclass(frozen=True)
class CameraConfig:
    """The simulated camera: pose, image, timing, and the ball's look."""

    position_m: tuple[float, float, float] = (1.2, 0.0, 0.45)  # camera centre in the base frame [m]
    look_at_m: tuple[float, float, float] = (0.5, 0.0, 0.3)  # the point at the image centre [m]
    fov_deg: float = 50.0  # horizontal field of view [deg]
    size: tuple[int, int] = (640, 480)  # (width, height) [px]
    fps: float = 60.0  # frame rate [1/s] (30–240)
    exposure_s: float = 0.004  # shutter open time [s] (motion blur); 0: sharp
    latency_s: float = 0.0  # added delay from the end of the exposure to the frame leaving the camera [s]
    ball_radius_m: float = 0.02  # [m]
    ball_bgr: tuple[int, int, int] = (35, 30, 205)  # a saturated red
    pivot_marker: str | None = None  # colour name of a marker disc drawn at the pivot, or None
    jpeg_quality: int = 90
    noise_std: float = 2.0  # sensor noise [grey levels]
    stamp: bool = False  # write the frame index into the image's bottom-left corner (see read_stamp), like a camera's frame counter
    seed: int = 0

    def geometry(self) -> CameraGeometry:
        """The camera's intrinsics and pose (what a calibration of this camera would give)."""
        return CameraGeometry.from_pose(self.position_m, self.look_at_m, self.fov_deg, self.size)


@dataclass
class StreamStats:
    """What the camera did: frames rendered and served, the render time and how late frames left [s]."""

    frames: int = 0
    render_s: list[float] = field(default_factory=list)  # per frame [s]
    late_s: list[float] = field(default_factory=list)  # frame left the camera this much after its due time [s]
    clients: int = 0


class CameraServer:
    """Serves ``scene`` as seen by the camera of ``config`` at http://127.0.0.1:PORT/stream.mjpg.

    Scene time t runs with the wall clock from :meth:`start` (t = clock() − start), or from ``t0`` given to start;
    frame k shows the scene at t_k = k / fps and leaves at start + t_k + exposure/2 + latency. ``frame_times`` keeps
    t_k of every frame served, so a test can pair the tracker's results with the truth.
    """

    def __init__(self, scene: Scene, config: CameraConfig | None = None, host: str = "127.0.0.1", port: int = 0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        if host not in ("127.0.0.1", "localhost", "::1"):
            raise ValueError("the simulated camera serves on loopback only")
        self.scene = scene
        self.config = config or CameraConfig()
        c = self.config
        if not 1.0 <= c.fps <= 1000.0:
            raise ValueError(f"fps must be in 1–1000, got {c.fps:g}")
        self.geometry = c.geometry()
        self.clock = clock
        self.stats = StreamStats()
        self.frame_times: list[float] = []  # scene time of each frame [s]
        self._host, self._port = host, port
        self._latest: tuple[int, bytes] | None = None
        self._cond = threading.Condition()
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []
        self._server: ThreadingHTTPServer | None = None
        self.t_start = math.nan  # clock() at scene time 0
        self._noise: list[np.ndarray] | None = None
        self._noise_k = 0

    # ------------------------------------------------------------------ lifecycle

    @property
    def url(self) -> str:
        assert self._server is not None, "start() first"
        return f"http://{self._host}:{self._server.server_address[1]}/stream.mjpg"

    def start(self) -> "CameraServer":
        server = self

        class Handler(BaseHTTPRequestHandler):
            def log_message(self, *args) -> None:  # quiet
                pass

            def do_GET(self) -> None:  # noqa: N802 (http.server's name)
                if self.path.split("?")[0] not in ("/stream.mjpg", "/"):
                    self.send_error(404)
                    return
                self.send_response(200)
                self.send_header("Content-Type", f"multipart/x-mixed-replace; boundary={BOUNDARY}")
                self.send_header("Cache-Control", "no-cache")
                self.send_header("Connection", "close")
                self.end_headers()
                server.stats.clients += 1
                server._serve(self.wfile)

        self._server = ThreadingHTTPServer((self._host, self._port), Handler)
        self._server.daemon_threads = True
        self.t_start = self.clock()
        for target, name in ((self._server.serve_forever, "camera-http"), (self._render_loop, "camera-render")):
            th = threading.Thread(target=target, name=name, daemon=True)
            th.start()
            self._threads.append(th)
        return self

    def stop(self) -> None:
        self._stop.set()
        with self._cond:
            self._cond.notify_all()
        if self._server is not None:
            self._server.shutdown()
            self._server.server_close()
        for th in self._threads:
            th.join(timeout=2.0)
        self._threads = []

    def __enter__(self) -> "CameraServer":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    # ------------------------------------------------------------------ rendering

    def render(self, t: float, rng: np.random.Generator | None = None, background: np.ndarray | None = None) -> np.ndarray:
        """The BGR frame showing the scene at time t [s] (the exposure centred on t)."""
        import cv2

        from tracking.synthetic import draw_pendulum, lab_background

        c = self.config
        g = self.geometry
        frame = (background if background is not None else lab_background(c.size, c.seed)).copy()
        m = 1
        if c.exposure_s > 0:
            b0, _ = self.scene(t - c.exposure_s / 2)
            b1, _ = self.scene(t + c.exposure_s / 2)
            span = g.project(np.vstack([b0, b1]))
            m = int(min(16, max(1, math.ceil(float(np.linalg.norm(span[1] - span[0])) / 0.5))))
        times = t + (np.linspace(-c.exposure_s / 2, c.exposure_s / 2, m) if m > 1 else np.zeros(1))
        balls = np.array([self.scene(float(tk))[0] for tk in times])
        ball_mid, pivot = self.scene(t)
        uv = g.project(balls)
        pivot_uv = g.project(np.asarray(pivot, float))[0]
        depth = float(g.depth(np.asarray(ball_mid, float))[0])
        if np.all(np.isfinite(uv)) and depth > 0:
            r_px = float(g.camera_matrix[0, 0]) * c.ball_radius_m / depth
            draw_pendulum(frame, pivot_uv, uv, r_px, c.ball_bgr, c.pivot_marker)
        if c.noise_std > 0:  # sensor noise from a bank of 8 fields drawn once (drawing a field costs ≈ 9 ms at VGA)
            if self._noise is None:
                gen = rng or np.random.default_rng(c.seed)
                self._noise = [np.round(gen.normal(0.0, c.noise_std, frame.shape)).astype(np.int16) for _ in range(8)]
            self._noise_k = (self._noise_k + 1) % len(self._noise)
            frame = cv2.add(frame, self._noise[self._noise_k], dtype=cv2.CV_8U)
        return cv2.GaussianBlur(frame, (0, 0), 0.5)

    def _render_loop(self) -> None:
        import cv2

        from tracking.synthetic import lab_background

        c = self.config
        bg = lab_background(c.size, c.seed)
        rng = np.random.default_rng(c.seed)
        period = 1.0 / c.fps
        k = 0
        while not self._stop.is_set():
            t_k = k * period
            due = self.t_start + t_k + c.exposure_s / 2 + c.latency_s
            r0 = time.perf_counter()
            if self.clock() - due > 4 * period + c.latency_s:  # far behind (a stalled machine): skip frames
                k += 1
                continue
            frame = self.render(t_k, rng, bg)
            if c.stamp:
                write_stamp(frame, k)
            ok, jpg = cv2.imencode(".jpg", frame, [cv2.IMWRITE_JPEG_QUALITY, int(c.jpeg_quality)])
            self.stats.render_s.append(time.perf_counter() - r0)
            wait = due - self.clock()
            if wait > 0:
                self._stop.wait(wait)
            if self._stop.is_set():
                break
            with self._cond:
                self._latest = (k, jpg.tobytes())
                self.frame_times.append(t_k)
                self.stats.frames += 1
                self.stats.late_s.append(max(0.0, self.clock() - due))
                self._cond.notify_all()
            k += 1

    def _serve(self, wfile) -> None:
        """Write the newest frame to one client whenever a new one is out (frames it misses are not queued)."""
        sent = -1
        while not self._stop.is_set():
            with self._cond:
                self._cond.wait_for(lambda: self._stop.is_set() or (self._latest is not None and self._latest[0] != sent),
                                    timeout=1.0)
                if self._stop.is_set() or self._latest is None or self._latest[0] == sent:
                    continue
                sent, jpg = self._latest
            try:
                wfile.write(
                    f"--{BOUNDARY}\r\nContent-Type: image/jpeg\r\nContent-Length: {len(jpg)}\r\n\r\n".encode() + jpg + b"\r\n"
                )
                wfile.flush()
            except (BrokenPipeError, ConnectionResetError, socket.error):
                return


_STAMP_BITS = 24
_STAMP_CELL_PX = 4


def write_stamp(frame: np.ndarray, index: int) -> None:
    """Write index (24 bits) as black/white 4×4 px cells along the bottom-left edge of the frame, in place."""
    h = frame.shape[0]
    for b in range(_STAMP_BITS):
        x = b * _STAMP_CELL_PX
        frame[h - _STAMP_CELL_PX : h, x : x + _STAMP_CELL_PX] = 255 if (index >> b) & 1 else 0


def read_stamp(frame: np.ndarray) -> int:
    """The frame index written by :func:`write_stamp` (survives JPEG compression)."""
    h = frame.shape[0]
    c = _STAMP_CELL_PX
    value = 0
    for b in range(_STAMP_BITS):
        cell = frame[h - c + 1 : h - 1, b * c + 1 : (b + 1) * c - 1]
        if float(cell.mean()) > 127.0:
            value |= 1 << b
    return value


class CameraProcess:
    """A :class:`CameraServer` in its own process (forked), as a real camera is its own device: its rendering does
    not compete with the reader for Python's interpreter lock. ``url`` and ``t_start`` (on the shared monotonic
    clock) are known once :meth:`start` returns; :meth:`stop` ends the process."""

    def __init__(self, scene: Scene, config: CameraConfig | None = None) -> None:
        self.scene = scene
        self.config = config or CameraConfig()
        self.geometry = self.config.geometry()
        self.url = ""
        self.t_start = math.nan
        self._proc = None
        self._conn = None

    def start(self, timeout: float = 10.0) -> "CameraProcess":
        import multiprocessing as mp

        ctx = mp.get_context("fork")
        parent, child = ctx.Pipe()
        self._proc = ctx.Process(target=_camera_child, args=(self.scene, self.config, child), daemon=True)
        self._proc.start()
        if not parent.poll(timeout):
            self.stop()
            raise RuntimeError("the simulated camera did not start")
        self.url, self.t_start = parent.recv()
        self._conn = parent
        return self

    def stop(self) -> None:
        if self._conn is not None:
            try:
                self._conn.send("stop")
            except (BrokenPipeError, OSError):
                pass
        if self._proc is not None:
            self._proc.join(timeout=3.0)
            if self._proc.is_alive():
                self._proc.terminate()
                self._proc.join(timeout=2.0)
        self._proc = self._conn = None

    def __enter__(self) -> "CameraProcess":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()


def _camera_child(scene: Scene, config: CameraConfig, conn) -> None:  # noqa: ANN001
    server = CameraServer(scene, config).start()
    conn.send((server.url, server.t_start))
    try:
        conn.recv()  # until told to stop (or the parent is gone)
    except EOFError:
        pass
    finally:
        server.stop()
