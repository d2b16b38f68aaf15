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
import os
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

    Scene time t runs with the wall clock from :meth:`start` (t = clock() − start; a scene object with a
    ``started(t_start)`` method is told that clock reading before the first frame);
    frame k shows the scene at t_k = k / fps and leaves at start + t_k + exposure/2 + latency. ``frame_times`` keeps
    t_k of every frame served, so a test can pair the tracker's results with the truth.
    """

    def __init__(
        self,
        scene: Scene,
        config: CameraConfig | None = None,
        host: str = "127.0.0.1",
        port: int = 0,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
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
        self._plates: list[np.ndarray] = []  # the backdrop with each noise field, blurred
        self._plates_of: np.ndarray | None = None

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
        started = getattr(self.scene, "started", None)
        if started is not None:  # a scene on the shared clock learns where its time 0 is
            started(self.t_start)
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

    def render(
        self, t: float, rng: np.random.Generator | None = None, background: np.ndarray | None = None
    ) -> np.ndarray:
        """The BGR frame showing the scene at time t [s] (the exposure centred on t): the backdrop, the flange, string
        and ball drawn on it, sensor noise (a bank of 8 fields drawn once: drawing a field costs ≈ 9 ms at VGA) and a
        slight blur. The backdrop with each noise field is blurred once; per frame only the region of the drawing is
        (the blur is local: the frame is the same as blurring it whole)."""
        import cv2

        from tracking.synthetic import draw_pendulum, lab_background

        c = self.config
        g = self.geometry
        bg = background if background is not None else lab_background(c.size, c.seed)
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
        noise = None
        if c.noise_std > 0:
            if self._noise is None or self._plates_of is not bg:
                gen = rng or np.random.default_rng(c.seed)
                self._noise = self._noise or [np.round(gen.normal(0.0, c.noise_std, bg.shape)).astype(np.int16)
                                              for _ in range(8)]  # fmt: skip
                self._plates = [cv2.GaussianBlur(cv2.add(bg, n, dtype=cv2.CV_8U), (0, 0), 0.5) for n in self._noise]
                self._plates_of = bg
            self._noise_k = (self._noise_k + 1) % len(self._noise)
            noise = self._noise[self._noise_k]
            out = self._plates[self._noise_k].copy()
        else:
            out = cv2.GaussianBlur(bg, (0, 0), 0.5)
        if not (np.all(np.isfinite(uv)) and np.all(np.isfinite(pivot_uv)) and depth > 0):
            return out
        r_px = float(g.camera_matrix[0, 0]) * c.ball_radius_m / depth
        h, w = bg.shape[:2]  # the region drawn in (the flange: 28 px either side, 70 px above the pivot), padded
        pad = 4
        x0 = int(max(0, min(uv[:, 0].min() - r_px, pivot_uv[0] - 40) - pad))
        x1 = int(min(w, max(uv[:, 0].max() + r_px, pivot_uv[0] + 40) + pad + 1))
        y0 = int(max(0, min(uv[:, 1].min() - r_px, pivot_uv[1] - 82) - pad))
        y1 = int(min(h, max(uv[:, 1].max() + r_px, pivot_uv[1] + 12) + pad + 1))
        if x1 - x0 <= 2 * pad or y1 - y0 <= 2 * pad:
            return out
        # drawn in that region only, with a margin the blur reads from (its kernel reaches 2 px at σ = 0.5)
        mx0, my0, mx1, my1 = max(0, x0 - pad), max(0, y0 - pad), min(w, x1 + pad), min(h, y1 + pad)
        part = bg[my0:my1, mx0:mx1].copy()
        shift = np.array([mx0, my0], float)
        draw_pendulum(part, pivot_uv - shift, uv - shift, r_px, c.ball_bgr, c.pivot_marker)
        if noise is not None:
            part = cv2.add(part, noise[my0:my1, mx0:mx1], dtype=cv2.CV_8U)
        part = cv2.GaussianBlur(part, (0, 0), 0.5)
        out[y0:y1, x0:x1] = part[y0 - my0 : y1 - my0, x0 - mx0 : x1 - mx0]
        return out

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
                self._cond.wait_for(
                    lambda: self._stop.is_set() or (self._latest is not None and self._latest[0] != sent), timeout=1.0
                )
                if self._stop.is_set() or self._latest is None or self._latest[0] == sent:
                    continue
                sent, jpg = self._latest
            try:
                wfile.write(
                    f"--{BOUNDARY}\r\nContent-Type: image/jpeg\r\nContent-Length: {len(jpg)}\r\n\r\n".encode()
                    + jpg
                    + b"\r\n"
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
    clock) are known once :meth:`start` returns; :meth:`stop` ends the process, as does the end of the process that
    started it. ``stop_after_s`` [s]: the camera stops streaming that long after its start — or after the scene's
    ``live_since`` [s, monotonic] when it has that attribute (None until it is live) — a failure drill.

    A plain ``os.fork`` (not multiprocessing): a daemonic process — the FRI simulator's — may start it too."""

    def __init__(self, scene: Scene, config: CameraConfig | None = None, stop_after_s: float | None = None,
                 niceness: int = 0) -> None:  # fmt: skip
        self.scene = scene
        self.config = config or CameraConfig()
        self.stop_after_s = stop_after_s
        self.niceness = niceness  # the camera process's priority lowered by this (a busy PC: others keep their pace)
        self.geometry = self.config.geometry()
        self.url = ""
        self.t_start = math.nan
        self._pid: int | None = None

    def start(self, timeout: float = 10.0) -> "CameraProcess":
        import select
        import signal

        r, w = os.pipe()
        parent = os.getpid()
        pid = os.fork()
        if pid == 0:  # the camera
            code = 1
            try:
                os.close(r)
                signal.signal(signal.SIGTERM, signal.SIG_DFL)
                signal.signal(signal.SIGINT, signal.SIG_IGN)  # its starter decides when it stops
                if self.niceness:
                    os.nice(self.niceness)
                _camera_child(self.scene, self.config, w, self.stop_after_s, parent)
                code = 0
            finally:
                os._exit(code)
        os.close(w)
        self._pid = pid
        try:
            ready, _, _ = select.select([r], [], [], timeout)
            line = os.read(r, 4096).decode() if ready else ""
        finally:
            os.close(r)
        if not line.strip():
            self.stop()
            raise RuntimeError("the simulated camera did not start")
        url, t_start = line.split()
        self.url, self.t_start = url, float(t_start)
        return self

    def stop(self) -> None:
        import signal

        pid, self._pid = self._pid, None
        if pid is None:
            return
        try:
            os.kill(pid, signal.SIGTERM)
        except ProcessLookupError:
            pass
        deadline = time.monotonic() + 3.0
        while True:
            try:
                done, _ = os.waitpid(pid, os.WNOHANG)
            except ChildProcessError:
                return
            if done or time.monotonic() > deadline:
                break
            time.sleep(0.01)
        if not done:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)

    def __enter__(self) -> "CameraProcess":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()


def _camera_child(scene: Scene, config: CameraConfig, out: int, stop_after_s: float | None, parent: int) -> None:
    """Serve until SIGTERM or the parent is gone; tell the parent the URL and t_start on the pipe ``out``."""
    server = CameraServer(scene, config).start()
    os.write(out, f"{server.url} {server.t_start!r}\n".encode())
    os.close(out)
    while os.getppid() == parent:
        time.sleep(0.05)
        since = getattr(scene, "live_since", None)  # a scene fed by a simulator counts from its first cycle
        since = server.t_start if since is None and not hasattr(scene, "live_since") else since
        if stop_after_s is not None and since is not None and server.clock() - since >= stop_after_s:
            server.stop()
            stop_after_s = None
    server.stop()
