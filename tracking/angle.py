"""The string angle from the ball and pivot positions in the image (or in a metric plane)."""

from __future__ import annotations

import numpy as np


def string_angle(ball_uv: np.ndarray, pivot_uv: np.ndarray) -> np.ndarray:
    """θ [rad] from the downward vertical, positive toward +u: atan2(u_ball − u_pivot, v_ball − v_pivot).

    Image v points down, so a ball hanging straight below the pivot has θ = 0. Arrays (n, 2) or (2,);
    NaN in, NaN out.
    """
    b = np.asarray(ball_uv, dtype=float)
    p = np.asarray(pivot_uv, dtype=float)
    d = b - p
    return np.arctan2(d[..., 0], d[..., 1])


def plane_axes(H: np.ndarray, near_uv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(down, right) unit vectors in a metric plane seen through homography H (undistorted px → plane m).

    Down is the plane axis (±x or ±y of the board) closest to the image's downward direction at near_uv
    [px], right the perpendicular axis pointing to the image's right: θ in the plane is measured from the
    board's axis, so the board must lie with its edges level and plumb.
    """
    from .calibration import apply_homography

    p = np.asarray(near_uv, float).reshape(1, 2)
    a, below, right = (apply_homography(H, p + d)[0] for d in ((0.0, 0.0), (0.0, 10.0), (10.0, 0.0)))
    axes = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]])
    down = axes[int(np.argmax(axes @ (below - a)))]
    side = np.array([-down[1], down[0]])
    if side @ (right - a) < 0:
        side = -side
    return down, side


def plane_string_angle(ball_xy: np.ndarray, pivot_xy: np.ndarray, down: np.ndarray, right: np.ndarray) -> np.ndarray:
    """θ [rad] in the plane of motion from ball and pivot plane coordinates [m] (n, 2) or (2,): from the down
    axis, positive toward the right axis (see :func:`plane_axes`). NaN in, NaN out."""
    d = np.asarray(ball_xy, dtype=float) - np.asarray(pivot_xy, dtype=float)
    return np.arctan2(d @ right, d @ down)
