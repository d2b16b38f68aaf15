"""Where the camera is: a pinhole camera posed in the robot's base frame, and the ball's tilt from one view.

A single camera sees the ball's direction from the camera, not its depth. Knowing the pivot's position in the
base frame and the string length L, the ball lies where the pixel's ray meets the sphere of radius L about the
pivot: two points (in front of and behind the pivot as the camera sees it). The one that continues the previous
estimate is taken (at first: the one nearer to hanging straight down). The depth part of the tilt is then well
conditioned only when the camera looks at the pendulum from above or below: for a camera at elevation ε the two
points differ by ≈ 2·L·sin ε·(tilt away from the camera); seen exactly level (ε = 0) both hang alike and the
tilt toward the camera is not observable (:attr:`TiltEstimate.ambiguous`).

Conventions: base frame z up; OpenCV camera frame (x right, y down, z forward); tilt components as
:class:`planners.pendulum.PendulumRun`: θx = atan2(s_x, −s_z), θy = atan2(s_y, −s_z) for the string direction s.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from trajectories.errors import InputError


@dataclass(frozen=True)
class CameraGeometry:
    """Intrinsics (camera matrix [px], OpenCV distortion) and pose: rotation base → camera, centre [m] in the base."""

    camera_matrix: np.ndarray  # (3, 3) [px]
    dist_coeffs: np.ndarray  # (k,) OpenCV order
    rotation: np.ndarray  # (3, 3) R with x_cam = R (X_base − centre)
    centre: np.ndarray  # (3,) camera centre in the base frame [m]
    image_size: tuple[int, int]  # (width, height) [px]

    @classmethod
    def from_pose(
        cls, position, look_at, fov_deg: float, size: tuple[int, int], up=(0.0, 0.0, 1.0)
    ) -> "CameraGeometry":
        """A distortion-free camera at position [m] looking at look_at [m] with a horizontal field of view fov_deg
        [deg], image size (w, h) [px], the image's up toward the base's up."""
        c = np.asarray(position, float)
        forward = np.asarray(look_at, float) - c
        if not np.linalg.norm(forward) > 0:
            raise ValueError("the camera must look at a point other than its own position")
        forward /= np.linalg.norm(forward)
        right = np.cross(forward, np.asarray(up, float))
        if np.linalg.norm(right) < 1e-9:  # looking straight up or down: any right
            right = np.cross(forward, np.array([1.0, 0.0, 0.0]))
        right /= np.linalg.norm(right)
        down = np.cross(forward, right)
        w, h = int(size[0]), int(size[1])
        f = 0.5 * w / math.tan(math.radians(fov_deg) / 2.0)
        K = np.array([[f, 0.0, w / 2.0], [0.0, f, h / 2.0], [0.0, 0.0, 1.0]])
        return cls(K, np.zeros(5), np.vstack([right, down, forward]), c, (w, h))

    @property
    def elevation_deg(self) -> float:
        """Angle of the optical axis below the horizontal [deg] (positive looking down)."""
        return math.degrees(math.asin(float(np.clip(-self.rotation[2, 2], -1.0, 1.0))))

    def project(self, points: np.ndarray) -> np.ndarray:
        """(n, 2) pixels [px] of base-frame points (n, 3) [m] (with the lens distortion); NaN behind the camera."""
        import cv2

        X = np.atleast_2d(np.asarray(points, float))
        cam = (X - self.centre) @ self.rotation.T
        out = np.full((len(X), 2), np.nan)
        front = cam[:, 2] > 1e-9
        if front.any():
            px, _ = cv2.projectPoints(
                cam[front].reshape(-1, 1, 3), np.zeros(3), np.zeros(3), self.camera_matrix, self.dist_coeffs
            )
            out[front] = px.reshape(-1, 2)
        return out

    def depth(self, points: np.ndarray) -> np.ndarray:
        """(n,) distance along the optical axis [m] of base-frame points (n, 3)."""
        X = np.atleast_2d(np.asarray(points, float))
        return (X - self.centre) @ self.rotation[2]

    def ray(self, uv) -> np.ndarray:
        """Unit direction (3,) in the base frame of the ray through pixel uv [px]."""
        from .calibration import undistort_exact

        n = undistort_exact(np.asarray(uv, float).reshape(1, 1, 2), self.camera_matrix, self.dist_coeffs).reshape(2)
        d = self.rotation.T @ np.array([n[0], n[1], 1.0])
        return d / np.linalg.norm(d)


@dataclass(frozen=True)
class TiltEstimate:
    """The ball's string direction from one view: tilt components [rad], the chosen point [m], and whether the
    other intersection is too close to tell them apart."""

    theta_x: float  # [rad] toward base +x
    theta_y: float  # [rad] toward base +y
    ball: np.ndarray  # (3,) [m] in the base frame
    separation_m: float  # distance between the two candidate points [m] (0 when the ray only grazes the sphere)
    miss_m: float  # how far the ray passes outside the sphere [m] (0 when it meets it)

    @property
    def ambiguous(self) -> bool:
        """The two candidate points are within 5 mm: the depth part of the tilt is not observable here."""
        return self.separation_m < 0.005


def tilt_from_pixel(geometry: CameraGeometry, uv, pivot_m, string_m: float, previous_m=None) -> TiltEstimate:
    """Tilt of the string from the ball's pixel uv [px], the pivot [m] (base frame) and the string length [m].

    previous_m: the ball's previous estimate [m] (continuity picks between the ray's two meetings with the
    sphere); without it the point nearer to hanging straight down is taken. A ray that misses the sphere
    (pixel noise, a wrong length) gives the sphere's point closest to the ray.
    """
    d = geometry.ray(uv)
    c = geometry.centre
    p = np.asarray(pivot_m, float)
    L = float(string_m)
    oc = c - p
    b = float(d @ oc)
    disc = b * b - (float(oc @ oc) - L * L)
    if disc >= 0.0:
        root = math.sqrt(disc)
        points = [c + (-b - root) * d, c + (-b + root) * d]
        separation, miss = 2.0 * root, 0.0
    else:  # the closest point of the ray to the pivot, pushed out onto the sphere
        q = c - b * d
        miss = float(np.linalg.norm(q - p)) - L
        points = [p + L * (q - p) / max(float(np.linalg.norm(q - p)), 1e-12)]
        separation = 0.0
    if previous_m is not None:
        prev = np.asarray(previous_m, float)
        ball = min(points, key=lambda x: float(np.linalg.norm(x - prev)))
    else:
        ball = max(points, key=lambda x: float(-(x - p)[2]))  # nearer to hanging straight down
    s = (ball - p) / L
    return TiltEstimate(math.atan2(s[0], -s[2]), math.atan2(s[1], -s[2]), ball, separation, miss)


def string_direction(theta_x: float, theta_y: float) -> np.ndarray:
    """Unit string direction (3,) of the tilt components θx, θy [rad] (as planners.pendulum.direction_from_angles)."""
    s = np.array([math.tan(theta_x), math.tan(theta_y), -1.0])
    return s / np.linalg.norm(s)


def hanging_length(geometry: CameraGeometry, uv, pivot_m) -> tuple[float, float, float]:
    """Where a ball hanging straight down below the pivot [m] must be for the camera to see it at pixel uv [px]:
    (string length [m] — how far below the pivot the pixel's ray passes the vertical through it —, the ray's
    closest distance to that vertical [m], the angle between the ray and the vertical [rad]). The length is well
    conditioned when the ray crosses the vertical steeply (a camera looking straight down cannot tell it)."""
    d = geometry.ray(uv)
    w0 = geometry.centre - np.asarray(pivot_m, float)
    b = float(d[2])  # d · e for the vertical e = (0, 0, 1)
    denom = 1.0 - b * b
    angle = math.acos(min(1.0, abs(b)))
    if denom < 1e-9:
        return math.nan, math.nan, angle
    dd, ee = float(d @ w0), float(w0[2])
    s = (b * ee - dd) / denom  # along the ray
    t = (ee - b * dd) / denom  # along the vertical, from the pivot (up positive)
    gap = float(np.linalg.norm(w0 + s * d - np.array([0.0, 0.0, t])))
    return -t, gap, angle


@dataclass(frozen=True)
class SwayView:
    """How well one camera sees a pendulum's sway along a path (see :func:`sway_view`): the smallest image shift
    [px] a 1° tilt toward base +x and toward +y makes anywhere on the path and the samples where it is smallest,
    and the first sample where the ball is out of the image (or behind the camera), None if it never is."""

    px_per_deg: tuple[float, float]
    worst: tuple[int, int]
    outside: int | None


def sway_view(geometry: CameraGeometry, pivots_m, string_m: float, sway_rad=None, margin_px: float = 0.0) -> SwayView:
    """The view of a ball on a string of string_m [m] hanging from each of pivots_m (n, 3) [m], tilted by sway_rad
    (n, 2) [rad] (θx, θy; default hanging): the pixel shift of a 1° tilt toward +x and +y about that tilt, and
    whether the ball's centre stays margin_px [px] inside the image."""
    P = np.atleast_2d(np.asarray(pivots_m, float))
    S = np.zeros((len(P), 2)) if sway_rad is None else np.atleast_2d(np.asarray(sway_rad, float))
    step = math.radians(1.0)
    pts = []
    for p, (tx, ty) in zip(P, S):
        for dx, dy in ((0.0, 0.0), (step, 0.0), (0.0, step)):
            pts.append(p + string_m * string_direction(tx + dx, ty + dy))
    uv = geometry.project(np.array(pts)).reshape(len(P), 3, 2)
    shift = np.linalg.norm(uv[:, 1:] - uv[:, :1], axis=2)  # (n, 2) [px per degree]
    shift = np.where(np.isfinite(shift), shift, 0.0)
    w, h = geometry.image_size
    c = uv[:, 0]
    inside = np.isfinite(c).all(axis=1) & (c[:, 0] >= margin_px) & (c[:, 0] <= w - margin_px) & \
        (c[:, 1] >= margin_px) & (c[:, 1] <= h - margin_px)  # fmt: skip
    worst = (int(np.argmin(shift[:, 0])), int(np.argmin(shift[:, 1])))
    out = np.flatnonzero(~inside)
    return SwayView((float(shift[worst[0], 0]), float(shift[worst[1], 1])), worst, int(out[0]) if len(out) else None)


def camera_pose_for(
    pivots_m,
    string_m: float,
    sway_rad=None,
    fov_deg: float = 50.0,
    size: tuple[int, int] = (640, 480),
    elevation_deg: float = 30.0,
    azimuth_deg: float = 45.0,
    margin: float = 0.08,
) -> tuple[np.ndarray, np.ndarray]:
    """(position, look_at) [m] of a camera that sees the whole of a pendulum's path: it looks at the middle of the
    ball's positions (pivots_m (n, 3) [m], string_m [m], tilted by sway_rad (n, 2) [rad]) from elevation_deg above
    and azimuth_deg around from the line from the base's origin to that middle (both sway axes then show in the
    image), as close as keeps every position ``margin`` of the width inside the frame (fov_deg, size (w, h) [px])."""
    P = np.atleast_2d(np.asarray(pivots_m, float))
    S = np.zeros((len(P), 2)) if sway_rad is None else np.atleast_2d(np.asarray(sway_rad, float))
    balls = np.array([p + string_m * string_direction(tx, ty) for p, (tx, ty) in zip(P, S)])
    look = 0.5 * (balls.min(axis=0) + balls.max(axis=0))
    az = math.atan2(look[1], look[0]) + math.radians(azimuth_deg) if np.hypot(look[0], look[1]) > 1e-6 else \
        math.radians(azimuth_deg)  # fmt: skip
    el = math.radians(elevation_deg)
    away = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
    distance = 0.3
    while distance < 20.0:
        g = CameraGeometry.from_pose(look + distance * away, look, fov_deg, size)
        if sway_view(g, P, string_m, S, margin * size[0]).outside is None:
            break
        distance *= 1.05
    return look + distance * away, look


# ---------------------------------------------------------------- files


def geometry_to_dict(g: CameraGeometry) -> dict:
    return {
        "image_size": list(g.image_size),
        "camera_matrix": np.asarray(g.camera_matrix, float).tolist(),
        "dist_coeffs": np.asarray(g.dist_coeffs, float).tolist(),
        "rotation": np.asarray(g.rotation, float).tolist(),
        "centre_m": np.asarray(g.centre, float).tolist(),
    }


def save_geometry(path: str | Path, g: CameraGeometry, **extra) -> None:
    """Write the geometry as JSON (extra fields, e.g. pivot_m and string_m, alongside)."""
    d = geometry_to_dict(g)
    d.update(
        {
            k: (np.asarray(v, float).tolist() if isinstance(v, (np.ndarray, list, tuple)) else v)
            for k, v in extra.items()
        }
    )
    Path(path).write_text(json.dumps(d, indent=2) + "\n")


def load_geometry(path: str | Path) -> tuple[CameraGeometry, dict]:
    """(geometry, the whole JSON object) from a file written by :func:`save_geometry` (or by hand: image_size,
    camera_matrix, dist_coeffs, rotation, centre_m; or position_m, look_at_m, fov_deg, image_size)."""
    spath = str(path)
    try:
        d = json.loads(Path(path).read_text())
    except FileNotFoundError:
        raise InputError("file not found", file=spath) from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(f"not a camera geometry JSON: {exc}", file=spath) from None
    if not isinstance(d, dict):
        raise InputError("not a camera geometry object", file=spath)

    def arr(key: str, shape: tuple[int, ...] | None):
        if key not in d:
            raise InputError(f"missing field '{key}'", file=spath)
        try:
            a = np.asarray(d[key], float)
        except (TypeError, ValueError):
            raise InputError(f"field '{key}' is not numeric", file=spath) from None
        if (shape is not None and a.shape != shape) or not np.all(np.isfinite(a)):
            raise InputError(f"field '{key}' must be finite with shape {shape}", file=spath)
        return a

    size = arr("image_size", (2,))
    if "position_m" in d:
        g = CameraGeometry.from_pose(
            arr("position_m", (3,)), arr("look_at_m", (3,)), float(arr("fov_deg", ())), (int(size[0]), int(size[1]))
        )
    else:
        g = CameraGeometry(
            arr("camera_matrix", (3, 3)),
            arr("dist_coeffs", None).ravel(),
            arr("rotation", (3, 3)),
            arr("centre_m", (3,)),
            (int(size[0]), int(size[1])),
        )
    return g, d
