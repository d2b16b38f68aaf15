"""The ball's centre to a small fraction of a pixel, two ways for two kinds of frame.

- :func:`matte_centre` (the live camera's clean frames): the centroid of a soft matte instead of a binary mask, as
  below.
- :func:`refine_centre` (video files, often heavily compressed): the centroid of the colour's hue weighted by its
  saturation above the background — a codec's 8×8 blocks and ringing blur the ball's colour into its surroundings, so
  a matte between two medians misjudges the edge there, while saturation survives the chroma subsampling.


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
from functools import lru_cache

import numpy as np

from .color import ColorSpec, color_mask
from .detect import TINY_MAX_AREA_PX, Blob

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


_REFINE_MIN_SATURATION = 40  # the colour's hue counts from this saturation on for the refined centre
_REFINE_MARGIN_PX = 1.5  # [px] pixels this far beyond the blob's radius count (a soft or blocky edge)
_REFINE_MAX_RADIUS_PX = 30.0  # [px] larger balls are measured precisely enough by their outline


@lru_cache(maxsize=32)
def _hue_only(spec: ColorSpec) -> ColorSpec:
    from .color import with_min_saturation

    return with_min_saturation(spec, min(_REFINE_MIN_SATURATION, min(b.lower[1] for b in spec.bands)))


def refine_centre(bgr: np.ndarray, spec: ColorSpec, blob: Blob) -> tuple[float, float]:
    """The blob's centre [px] weighted by how much more saturated than the background each pixel of the colour's hue
    is, within its radius + 1.5 px of the blob's centroid: a sub-pixel centre that does not follow the blocky outline a
    low-bitrate codec gives the thresholded mask. The blob's own centre when the ball is tiny (already so weighted) or
    large, or when the weighted centre moves more than half a radius (something else of the colour in reach)."""
    import cv2

    r = blob.radius_px
    if blob.area_px <= TINY_MAX_AREA_PX or r > _REFINE_MAX_RADIUS_PX:
        return blob.u, blob.v
    h, w = bgr.shape[:2]
    reach = r + _REFINE_MARGIN_PX
    x0, y0 = max(int(blob.u - reach), 0), max(int(blob.v - reach), 0)
    x1, y1 = min(int(blob.u + reach) + 2, w), min(int(blob.v + reach) + 2, h)
    hsv = cv2.cvtColor(bgr[y0:y1, x0:x1], cv2.COLOR_BGR2HSV)
    hue = color_mask(hsv, _hue_only(spec))
    sat = hsv[:, :, 1]
    background = cv2.mean(sat, cv2.bitwise_not(hue))[0] if cv2.countNonZero(hue) < hue.size else 0.0
    inside = np.zeros_like(hue)  # the disc of reach around the centroid (4 fractional bits)
    cv2.circle(inside, (round((blob.u - x0) * 16), round((blob.v - y0) * 16)), round(reach * 16), 255, -1, shift=4)
    weight = cv2.bitwise_and(cv2.subtract(sat, max(background, _REFINE_MIN_SATURATION)), cv2.bitwise_and(hue, inside))
    m = cv2.moments(weight)
    if m["m00"] <= 0.0:
        return blob.u, blob.v
    u, v = m["m10"] / m["m00"] + x0, m["m01"] / m["m00"] + y0
    if math.hypot(u - blob.u, v - blob.v) > 0.5 * r:
        return blob.u, blob.v
    return u, v
