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
