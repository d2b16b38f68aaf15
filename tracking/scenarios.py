"""Named hard cases for the tracker, rendered as small or large videos with ground truth (tests, benchmarks).

Each scenario renders one video with :func:`tracking.synthetic.render_pendulum_video` and says how to track
it (keyword arguments of :func:`tracking.pipeline.track_video`) and which frames count (the ball visible).
Geometry scales with the frame height, so the same scenario is a 320x180 test clip or a 1280x720 benchmark.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from .calibration import CameraCalibration, PlaneCalibration
from .color import color_spec
from .tracker import TrackerOptions
from .synthetic import (
    ORANGE_BGR,
    Distractor,
    GroundTruth,
    hand_beside_ball,
    render_pendulum_video,
    rod_occluder,
    swing_up,
    tilted_view,
)


@dataclass(frozen=True)
class Scenario:
    """A rendered case: ground truth, track_video keyword arguments, frames that count, adversarial flag."""

    name: str
    path: Path
    truth: GroundTruth
    track_kwargs: dict
    counted: np.ndarray  # (n,) bool: frames where the ball is visible enough that it must be found
    adversarial: bool = False  # beyond the stated goals (reported, not required)
    notes: str = ""
    time_scale: float = 1.0  # true capture time = container time / time_scale (slow-motion videos)
    extra: dict = field(default_factory=dict)


def _swing(duration_s: float, amplitude_deg: float = 30.0, period_s: float = 1.0, lead_s: float = 0.0,
           held: bool = False):
    """A slowly decaying swing starting at lead_s [s]: from the bottom at full speed, or (held) released at
    rest from the amplitude, where it was held until then."""
    t = np.arange(int(round(duration_s * 1000)) + 1) / 1000.0
    s = np.clip(t - lead_s, 0.0, None)
    wave = np.cos if held else np.sin
    return t, np.radians(amplitude_deg) * np.exp(-0.1 * s) * wave(2 * np.pi * s / period_s)


def _geometry(size: tuple[int, int], pivot_y: float = 0.15, string: float = 0.6) -> tuple[tuple[float, float], float, float]:
    w, h = size
    return (w / 2.0, pivot_y * h), string * h, max(4.0, 0.017 * h)


def _visible(gt: GroundTruth) -> np.ndarray:
    return gt.in_frame


def _rod_clear(gt: GroundTruth, p0, p1, width_px: float) -> np.ndarray:
    """(n,) bool: at most a third of the ball's diameter is behind the rod."""
    a, b = np.asarray(p0, float), np.asarray(p1, float)
    ab = b - a
    s = np.clip(((gt.ball_uv - a) @ ab) / (ab @ ab), 0.0, 1.0)
    d = np.linalg.norm(a + s[:, None] * ab - gt.ball_uv, axis=1)
    return d > gt.ball_radius_px / 3.0 + width_px / 2.0


def plain(path: Path, size, duration_s: float, seed: int = 0) -> Scenario:
    piv, L, r = _geometry(size)
    t, th = _swing(duration_s)
    gt = render_pendulum_video(path, t, th, piv, L, r, size, 60.0, seed=seed)
    return Scenario("plain", path, gt, {"pivot_uv": piv}, _visible(gt))


def dark_start(path: Path, size, duration_s: float, seed: int = 1) -> Scenario:
    """The first 0.4 s are nearly black (auto-exposure settling), brightening until 0.7 s."""
    piv, L, r = _geometry(size)
    t, th = _swing(duration_s)
    gain = lambda tk: float(np.interp(tk, [0.0, 0.4, 0.7], [0.22, 0.22, 1.0]))  # noqa: E731
    gt = render_pendulum_video(path, t, th, piv, L, r, size, 60.0, gain=gain, seed=seed)
    counted = _visible(gt) & (gt.t >= 0.7)
    return Scenario("dark early frames", path, gt, {"pivot_uv": piv}, counted)


def red_disc(path: Path, size, duration_s: float, seed: int = 2) -> Scenario:
    """A static red disc as round as the ball, beside the swing (the ball starts at rest for 0.3 s)."""
    piv, L, r = _geometry(size)
    t, th = _swing(duration_s, lead_s=0.3)
    disc = Distractor("disc", np.array([piv[0] - L * math.sin(math.radians(50)), piv[1] + L * 0.85]), radius_px=r * 1.05)
    gt = render_pendulum_video(path, t, th, piv, L, r, size, 60.0, distractors=[disc], seed=seed)
    return Scenario("static red disc", path, gt, {"pivot_uv": piv}, _visible(gt))


def red_disc_start(path: Path, size, duration_s: float, seed: int = 3) -> Scenario:
    """The red disc again, no pivot given: the ball is named with its start point instead."""
    piv, L, r = _geometry(size)
    t, th = _swing(duration_s, lead_s=0.3)
    disc = Distractor("disc", np.array([piv[0] + L * 0.6, piv[1] + L * 0.8]), radius_px=r)
    gt = render_pendulum_video(path, t, th, piv, L, r, size, 60.0, distractors=[disc], seed=seed)
    start = tuple(float(c) for c in gt.ball_uv[0])
    return Scenario("static red disc, --start", path, gt, {"options": TrackerOptions(start_uv=start)}, _visible(gt))


def tilted(path: Path, size, duration_s: float, seed: int = 4) -> Scenario:
    """A camera looking at the plane of motion obliquely (25° and 30° off, rolled 4°), with a plane calibration
    (an exact pinhole camera; metres in the plane, y down)."""
    w, h = size
    piv, L, r = _geometry(size, pivot_y=0.2, string=0.5)
    focal = 1.1 * w
    H = tilted_view(size, focal, (25.0, -30.0, 4.0), (w / 2.0, 0.45 * h))
    K = np.array([[focal, 0.0, w / 2.0], [0.0, focal, h / 2.0], [0.0, 0.0, 1.0]])
    t, th = _swing(duration_s, amplitude_deg=35.0)
    gt = render_pendulum_video(path, t, th, piv, L, r, size, 60.0, plane_to_image=H, distractors=None, seed=seed)
    m_per_plane_px = 0.25 / L  # a 25 cm string
    to_m = np.diag([m_per_plane_px, m_per_plane_px, 1.0]) @ np.linalg.inv(H)
    cal = CameraCalibration(
        camera_matrix=K, dist_coeffs=np.zeros(5), image_size=(w, h), rms_px=0.0, board=(9, 6), square_m=0.025, views=0,
        plane=PlaneCalibration(to_m / to_m[2, 2], m_per_plane_px, np.zeros(3), np.zeros(3)),
    )
    pivot_image = tuple(float(c) for c in gt.pivot_uv[0])
    return Scenario("tilted camera + calibration", path, gt, {"pivot_uv": pivot_image, "calibration": cal}, _visible(gt),
                    extra={"metres_per_plane_px": m_per_plane_px})


def fast_swing_up(path: Path, size, duration_s: float, fps: float = 60.0, exposure: float = 0.5, seed: int = 5) -> Scenario:
    """A swing-up to ±150° (≈ 4 m/s on a 25 cm string) filmed at fps with the shutter open exposure of a frame."""
    piv, L, r = _geometry(size, pivot_y=0.45, string=0.4)
    t, th = swing_up(duration_s, 150.0, 1.0)
    gt = render_pendulum_video(path, t, th, piv, L, r, size, fps, exposure=exposure, seed=seed)
    name = f"swing-up ±150°, {fps:.0f} fps, 1/{fps / exposure:.0f} s"
    return Scenario(name, path, gt, {"pivot_uv": piv}, _visible(gt), adversarial=fps * 1.0 / exposure < 59.0)


def orange_hand(path: Path, size, duration_s: float, seed: int = 6) -> Scenario:
    """An orange ball held out at 30° by a skin-coloured hand beside it, released at 0.5 s; the hand stays in view."""
    piv, L, r = _geometry(size)
    t, th = _swing(duration_s, lead_s=0.5, held=True)
    hand = hand_beside_ball((3.2 * r, 0.4 * r), 0.5, scale_px=1.6 * r)
    gt = render_pendulum_video(path, t, th, piv, L, r, size, 60.0, ball_bgr=ORANGE_BGR, foreground=[hand], seed=seed)
    return Scenario("orange ball, skin-coloured hand", path, gt, {"pivot_uv": piv, "ball": color_spec("orange")}, _visible(gt))


def occluding_rod(path: Path, size, duration_s: float, seed: int = 7) -> Scenario:
    """A dark rod in front of the swing, crossing the ball's path."""
    w, h = size
    piv, L, r = _geometry(size)
    p0, p1 = (0.2 * w, 0.62 * h), (0.45 * w, 0.95 * h)
    width = max(3.0, 0.5 * r)
    t, th = _swing(duration_s, amplitude_deg=35.0)
    gt = render_pendulum_video(path, t, th, piv, L, r, size, 60.0, foreground=[rod_occluder(p0, p1, width)], seed=seed)
    return Scenario("occluding rod", path, gt, {"pivot_uv": piv}, _visible(gt) & _rod_clear(gt, p0, p1, width))


def moving_pivot(path: Path, size, duration_s: float, seed: int = 8) -> Scenario:
    """The pivot moves with the robot's flange and carries a green marker; red box and cable in view."""
    w, h = size
    _, L, r = _geometry(size, string=0.5)
    t, th = _swing(duration_s, amplitude_deg=25.0)
    pivot = np.column_stack([w * (0.35 + 0.3 * np.sin(np.pi * t / t[-1]) ** 2), np.full_like(t, 0.15 * h)])
    gt = render_pendulum_video(path, t, th, pivot, L, r, size, 60.0, pivot_marker="green", seed=seed)
    return Scenario("moving pivot, marker", path, gt, {"pivot_color": color_spec("green")}, _visible(gt))


def slow_motion(path: Path, size, duration_s: float, seed: int = 9) -> Scenario:
    """Filmed at 240 fps, stored as a 30 fps video (slow motion): --fps 240 gives the real times."""
    piv, L, r = _geometry(size)
    t, th = _swing(duration_s / 8.0 + 0.01, amplitude_deg=30.0, period_s=0.5)
    gt = render_pendulum_video(path, t * 8.0, th, piv, L, r, size, 30.0, exposure=0.1, seed=seed)
    return Scenario("slow motion, --fps 240", path, gt, {"pivot_uv": piv, "fps": 240.0}, _visible(gt), time_scale=8.0)


def compressed(path: Path, size, duration_s: float, seed: int = 10) -> Scenario:
    """Heavy compression (every frame JPEG quality 12, then mp4v) with a moving marked pivot, a fast swing."""
    w, h = size
    _, L, r = _geometry(size, string=0.5)
    t, th = _swing(duration_s, amplitude_deg=45.0, period_s=0.9)
    pivot = np.column_stack([w * (0.4 + 0.2 * np.sin(np.pi * t / t[-1]) ** 2), np.full_like(t, 0.15 * h)])
    gt = render_pendulum_video(path, t, th, pivot, L, r, size, 60.0, pivot_marker="green", jpeg_quality=12, seed=seed)
    return Scenario("heavy compression, moving marker", path, gt, {"pivot_color": color_spec("green")}, _visible(gt))


ALL: dict[str, Callable[..., Scenario]] = {
    "plain": plain,
    "dark_start": dark_start,
    "red_disc": red_disc,
    "red_disc_start": red_disc_start,
    "tilted": tilted,
    "swing_up_60": lambda p, s, d: fast_swing_up(p, s, d, fps=60.0, exposure=1.0),
    "swing_up_30_short": lambda p, s, d: fast_swing_up(p, s, d, fps=30.0, exposure=0.5),
    "swing_up_30_long": lambda p, s, d: fast_swing_up(p, s, d, fps=30.0, exposure=1.0),
    "orange_hand": orange_hand,
    "occluding_rod": occluding_rod,
    "moving_pivot": moving_pivot,
    "slow_motion": slow_motion,
    "compressed": compressed,
}


@dataclass(frozen=True)
class Outcome:
    """How a track did against the truth: found share of the counted frames, false fixes, errors."""

    found_percent: float  # [%] of the counted frames
    false_fixes: int  # fixes more than 5 px from the true centre
    centre_rms_px: float  # over correct fixes
    theta_rms_deg: float  # over correct fixes with θ (NaN without a pivot)


def score(sc: Scenario, track) -> Outcome:  # noqa: ANN001 (tracking.pipeline.Track)
    """Compare a track with the scenario's ground truth."""
    gt = sc.truth
    err = np.linalg.norm(track.uv - gt.ball_uv, axis=1)
    fixed = track.found
    false = fixed & (err > 5.0)
    good = fixed & ~false
    found = float(100.0 * np.mean(fixed[sc.counted])) if sc.counted.any() else math.nan
    rms = float(np.sqrt(np.mean(err[good] ** 2))) if good.any() else math.nan
    th = math.nan
    if track.theta is not None:
        ok = good & np.isfinite(track.theta)
        if ok.any():
            d = (track.theta[ok] - gt.theta[ok] + np.pi) % (2 * np.pi) - np.pi
            th = float(np.degrees(np.sqrt(np.mean(d**2))))
    return Outcome(found, int(false.sum()), rms, th)
