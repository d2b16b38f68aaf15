"""Coloured-blob detection: HSV threshold, morphology, contours gated by area and circularity.

The centre is the image-moment centroid of the blob's outer contour (sub-pixel; holes such as a
specular highlight do not bias it). Circularity is 4π·area/perimeter²: a pixelated disc scores ≈ 0.85–0.9,
a square 0.785, an elongated box or a cable far less, so a red object that is not a ball is not taken.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .color import ColorSpec, color_mask

_KERNEL_SIZE = 3  # [px] morphology structuring element (removes single-pixel noise, fills pinholes)


@dataclass(frozen=True)
class BlobGates:
    """Which blobs can be the ball: area [px²] range and minimum circularity (4π·A/P², 1 for a disc)."""

    min_area_px: float = 12.0  # a disc of radius ≈ 2 px
    max_area_px: float = 12000.0  # a disc of radius ≈ 62 px
    min_circularity: float = 0.8

    @classmethod
    def for_radius(cls, radius_px: float, min_circularity: float = 0.8) -> "BlobGates":
        """Gates for a ball of about radius_px [px]: area from 0.3× to 3× that of the disc."""
        area = math.pi * radius_px**2
        return cls(min_area_px=0.3 * area, max_area_px=3.0 * area, min_circularity=min_circularity)


@dataclass(frozen=True)
class Blob:
    """A detected blob: centre (u, v) [px] in full-frame coordinates, area [px²], circularity, clipped flag."""

    u: float
    v: float
    area_px: float
    circularity: float
    clipped: bool  # the blob touches an edge of the searched window that is not an edge of the frame

    @property
    def radius_px(self) -> float:
        """Radius [px] of the disc with the blob's area."""
        return math.sqrt(self.area_px / math.pi)


def _kernel():
    import cv2

    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (_KERNEL_SIZE, _KERNEL_SIZE))


def blob_mask(bgr: np.ndarray, spec: ColorSpec) -> np.ndarray:
    """Cleaned uint8 mask of the colour: 3×3 Gaussian blur → HSV → bands → open → close."""
    import cv2

    hsv = cv2.cvtColor(cv2.GaussianBlur(bgr, (3, 3), 0), cv2.COLOR_BGR2HSV)
    mask = color_mask(hsv, spec)
    k = _kernel()
    mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, k)
    return cv2.morphologyEx(mask, cv2.MORPH_CLOSE, k)


def find_blobs(
    bgr: np.ndarray,
    spec: ColorSpec,
    gates: BlobGates,
    origin: tuple[int, int] = (0, 0),
    frame_size: tuple[int, int] | None = None,
) -> list[Blob]:
    """All blobs of the colour passing the gates in a BGR image, or in a window of a frame.

    origin: (x0, y0) [px] of the window in the frame; frame_size: (width, height) [px] of the frame (the
    window's size when None), so that a blob cut by the window's inner edge is flagged ``clipped``.
    """
    import cv2

    mask = blob_mask(bgr, spec)
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    h, w = mask.shape
    x0, y0 = origin
    fw, fh = frame_size if frame_size is not None else (w + x0, h + y0)
    inner_left, inner_top, inner_right, inner_bottom = x0 > 0, y0 > 0, x0 + w < fw, y0 + h < fh
    out: list[Blob] = []
    for c in contours:
        if len(c) < 5:
            continue
        m = cv2.moments(c)
        area = m["m00"]
        if not gates.min_area_px <= area <= gates.max_area_px:
            continue
        perimeter = cv2.arcLength(c, True)
        circ = 4.0 * math.pi * area / (perimeter * perimeter)
        if circ < gates.min_circularity:
            continue
        bx, by, bw, bh = cv2.boundingRect(c)
        clipped = (
            (inner_left and bx <= 0)
            or (inner_top and by <= 0)
            or (inner_right and bx + bw >= w)
            or (inner_bottom and by + bh >= h)
        )
        out.append(Blob(m["m10"] / area + x0, m["m01"] / area + y0, area, circ, clipped))
    return out
