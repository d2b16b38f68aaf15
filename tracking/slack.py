"""A slack string in a track: the ball nearer to the pivot than the string's length, where a string angle means nothing.

While the string is taut the ball–pivot distance is the string's length in the image (its high percentile over the
track, the ball being taut for part of any run that swings it); frames whose distance falls short of it by more
than a tolerance are slack: the ball flies free (or lies in the cup), its position is still measured, its θ is not.
The default tolerance (30 %) keeps a taut string seen obliquely (foreshortened by up to ≈ 25 % in the project's
tilted-camera case) taut; a ball flying in toward the pivot passes it early in its flight.
"""

from __future__ import annotations

import numpy as np

STRING_PERCENTILE = 90.0  # the string length is this percentile of the ball–pivot distances [%]


def string_length_px(distance: np.ndarray) -> float:
    """The taut string's length [px] from the ball–pivot distances of a track (NaN where not measured)."""
    d = np.asarray(distance, dtype=float)
    d = d[np.isfinite(d)]
    return float(np.percentile(d, STRING_PERCENTILE)) if d.size else float("nan")


def slack_frames(
    ball_uv: np.ndarray, pivot_uv: np.ndarray, tolerance: float = 0.3, min_px: float = 3.0
) -> tuple[np.ndarray, np.ndarray, float]:
    """(slack mask (n,), ball–pivot distance (n,) [px], string length [px]): a frame is slack when the ball is nearer
    than (1 − tolerance)·length − min_px to the pivot. ``pivot_uv`` (n, 2) or (2,) [px]."""
    d = np.hypot(*(np.asarray(ball_uv, float) - np.asarray(pivot_uv, float)).T)
    length = string_length_px(d)
    with np.errstate(invalid="ignore"):
        slack = d < (1.0 - tolerance) * length - min_px
    return slack & np.isfinite(d), d, length
