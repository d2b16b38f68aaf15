"""The ball's centre to a small fraction of a pixel: the centroid of a soft matte instead of a binary mask.

A detected blob's centre (:mod:`.detect`) is the centroid of its thresholded outline: as the ball moves by a tenth of
a pixel the outline changes by whole pixels or not at all, so the centre moves in steps of about 0.1–0.2 px for a
ball a few pixels across. Where a camera sees a 1° tilt as half a pixel that is a stepped tilt reading with dead
zones of a few tenths of a degree (a sway smaller than that is not seen at all). The matte weighs every pixel near
the blob by how much of the ball's colour it holds — α = the projection of (pixel − background) onto (ball −
background), clipped to 0..1, the background and the ball's colour the medians of a ring around the blob and of its
core —, so the blurred, anti-aliased edge pixels move the centre continuously. A pixel that is no blend of the two
(the string over the ball, a shadow: a dark pixel projects far onto a dark ball's colour) weighs the less the
farther its colour is from every blend.
"""

from __future__ import annotations

import math

import numpy as np

EDGE_PX = 2.5  # [px] the matte reaches this far beyond the blob's radius (blur and anti-aliasing)
RING_PX = 2.0  # [px] width of the background ring just outside it
OFF_LINE = 0.6  # a pixel this share of the contrast away from every blend of background and ball weighs nothing
MIN_CONTRAST = 10.0
MAX_SHIFT_PX = 0.75  # [px] the outline's centre is off by a few tenths at most; a matte farther off saw something else
MAX_ELONGATION = 1.3  # a motion-blurred streak: its ends reach the background ring (kept: the outline's centre)  # [grey levels] the ball's colour must differ from the background's by this much (RGB distance)


def matte_centre(frame: np.ndarray, u: float, v: float, radius_px: float) -> tuple[float, float]:
    """The centre (u, v) [px] of the ball seen near the blob centre (u, v) of radius ``radius_px`` [px] in the BGR
    (or grey) ``frame``: the centroid of its matte (see the module). The blob's own centre where the matte cannot be
    made (the ball at the image's edge, too little contrast), strays more than MAX_SHIFT_PX from it or is elongated
    (a motion-blurred streak)."""
    if not (math.isfinite(u) and math.isfinite(v) and math.isfinite(radius_px) and radius_px > 0):
        return u, v
    img = frame if frame.ndim == 3 else frame[:, :, None]
    h, w = img.shape[:2]
    reach = radius_px + EDGE_PX
    outer = reach + RING_PX
    x0, x1 = int(math.floor(u - outer)), int(math.ceil(u + outer)) + 1
    y0, y1 = int(math.floor(v - outer)), int(math.ceil(v + outer)) + 1
    if x0 < 0 or y0 < 0 or x1 > w or y1 > h:
        return u, v  # the ring would be cut: the background is not known all round
    patch = img[y0:y1, x0:x1].astype(np.float32)
    yy, xx = np.mgrid[y0:y1, x0:x1].astype(np.float32)
    d = np.hypot(xx - u, yy - v)
    ring, core = (d > reach) & (d <= outer), d <= max(1.0, 0.5 * radius_px)
    background = np.median(patch[ring], axis=0)
    contrast = np.median(patch[core], axis=0) - background
    c2 = float(contrast @ contrast)
    if c2 < MIN_CONTRAST**2:
        return u, v
    diff = patch - background
    share = (diff @ contrast) / c2
    off_line = np.linalg.norm(diff - share[..., None] * contrast, axis=-1)  # [grey levels] not a blend of the two
    alpha = np.clip(share, 0.0, 1.0) * np.clip(1.0 - off_line / (OFF_LINE * math.sqrt(c2)), 0.0, 1.0)
    alpha[d > reach] = 0.0
    total = float(alpha.sum())
    if total <= 0.0:
        return u, v
    cu, cv = float((alpha * xx).sum()) / total, float((alpha * yy).sum()) / total
    if math.hypot(cu - u, cv - v) > MAX_SHIFT_PX or _elongation(alpha, xx - cu, yy - cv, total) > MAX_ELONGATION:
        return u, v  # not a refinement of the outline's centre: something else in the window, or a streak
    return cu, cv


def _elongation(alpha: np.ndarray, dx: np.ndarray, dy: np.ndarray, total: float) -> float:
    """Length / width of the matte's second-moment ellipse (1 for a disc)."""
    cov = np.array([[(alpha * dx * dx).sum(), (alpha * dx * dy).sum()], [0.0, (alpha * dy * dy).sum()]]) / total
    cov[1, 0] = cov[0, 1]
    lo, hi = np.linalg.eigvalsh(cov)
    return math.sqrt(hi / lo) if lo > 1e-9 else math.inf
