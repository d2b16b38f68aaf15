"""Drawn test frames, independent of OpenCV's drawing: a flat canvas and an anti-aliased disc."""

from __future__ import annotations

import numpy as np


def canvas(w=200, h=150, value=170):
    return np.full((h, w, 3), value, np.uint8)


def draw_disc(img, cx, cy, r, bgr):
    """Anti-aliased disc by exact-ish pixel coverage (independent of OpenCV's drawing)."""
    h, w = img.shape[:2]
    ys, xs = np.mgrid[0:h, 0:w]
    a = np.clip(r + 0.5 - np.hypot(xs - cx, ys - cy), 0, 1)[:, :, None]
    img[:] = np.round(img * (1 - a) + np.array(bgr, float) * a).astype(np.uint8)
