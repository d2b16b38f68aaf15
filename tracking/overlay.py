"""Drawing a frame's detection over the video frame (for the preview video): pure drawing on arrays."""

from __future__ import annotations

import math

import numpy as np

_BALL = (0, 255, 255)  # yellow circle around the ball (BGR)
_PIVOT = (255, 255, 0)  # cyan pivot
_STRING = (255, 255, 255)
_TEXT = (255, 255, 255)


def draw_overlay(
    frame: np.ndarray,
    t: float,
    ball_uv: tuple[float, float] | None,
    ball_radius_px: float | None,
    pivot_uv: tuple[float, float] | None,
    theta: float,
) -> np.ndarray:
    """Draw in place on a BGR frame: circle on the ball (or 'lost'), pivot, string line, θ [deg] and t [s]."""
    import cv2

    s = 16.0  # fixed-point drawing for sub-pixel positions

    def fp(p: tuple[float, float]) -> tuple[int, int]:
        return int(round(p[0] * s)), int(round(p[1] * s))

    if ball_uv is not None and pivot_uv is not None:
        cv2.line(frame, fp(pivot_uv), fp(ball_uv), _STRING, 1, cv2.LINE_AA, 4)
    if pivot_uv is not None:
        cv2.circle(frame, fp(pivot_uv), int(5 * s), _PIVOT, 2, cv2.LINE_AA, 4)
        cv2.drawMarker(frame, (int(pivot_uv[0]), int(pivot_uv[1])), _PIVOT, cv2.MARKER_CROSS, 10, 1)
    if ball_uv is not None:
        r = max(float(ball_radius_px or 5.0), 3.0) + 4.0
        cv2.circle(frame, fp(ball_uv), int(r * s), _BALL, 2, cv2.LINE_AA, 4)
        cv2.drawMarker(frame, (int(round(ball_uv[0])), int(round(ball_uv[1]))), _BALL, cv2.MARKER_CROSS, 6, 1)
    text = f"t {t:7.3f} s"
    if ball_uv is None:
        text += "   ball lost"
    elif math.isfinite(theta):
        text += f"   theta {math.degrees(theta):+7.2f} deg"
    cv2.putText(frame, text, (12, 30), cv2.FONT_HERSHEY_SIMPLEX, 0.8, (0, 0, 0), 4, cv2.LINE_AA)
    cv2.putText(frame, text, (12, 30), cv2.FONT_HERSHEY_SIMPLEX, 0.8, _TEXT, 1, cv2.LINE_AA)
    return frame


def draw_candidates(frame: np.ndarray, blobs: list) -> np.ndarray:  # list[tracking.detect.Blob]
    """Draw in place every ball-like blob of a frame with its centre 'U,V' [px] (to pick one as the ball's start point,
    TrackerOptions.start_uv)."""
    import cv2

    for b in blobs:
        r = max(float(b.radius_px), 3.0) + 5.0
        cv2.circle(frame, (int(round(b.u * 16)), int(round(b.v * 16))), int(r * 16), _BALL, 2, cv2.LINE_AA, 4)
        text = f"{b.u:.0f},{b.v:.0f}"
        org = (int(b.u + r + 4), int(b.v + 5))
        cv2.putText(frame, text, org, cv2.FONT_HERSHEY_SIMPLEX, 0.6, (0, 0, 0), 3, cv2.LINE_AA)
        cv2.putText(frame, text, org, cv2.FONT_HERSHEY_SIMPLEX, 0.6, _TEXT, 1, cv2.LINE_AA)
    return frame
