"""Synthetic pendulum videos with known ground truth: a red ball on a string hanging from a (moving) pivot.

Used to measure the tracker (tests, benchmarks) and to render a simulated run as a video (the demo).
The ball is an anti-aliased, shaded disc with motion blur over the exposure; the frame gets defocus blur,
sensor noise and lossy compression (mp4v by default), and optionally red distractors (a box and a cable)
that a tracker must not take for the ball. θ is measured from the downward vertical, positive toward +u
(image x to the right): ball = pivot + L·(sin θ, cos θ) with image v pointing down.

Harder footage for robustness checks: a static red disc (``Distractor("disc", ...)``), dark early frames
(``gain``), foreground objects drawn over the ball (``foreground``: an occluding rod, a skin-coloured hand
beside an orange ball), long exposures at 30 or 60 fps (``exposure``), and a camera that sees the plane of
motion obliquely (``plane_to_image``: the pendulum lives in a plane whose coordinates are "plane pixels",
mapped to the image by a homography; θ is then measured in that plane).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Literal, Sequence

import numpy as np

from .calibration import apply_homography
from .video import VideoSink

BALL_BGR = (35, 30, 205)  # a saturated red (OpenCV hue ≈ 178)
MARKER_BGR = {"green": (60, 170, 40), "blue": (200, 90, 30), "yellow": (30, 200, 220), "red": BALL_BGR}
ORANGE_BGR = (20, 110, 235)  # an orange ball (OpenCV hue ≈ 12)
SKIN_BGR = (120, 150, 200)  # a light skin tone (OpenCV hue ≈ 11, saturation ≈ 100: at the orange band's edge)
ROD_BGR = (70, 70, 75)  # a dark grey rod

Foreground = Callable[[np.ndarray, float, np.ndarray], None]  # draw(frame, t [s], ball centre (2,) [px]) in place


@dataclass(frozen=True)
class Distractor:
    """An object of the ball's colour that is not the ball [px]: ``box`` (points = two opposite corners),
    ``label`` (a box with lines of white text), ``cable`` (polyline), ``disc`` (points = its centre, radius_px:
    its radius; as round as the ball) or ``tool`` (a screwdriver: points = the handle's centre, radius_px = half
    its length, an elongated rounded handle and a grey shaft, turned by angle_deg)."""

    kind: Literal["box", "label", "cable", "disc", "tool"]
    points: np.ndarray
    thickness_px: int = 5  # cable width [px]
    radius_px: float = 8.0  # disc radius, half the tool handle's length [px]
    bgr: tuple[int, int, int] = (35, 30, 205)  # its colour (the red ball's by default)
    angle_deg: float = 0.0  # tool: direction of the shaft from the image's +u axis [deg]


@dataclass(frozen=True)
class GroundTruth:
    """What was drawn in every frame: time [s], ball and pivot centres [px], θ [rad]."""

    t: np.ndarray  # (n,) frame times [s]
    ball_uv: np.ndarray  # (n, 2) ball centre at the frame time [px]
    pivot_uv: np.ndarray  # (n, 2) pivot [px]
    theta: np.ndarray  # (n,) string angle from the downward vertical, + toward +u [rad]
    ball_radius_px: float
    string_px: float
    size: tuple[int, int]  # (width, height) [px]
    fps: float  # [1/s]
    distractors: tuple[Distractor, ...] = field(default=())

    @property
    def in_frame(self) -> np.ndarray:
        """(n,) bool: the whole ball lies inside the image."""
        w, h = self.size
        r = self.ball_radius_px
        u, v = self.ball_uv[:, 0], self.ball_uv[:, 1]
        return (u - r >= 0) & (u + r <= w - 1) & (v - r >= 0) & (v + r <= h - 1)


def _background(size: tuple[int, int], rng: np.random.Generator) -> np.ndarray:
    """A lab-like backdrop: a light wall with a vertical gradient, low-frequency texture and a darker table."""
    import cv2

    w, h = size
    yy = np.linspace(0.0, 1.0, h, dtype=np.float32)[:, None]
    base = 175.0 - 40.0 * yy  # brighter at the top
    tex = cv2.resize(
        rng.normal(0.0, 10.0, (h // 40 + 2, w // 40 + 2)).astype(np.float32), (w, h), interpolation=cv2.INTER_CUBIC
    )
    gray = np.clip(base + tex, 0, 255)
    bg = np.stack([gray * 0.97, gray * 0.99, gray], axis=2)  # slightly warm white
    table = int(h * 0.9)
    bg[table:] = (70, 80, 95)  # brownish-grey table edge
    return bg.astype(np.uint8)


def _auto_distractors(size, ball_uv, pivot_uv, r) -> tuple[Distractor, ...]:
    """A red box and a red cable placed clear of the ball's and the string's path (when there is room)."""
    w, h = size
    pts = np.vstack([ball_uv, pivot_uv])
    lo = pts.min(axis=0) - 4 * r - 20
    hi = pts.max(axis=0) + 4 * r + 20
    bw, bh = 6 * r + 30, 4 * r + 20  # a box clearly larger than the ball
    out: list[Distractor] = []
    for x0 in (lo[0] - bw, hi[0]):  # left of the path, else right of it
        if 10 <= x0 and x0 + bw <= w - 10:
            y0 = min(max(hi[1] - bh, 10), h - bh - 10)
            out.append(Distractor("box", np.array([[x0, y0], [x0 + bw, y0 + bh]])))
            break
    # A cable hanging down the side of the frame opposite to the box, or along the bottom.
    side = w - 40.0 if not out or out[0].points[0, 0] < w / 2 else 40.0
    if side < lo[0] or side > hi[0]:
        y = np.linspace(0.1 * h, 0.85 * h, 40)
        x = side + 12.0 * np.sin(y / 37.0)
        out.append(Distractor("cable", np.column_stack([x, y])))
    return tuple(out)


def _draw_distractors(frame: np.ndarray, distractors: Sequence[Distractor]) -> None:
    import cv2

    for d in distractors:
        p = np.round(np.asarray(d.points) * 16).astype(np.int32)
        if d.kind in ("box", "label"):
            cv2.rectangle(frame, tuple(p[0]), tuple(p[1]), d.bgr, -1, cv2.LINE_AA, 4)
            if d.kind == "label":  # lines of white "text": dashes of random length
                (x0, y0), (x1, y1) = np.sort(np.asarray(d.points, float), axis=0)
                rng = np.random.default_rng(int(x0 * 7 + y0))
                rows = max(1, int((y1 - y0) // 9))
                for k in range(rows):
                    y = y0 + (k + 0.5) * (y1 - y0) / rows
                    x = x0 + 0.12 * (x1 - x0)
                    while x < x1 - 0.15 * (x1 - x0):
                        n = rng.uniform(0.05, 0.2) * (x1 - x0)
                        a, b = (int(x * 16), int(y * 16)), (int(min(x + n, x1 - 0.12 * (x1 - x0)) * 16), int(y * 16))
                        cv2.line(frame, a, b, (235, 235, 235), 2, cv2.LINE_AA, 4)
                        x += n + rng.uniform(0.02, 0.06) * (x1 - x0)
        elif d.kind == "disc":
            _draw_ball(frame, np.asarray(d.points, float).reshape(1, 2), d.radius_px, d.bgr)
        elif d.kind == "tool":
            c = np.asarray(d.points, float).reshape(2)
            L = float(d.radius_px)
            e = np.array([math.cos(math.radians(d.angle_deg)), math.sin(math.radians(d.angle_deg))])
            tip = c + e * 2.6 * L
            cv2.line(
                frame,
                tuple(int(x * 16) for x in c),
                tuple(int(x * 16) for x in tip),
                (150, 150, 155),
                max(2, int(0.25 * L)),
                cv2.LINE_AA,
                4,
            )
            cv2.ellipse(
                frame,
                (tuple(float(x) for x in c), (2.0 * L, 2.0 * L / 2.8), float(d.angle_deg)),
                d.bgr,
                -1,
                cv2.LINE_AA,
            )
        else:
            cv2.polylines(frame, [p.reshape(-1, 1, 2)], False, d.bgr, d.thickness_px, cv2.LINE_AA, 4)


def _disc_alpha(centres: np.ndarray, r: float, x0: int, y0: int, pw: int, ph: int) -> np.ndarray:
    """Coverage (0..1) of a disc of radius r [px] averaged over sub-exposure centres, on a patch at (x0, y0)."""
    xs = np.arange(x0, x0 + pw, dtype=np.float32)[None, :]
    ys = np.arange(y0, y0 + ph, dtype=np.float32)[:, None]
    acc = np.zeros((ph, pw), np.float32)
    for cx, cy in centres:
        d = np.sqrt((xs - cx) ** 2 + (ys - cy) ** 2)
        acc += np.clip(r + 0.5 - d, 0.0, 1.0)
    return acc / len(centres)


def _draw_ball(frame: np.ndarray, centres: np.ndarray, r: float, color: tuple[int, int, int]) -> None:
    """Alpha-blend a shaded, motion-blurred ball (centres: (m, 2) positions over the exposure)."""
    h, w = frame.shape[:2]
    x0 = int(math.floor(centres[:, 0].min() - r - 2))
    y0 = int(math.floor(centres[:, 1].min() - r - 2))
    x1 = int(math.ceil(centres[:, 0].max() + r + 3))
    y1 = int(math.ceil(centres[:, 1].max() + r + 3))
    cx0, cy0, cx1, cy1 = max(x0, 0), max(y0, 0), min(x1, w), min(y1, h)
    if cx1 <= cx0 or cy1 <= cy0:
        return
    alpha = _disc_alpha(centres, r, cx0, cy0, cx1 - cx0, cy1 - cy0)
    mid = centres.mean(axis=0)
    xs = np.arange(cx0, cx1, dtype=np.float32)[None, :] - mid[0]
    ys = np.arange(cy0, cy1, dtype=np.float32)[:, None] - mid[1]
    shade = 1.0 - 0.22 * np.clip((xs**2 + ys**2) / (r * r), 0.0, 1.0)  # darker toward the rim
    ball = shade[:, :, None] * np.asarray(color, np.float32)[None, None, :]
    patch = frame[cy0:cy1, cx0:cx1].astype(np.float32)
    a = alpha[:, :, None]
    frame[cy0:cy1, cx0:cx1] = np.clip(patch * (1.0 - a) + ball * a + 0.5, 0, 255).astype(np.uint8)


def draw_pendulum(
    frame: np.ndarray,
    pivot_uv: np.ndarray,
    ball_centres: np.ndarray,
    radius_px: float,
    ball_bgr: tuple[int, int, int] = BALL_BGR,
    pivot_marker: str | None = None,
    pivot_marker_radius_px: float = 9.0,
    ball_uv: np.ndarray | None = None,
    string_px: float | None = None,
) -> None:
    """Draw in place the robot's flange above the pivot [px], the pivot marker (a colour name, or None), the string
    to the ball (at ball_uv [px], default the middle of its centres; with string_px, its length [px], drawn sagging
    when the ball is nearer — a slack string) and the ball, motion-blurred over its centres during the exposure
    (m, 2) [px]."""
    import cv2

    p = np.asarray(pivot_uv, float)
    fx, fy = int(round(p[0])), int(round(p[1]))
    cv2.rectangle(frame, (fx - 28, fy - 70), (fx + 28, fy - 8), (90, 90, 95), -1, cv2.LINE_AA)
    if pivot_marker is not None:
        _draw_ball(frame, p[None, :], pivot_marker_radius_px, MARKER_BGR.get(pivot_marker, MARKER_BGR["green"]))
    c = np.asarray(ball_centres, float).reshape(-1, 2)
    b = c.mean(axis=0) if ball_uv is None else np.asarray(ball_uv, float)
    if string_px is None or np.hypot(*(b - p)) >= 0.99 * string_px:  # taut: a straight string
        cv2.line(
            frame, (int(p[0] * 16), int(p[1] * 16)), (int(b[0] * 16), int(b[1] * 16)), (45, 45, 50), 1, cv2.LINE_AA, 4
        )
    else:
        string = _string_polyline(p, b, string_px)
        cv2.polylines(
            frame, [np.round(string * 16).astype(np.int32).reshape(-1, 1, 2)], False, (45, 45, 50), 1, cv2.LINE_AA, 4
        )
    _draw_ball(frame, c, radius_px, ball_bgr)


def lab_background(size: tuple[int, int], seed: int = 0) -> np.ndarray:
    """The backdrop of the rendered videos (a light wall, a darker table), (h, w, 3) BGR."""
    return _background(size, np.random.default_rng(seed))


def _string_polyline(p: np.ndarray, b: np.ndarray, length: float, n: int = 12) -> np.ndarray:
    """(n, 2) points of a string of ``length`` [px] from p to b: straight when taut, sagging (a parabola hanging down
    by the excess length) when the ball is nearer."""
    d = float(np.hypot(*(b - p)))
    u = np.linspace(0.0, 1.0, n)[:, None]
    line = p[None, :] + u * (b - p)[None, :]
    if d >= 0.99 * length:
        return line
    sag = 0.5 * math.sqrt(max(length * length - d * d, 0.0))
    return line + np.array([0.0, 1.0]) * (4.0 * sag * u * (1.0 - u))


def rod_occluder(
    p0: Sequence[float], p1: Sequence[float], width_px: float = 6.0, bgr: tuple[int, int, int] = ROD_BGR
) -> Foreground:
    """A static rod from p0 to p1 [px] drawn in front of the ball (it hides the ball where they cross)."""
    import cv2

    a = tuple(int(round(c * 16)) for c in p0)
    b = tuple(int(round(c * 16)) for c in p1)

    def draw(frame: np.ndarray, t: float, ball: np.ndarray) -> None:
        cv2.line(frame, a, b, bgr, max(1, int(round(width_px))), cv2.LINE_AA, 4)

    return draw


def hand_beside_ball(
    offset_px: Sequence[float], release_s: float, scale_px: float = 14.0, bgr: tuple[int, int, int] = SKIN_BGR
) -> Foreground:
    """A skin-coloured hand (palm and four fingers) held at offset_px [px] from the ball until release_s [s],
    then lowered by 3.5 × scale_px over 0.15 s, out of the swing's way, and left in view."""
    import cv2

    state: dict[str, np.ndarray] = {}

    def draw(frame: np.ndarray, t: float, ball: np.ndarray) -> None:
        if t <= release_s or "at" not in state:
            state["at"] = np.asarray(ball, float) + np.asarray(offset_px, float)
        drop = 3.5 * scale_px * min(1.0, max(0.0, (t - release_s) / 0.15))  # the hand moves down out of the way
        c = state["at"] + (0.0, drop)
        s = scale_px
        centre = (int(c[0] * 16), int(c[1] * 16))
        cv2.ellipse(frame, centre, (int(1.1 * s * 16), int(1.3 * s * 16)), 0, 0, 360, bgr, -1, cv2.LINE_AA, 4)
        for k in range(4):  # fingers pointing up
            x = c[0] + (k - 1.5) * 0.55 * s
            p0 = (int(x * 16), int((c[1] - 0.9 * s) * 16))
            p1 = (int((x + 0.1 * (k - 1.5) * s) * 16), int((c[1] - (2.1 - 0.15 * abs(k - 1.5)) * s) * 16))
            cv2.line(frame, p0, p1, bgr, max(2, int(0.4 * s)), cv2.LINE_AA, 4)
        thumb0 = (int((c[0] + 1.0 * s) * 16), int((c[1] + 0.1 * s) * 16))
        thumb1 = (int((c[0] + 1.9 * s) * 16), int((c[1] - 0.6 * s) * 16))
        cv2.line(frame, thumb0, thumb1, bgr, max(2, int(0.45 * s)), cv2.LINE_AA, 4)

    return draw


def homography_scale(H: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """(n,) local linear scale sqrt|det J| of the homography H at points (n, 2) (image px per plane px)."""
    pts = np.asarray(pts, float).reshape(-1, 2)
    e = 0.5
    a, bx, by = apply_homography(H, pts), apply_homography(H, pts + (e, 0.0)), apply_homography(H, pts + (0.0, e))
    jx, jy = (bx - a) / e, (by - a) / e
    return np.sqrt(np.abs(jx[:, 0] * jy[:, 1] - jx[:, 1] * jy[:, 0]))


def tilted_view(
    size: tuple[int, int],
    focal_px: float,
    tilt_deg: Sequence[float],
    centre_plane_px: Sequence[float],
    distance_px: float | None = None,
) -> np.ndarray:
    """Homography plane px → image px of a pinhole camera (focal_px, principal point at the image centre) looking at
    the plane of motion from a direction tilted by (about x, about y, about the optical axis) [deg], aimed at
    centre_plane_px, at distance_px (plane px; default: focal_px, so the scale there is ≈ 1 image px per plane px)."""
    import cv2

    w, h = size
    K = np.array([[focal_px, 0.0, w / 2.0], [0.0, focal_px, h / 2.0], [0.0, 0.0, 1.0]])
    R, _ = cv2.Rodrigues(np.radians(np.asarray(tilt_deg, float)))
    d = float(distance_px if distance_px is not None else focal_px)
    c = np.array([centre_plane_px[0], centre_plane_px[1], 0.0])
    t = np.array([0.0, 0.0, d]) - R @ c  # the plane point c lies on the optical axis at depth d
    H = K @ np.column_stack([R[:, 0], R[:, 1], t])
    return H / H[2, 2]


class _Motion:
    """The drawn motion: θ(t) on a string from a (moving) pivot, or a given ball path, interpolated at any time
    (extrapolated along the end slopes: the exposure of the last frame runs past the last sample), in the plane of
    motion; ``to_image`` maps plane points through the homography H (None: the plane is the image)."""

    def __init__(self, t, theta, pivot_uv, string_px: float, ball_path, H) -> None:  # noqa: ANN001
        t = np.asarray(t, dtype=float)
        theta = np.asarray(theta, dtype=float)
        if t.ndim != 1 or theta.shape != t.shape or len(t) < 2 or np.any(np.diff(t) <= 0):
            raise ValueError("t and theta must be (n,) arrays with n ≥ 2 and t increasing")
        piv = np.asarray(pivot_uv, dtype=float)
        if piv.shape == (2,):
            piv = np.tile(piv, (len(t), 1))
        if piv.shape != (len(t), 2):
            raise ValueError(f"pivot_uv must be (2,) or ({len(t)}, 2), got {piv.shape}")
        self.t, self.theta, self.piv = t, theta, piv
        self.string_px = float(string_px)
        self.ball_path = ball_path
        self.H = None if H is None else np.asarray(H, float)

    def _interp(self, times: np.ndarray, y: np.ndarray) -> np.ndarray:
        t = self.t
        out = np.interp(times, t, y)
        for sel, i, j in ((times > t[-1], -2, -1), (times < t[0], 0, 1)):
            if np.any(sel):
                slope = (y[j] - y[i]) / (t[j] - t[i])
                out[sel] = y[j if i < 0 else i] + slope * (times[sel] - t[j if i < 0 else i])
        return out

    def state(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(θ [rad], pivot, ball) at the times [s], in the plane."""
        pv = np.column_stack([self._interp(times, self.piv[:, 0]), self._interp(times, self.piv[:, 1])])
        if self.ball_path is not None:
            bp = self.ball_path
            b = np.column_stack([self._interp(times, bp[:, 0]), self._interp(times, bp[:, 1])])
            return np.arctan2(b[:, 0] - pv[:, 0], b[:, 1] - pv[:, 1]), pv, b
        th = self._interp(times, self.theta)
        return th, pv, pv + self.string_px * np.column_stack([np.sin(th), np.cos(th)])

    def to_image(self, pts: np.ndarray) -> np.ndarray:
        return pts if self.H is None else apply_homography(self.H, pts)

    def exposed(self, tk: float, exposure: float, fps: float, r: float) -> tuple[np.ndarray, float]:
        """(the ball's sub-frame centres over the exposure of the frame at tk [s], centred on it, in the image (m, 2)
        [px]; its radius there [px]) — as many centres as keep them ≤ 0.5 px apart, at most 24 (motion blur)."""
        half = 0.5 * exposure / fps
        m = 1
        if exposure > 0:
            _, _, ends = self.state(np.array([tk - half, tk + half]))
            m = int(min(24, max(1, math.ceil(np.linalg.norm(ends[1] - ends[0]) / 0.5))))
        times = tk + (np.linspace(-half, half, m) if m > 1 else np.zeros(1))
        _, _, centres = self.state(times)
        rk = r if self.H is None else r * float(homography_scale(self.H, centres.mean(axis=0))[0])
        return self.to_image(centres), rk


@dataclass(frozen=True)
class _Camera:
    """What the camera does to a drawn frame: brightness gain(t), defocus blur σ [px], sensor noise σ [grey levels],
    JPEG compression at a quality (see :func:`render_pendulum_video`)."""

    gain: Callable[[float], float] | None
    defocus_px: float
    noise_std: float
    jpeg_quality: int | None
    noise: np.ndarray  # (h, w, 3) int16 buffers: the noise drawn
    frame16: np.ndarray  # ... and the frame with it

    def film(self, frame: np.ndarray, t: float) -> np.ndarray:
        """The frame at time t [s] (from the start) as the camera delivers it."""
        import cv2

        if self.gain is not None:
            g = float(self.gain(t))
            if g != 1.0:
                frame = np.clip(frame.astype(np.float32) * g + 0.5, 0, 255).astype(np.uint8)
        if self.defocus_px > 0:
            frame = cv2.GaussianBlur(frame, (0, 0), self.defocus_px)
        if self.noise_std > 0:
            cv2.randn(self.noise, 0, self.noise_std)
            np.add(frame, self.noise, out=self.frame16, dtype=np.int16)
            frame = np.clip(self.frame16, 0, 255).astype(np.uint8)
        if self.jpeg_quality is not None:  # blocky, chroma-subsampled frames like a low-bitrate stream
            ok, buf = cv2.imencode(".jpg", frame, [cv2.IMWRITE_JPEG_QUALITY, int(self.jpeg_quality)])
            frame = cv2.imdecode(buf, cv2.IMREAD_COLOR)
        return frame


def render_pendulum_video(
    path: str | Path,
    t: np.ndarray,
    theta: np.ndarray,
    pivot_uv: Sequence[float] | np.ndarray,
    string_px: float,
    ball_radius_px: float,
    size: tuple[int, int] = (1280, 720),
    fps: float = 60.0,
    *,
    exposure: float = 0.5,
    defocus_px: float = 0.6,
    noise_std: float = 2.5,
    codec: str = "mp4v",
    distractors: Sequence[Distractor] | Literal["auto"] | None = "auto",
    pivot_marker: str | None = None,
    pivot_marker_radius_px: float = 9.0,
    ball_bgr: tuple[int, int, int] = BALL_BGR,
    gain: Callable[[float], float] | None = None,
    foreground: Sequence[Foreground] = (),
    plane_to_image: np.ndarray | None = None,
    jpeg_quality: int | None = None,
    bitrate_kbps: float | None = None,
    ball_path: np.ndarray | None = None,
    seed: int = 0,
    progress: Callable[[int], None] | None = None,
    target: str | Path | None = None,
) -> GroundTruth:
    """Render a pendulum video from θ(t) and return what was drawn.

    t: (n,) increasing times [s] of the θ [rad] samples (θ from the downward vertical, + toward image +u);
    pivot_uv: fixed pivot (2,) or per-sample pivot track (n, 2) [px]; string_px: string length [px];
    ball_radius_px: ball radius [px]. Frames are rendered at k/fps for t[0] ≤ k/fps ≤ t[-1] (time starts at
    t[0]). exposure: shutter-open fraction of a frame (motion blur); defocus_px: Gaussian blur σ [px];
    noise_std: sensor noise σ [grey levels]; codec: FourCC for cv2.VideoWriter ('mp4v' lossy, 'MJPG', ...);
    distractors: 'auto' (a red box and a red cable clear of the ball's path), None or explicit ones;
    pivot_marker: colour name of a disc drawn on the pivot (a marker to track: track_video's pivot_color), or None;
    gain(t): brightness factor of the frame at time t [s] (e.g. dark early frames); foreground: drawers called
    on every frame after the ball (occluders, a hand); plane_to_image: homography from the plane of motion
    (pivot_uv, string_px and ball_radius_px are then in plane px) to the image (ball radius scaled by the
    local scale); the returned ball and pivot positions are in the image, θ in the plane; jpeg_quality:
    each frame JPEG-compressed at this quality (1–100) before encoding (heavy compression artifacts);
    bitrate_kbps: target bitrate [kbit/s] for codec 'h264', 'hevc', 'vp9' or 'av1' (written with PyAV); ball_path:
    (n, 2) ball centres [px] per sample instead of pivot + string_px·(sin θ, cos θ) — a ball that may fly on a slack
    string (drawn sagging when the ball is nearer than string_px); θ is then the direction pivot → ball; target: the
    name an OutputError reports (the final name when ``path`` is a temporary one).
    """
    import cv2

    motion = _Motion(t, theta, pivot_uv, string_px, ball_path, plane_to_image)
    w, h, r, t0 = int(size[0]), int(size[1]), float(ball_radius_px), motion.t[0]
    tf = t0 + np.arange(int(math.floor((motion.t[-1] - t0) * fps + 1e-9)) + 1) / fps
    th_f, piv_f, ball_f_plane = motion.state(tf)
    piv_f, ball_f = motion.to_image(piv_f), motion.to_image(ball_f_plane)
    dis = _auto_distractors((w, h), ball_f, piv_f, r) if isinstance(distractors, str) else tuple(distractors or ())
    bg = _background((w, h), np.random.default_rng(seed))
    _draw_distractors(bg, dis)
    cv2.setRNGSeed(seed)
    buffers = (np.empty((h, w, 3), np.int16), np.empty((h, w, 3), np.int16))
    camera = _Camera(gain, defocus_px, noise_std, jpeg_quality, *buffers)
    slack_px = None if ball_path is None else motion.string_px
    with VideoSink(path, codec, fps, (w, h), bitrate_kbps, target=target) as writer:
        for k in range(len(tf)):
            frame = bg.copy()
            centres, rk = motion.exposed(tf[k], exposure, fps, r)
            draw_pendulum(frame, piv_f[k], centres, rk, ball_bgr, pivot_marker, pivot_marker_radius_px, ball_f[k],
                          slack_px)  # fmt: skip
            for draw in foreground:
                draw(frame, float(tf[k] - t0), ball_f[k])
            writer.write(camera.film(frame, float(tf[k] - t0)))
            if progress is not None:
                progress(k + 1)
    scale = 1.0 if motion.H is None else float(np.median(homography_scale(motion.H, ball_f_plane)))
    return GroundTruth(tf - t0, ball_f, piv_f, th_f, r * scale, motion.string_px, (w, h), float(fps), dis)


def swing_up(
    duration_s: float, max_deg: float = 150.0, period_s: float = 1.0, rate_hz: float = 1000.0
) -> tuple[np.ndarray, np.ndarray]:
    """A test signal like a pumped swing-up: θ(t) [rad] oscillating with period_s [s], its amplitude growing
    linearly from 0 to max_deg [deg] over the first half of duration_s [s], then held (at 150° and 1 s a 25 cm
    string moves the ball at ≈ 4 m/s)."""
    t = np.arange(int(round(duration_s * rate_hz)) + 1) / rate_hz
    return t, np.radians(max_deg) * np.minimum(1.0, 2.0 * t / t[-1]) * np.sin(2 * np.pi * t / period_s)


def _normalised_rays(K: np.ndarray, D: np.ndarray, w: int, h: int) -> np.ndarray:
    """(h, w, 3) normalised camera rays (x, y, 1) of the pixel centres of a camera with distortion D.

    The lens model is inverted exactly (iterated undistortPoints) on a coarse grid and interpolated with
    bicubic splines (the distortion is smooth, so the interpolation error is far below 0.01 px).
    """
    from scipy.interpolate import RectBivariateSpline

    from .calibration import undistort_exact

    step = 8.0
    gx = np.arange(-2 * step, w + 2 * step, step)
    gy = np.arange(-2 * step, h + 2 * step, step)
    grid = np.stack(np.meshgrid(gx, gy), axis=-1).reshape(-1, 1, 2)
    norm = undistort_exact(grid, K, D).reshape(len(gy), len(gx), 2)
    xs, ys = np.arange(w, dtype=float), np.arange(h, dtype=float)
    nx = RectBivariateSpline(gy, gx, norm[:, :, 0])(ys, xs)
    ny = RectBivariateSpline(gy, gx, norm[:, :, 1])(ys, xs)
    return np.stack([nx, ny, np.ones_like(nx)], axis=-1)


def _ramp(X: np.ndarray) -> np.ndarray:
    """±1 square parity along one board axis, ramped linearly over one pixel across each grid line."""
    gy, gx = np.gradient(X)
    per_px = np.maximum(np.hypot(gx, gy), 1e-9)  # board units per pixel
    edge_px = np.abs(X - np.round(X)) / per_px  # distance to the nearest grid line [px]
    parity = np.where(np.floor(X) % 2 == 0, 1.0, -1.0)
    return parity * np.minimum(1.0, 2.0 * edge_px)


def render_board_views(
    camera_matrix: np.ndarray,
    dist_coeffs: np.ndarray,
    poses: Sequence[tuple[np.ndarray, np.ndarray]],
    board: tuple[int, int] = (9, 6),
    square_m: float = 0.025,
    size: tuple[int, int] = (640, 480),
    noise_std: float = 1.0,
    seed: int = 0,
) -> list[np.ndarray]:
    """Grey images of a checkerboard seen by a camera with lens distortion, one per pose.

    poses: (rvec (3,), tvec (3,) [m]) of the board in the camera frame (OpenCV convention); board: inner
    corners (cols, rows), whose first corner is the board origin; the board has one more square per side
    and a white margin of one square. Square edges are anti-aliased over one pixel; noise_std [grey levels].
    The inner corners lie where cv2.projectPoints puts them.
    """
    import cv2

    w, h = size
    rays = _normalised_rays(np.asarray(camera_matrix, float), np.asarray(dist_coeffs, float), w, h)
    cols, rows = board
    rng = np.random.default_rng(seed)
    images = []
    for rvec, tvec in poses:
        R, _ = cv2.Rodrigues(np.asarray(rvec, float))
        Hn = np.column_stack([R[:, 0], R[:, 1], np.asarray(tvec, float).ravel()])  # board (X, Y, 1) → ray
        to_squares = np.diag([1.0 / square_m, 1.0 / square_m, 1.0]) @ np.linalg.inv(Hn)
        p = rays @ to_squares.T
        front = p[..., 2] > 0
        X, Y = p[..., 0] / p[..., 2], p[..., 1] / p[..., 2]
        on_squares = (X >= -1) & (X < cols) & (Y >= -1) & (Y < rows) & front
        on_board = (X >= -2) & (X < cols + 1) & (Y >= -2) & (Y < rows + 1) & front
        img = np.where(on_board, 235.0, 90.0)  # white margin on a grey background
        checker = _ramp(X) * _ramp(Y)  # +1 black, −1 white
        img = np.where(on_squares, 127.5 - 107.5 * checker, img)
        img += noise_std * rng.standard_normal(img.shape)
        images.append(np.clip(img + 0.5, 0, 255).astype(np.uint8))
    return images
