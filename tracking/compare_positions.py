"""Model–experiment comparison of the ball's position where the string is slack (the cup-and-ball flight).

The model gives the ball's position relative to the string's anchor [m] and its phase; the track gives the ball and
the pivot marker in the image [px]. The image scale is the tracked string length over the model's (both taut), the
image u axis is the model's lateral axis and v points down (``flip`` mirrors u); the time lag is the one the angle
comparison found (track time = model time + lag). Pure functions on arrays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class PositionComparison:
    """Ball position in the model's flight against the track: errors [m] over the compared frames."""

    px_per_m: float  # image scale used [px/m]
    frames: int  # track frames compared (the model slack there, the ball found)
    rms_m: float  # RMS distance between tracked and modelled ball [m] (relative to the anchor)
    max_m: float  # largest of those distances [m]
    t: np.ndarray  # (m,) track times compared [s]
    model: np.ndarray  # (m, 2) modelled (lateral, up) [m]
    measured: np.ndarray  # (m, 2) tracked (lateral, up) [m]


def compare_positions(
    t_model: np.ndarray,
    rel_model: np.ndarray,
    slack_model: np.ndarray,
    taut_length_m: float,
    t_track: np.ndarray,
    rel_track_px: np.ndarray,
    string_px: float,
    lag_s: float,
    flip: bool = False,
) -> PositionComparison:
    """Compare over the track frames at which the model's ball is slack.

    rel_model (n, 2): ball − anchor in the model's swing plane (lateral, up) [m]; slack_model (n,) bool;
    taut_length_m: the model's string length [m]; rel_track_px (m, 2): ball − pivot in the image (u, v) [px];
    string_px: the tracked string length [px].
    """
    scale = string_px / taut_length_m
    tm = np.asarray(t_track, float) - lag_s
    inside = (tm >= t_model[0]) & (tm <= t_model[-1])
    k = np.clip(np.searchsorted(t_model, tm), 1, len(t_model) - 1)
    near = np.where(np.abs(t_model[k] - tm) < np.abs(t_model[k - 1] - tm), k, k - 1)
    use = inside & np.asarray(slack_model, bool)[near] & np.all(np.isfinite(rel_track_px), axis=1)
    model = np.column_stack(
        [np.interp(tm[use], t_model, rel_model[:, 0]), np.interp(tm[use], t_model, rel_model[:, 1])]
    )
    sign = -1.0 if flip else 1.0
    measured = np.column_stack([sign * rel_track_px[use, 0], -rel_track_px[use, 1]]) / scale
    err = np.hypot(*(measured - model).T) if use.any() else np.empty(0)
    return PositionComparison(
        px_per_m=float(scale),
        frames=int(use.sum()),
        rms_m=float(np.sqrt(np.mean(err**2))) if err.size else float("nan"),
        max_m=float(err.max()) if err.size else float("nan"),
        t=np.asarray(t_track, float)[use],
        model=model,
        measured=measured,
    )
