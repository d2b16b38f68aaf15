"""Coloured-blob detection: HSV threshold, morphology, contours gated by area and shape.

The centre is the image-moment centroid of the blob's outer contour (sub-pixel; holes such as a
specular highlight do not bias it). Two shape gates keep red objects that are not a ball out:
- circularity 4π·area/perimeter² (disc ≈ 0.85–0.95 after pixelation, a cable ≈ 0.1) rejects thin and
  strongly elongated blobs;
- ellipse fit, the intersection over union of the blob with the ellipse of the same second moments: a disc
  (and a motion-blurred ball, a stadium) ≥ 0.9, any box or rectangle ≈ 0.83 whatever its size, aspect or
  rotation — circularity alone cannot tell a square (0.785, ≈ 0.81 once morphology rounds its corners)
  from a pixelated disc.
Below ≈ 64 px² (a disc of radius ≈ 4.5 px) pixelation distorts both measures, so the gates are relaxed
there (a blob that small cannot be told from a tiny box anyway).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .color import ColorSpec, color_mask

_KERNEL_SIZE = 3  # [px] morphology structuring element (removes single-pixel noise, fills pinholes)
# Below this area [px²] the shape gates are relaxed by _SMALL_RELAX (pixelation, see the module docstring).
_SMALL_AREA_PX = 64.0
SHAPE_MIN_AREA_PX = _SMALL_AREA_PX  # [px²] a blob this large has a shape that tells a ball from a box
_SMALL_RELAX = 0.15


@dataclass(frozen=True)
class BlobGates:
    """Which blobs can be the ball: area [px²] range, minimum circularity (4π·A/P²) and ellipse fit (IoU)."""

    min_area_px: float = 12.0  # a disc of radius ≈ 2 px
    max_area_px: float = 12000.0  # a disc of radius ≈ 62 px
    min_circularity: float = 0.6
    min_ellipse_fit: float = 0.88

    @classmethod
    def for_radius(cls, radius_px: float, min_circularity: float = 0.6, min_ellipse_fit: float = 0.88) -> "BlobGates":
        """Gates for a ball of about radius_px [px]: area from 0.3× to 3× that of the disc."""
        area = math.pi * radius_px**2
        return cls(0.3 * area, 3.0 * area, min_circularity, min_ellipse_fit)


@dataclass(frozen=True)
class Blob:
    """A detected blob: centre (u, v) [px] in full-frame coordinates, area [px²], shape measures, clipped flag."""

    u: float
    v: float
    area_px: float
    circularity: float  # 4π·area/perimeter²
    ellipse_fit: float  # IoU of the blob with its second-moment ellipse
    clipped: bool  # the blob touches an edge of the searched window that is not an edge of the frame
    saturation: float = float("nan")  # peak HSV saturation of the blob's pixels (0–255; the ball's own colour)
    aspect: float = 1.0  # length / width of the blob's second-moment ellipse (1 for a disc)

    @property
    def radius_px(self) -> float:
        """Radius [px] of the disc with the blob's area."""
        return math.sqrt(self.area_px / math.pi)


def _kernel():
    import cv2

    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (_KERNEL_SIZE, _KERNEL_SIZE))


def to_hsv(bgr: np.ndarray) -> np.ndarray:
    """3×3 Gaussian blur → HSV (OpenCV ranges), the input of :func:`blob_mask`."""
    import cv2

    return cv2.cvtColor(cv2.GaussianBlur(bgr, (3, 3), 0), cv2.COLOR_BGR2HSV)


def blob_mask(bgr: np.ndarray, spec: ColorSpec, hsv: np.ndarray | None = None) -> np.ndarray:
    """Cleaned uint8 mask of the colour: 3×3 Gaussian blur → HSV → bands → open → close (hsv: precomputed)."""
    import cv2

    if hsv is None:
        hsv = to_hsv(bgr)
    mask = color_mask(hsv, spec)
    k = _kernel()
    mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, k)
    return cv2.morphologyEx(mask, cv2.MORPH_CLOSE, k)


def ellipse_fit(contour: np.ndarray) -> float:
    """IoU of the filled contour with the ellipse of equal second moments (1 for an ellipse, ≈ 0.83 for a box).

    A pixel is in the ellipse when its centre is (Mahalanobis distance² ≤ 4: a uniform ellipse with
    semi-axes a, b has variances a²/4, b²/4 along its axes). The ellipse's pixels are counted row by row as
    intervals, the blob's inside it through per-row cumulative sums over the contour's box only.
    """
    import cv2

    x, y, w, h = cv2.boundingRect(contour)
    fill = np.zeros((h, w), np.uint8)
    cv2.drawContours(fill, (contour,), -1, 1, -1, offset=(-x, -y))
    m = cv2.moments(fill, True)
    if m["m00"] <= 0:
        return 0.0
    c20, c11, c02 = m["mu20"] / m["m00"], m["mu11"] / m["m00"], m["mu02"] / m["m00"]
    det = c20 * c02 - c11 * c11
    if det <= 1e-9:
        return 0.0
    cx, cy = m["m10"] / m["m00"], m["m01"] / m["m00"]
    # per row, the pixel centres inside: c02 dx² − 2 c11 dy dx + c20 dy² ≤ 4 det, an interval of dx
    half = 2.0 * math.sqrt(c02) + 1.0  # [px] beyond the ellipse's vertical half-extent (dy² ≤ 4 c02)
    first, last = math.floor(cy - half), math.ceil(cy + half)
    cs = np.zeros((h, w + 1), np.int32)
    np.cumsum(fill, axis=1, out=cs[:, 1:])
    count = _rows_in_ellipse_py if last - first < _PY_ROWS else _rows_in_ellipse_np
    inner, both = count(cs, first, last, cx, cy, c20, c11, c02, det)
    union = m["m00"] + inner - both
    return both / union if union > 0 else 0.0


_PY_ROWS = 48  # an ellipse over fewer rows is counted row by row in Python (numpy's cost is per call, not per row)


def _rows_in_ellipse_py(cs, first, last, cx, cy, c20, c11, c02, det) -> tuple[float, float]:  # noqa: ANN001
    """(pixels of the ellipse, of them the blob's) over rows first..last of the box (cs: the blob's per-row cumulative
    sums); the same arithmetic as :func:`_rows_in_ellipse_np`, one row at a time."""
    h, w = cs.shape[0], cs.shape[1] - 1
    rows = cs.tolist()
    a2, b2 = c11 * c11 - c02 * c20, 4.0 * det * c02
    inner = both = 0.0
    for r in range(first, last + 1):
        dy = r - cy
        disc = a2 * dy * dy + b2
        root = math.sqrt(max(disc, 0.0))
        lo = math.ceil(cx + (c11 * dy - root) / c02)
        hi = max(math.floor(cx + (c11 * dy + root) / c02) + 1, lo) if disc >= 0.0 else lo
        inner += hi - lo
        if 0 <= r < h:
            row = rows[r]
            both += row[min(max(hi, 0), w)] - row[min(max(lo, 0), w)]
    return inner, both


def _rows_in_ellipse_np(cs, first, last, cx, cy, c20, c11, c02, det) -> tuple[float, float]:  # noqa: ANN001
    """:func:`_rows_in_ellipse_py` for all rows at once."""
    h, w = cs.shape[0], cs.shape[1] - 1
    rows = np.arange(first, last + 1)
    dy = rows - cy
    disc = (c11 * c11 - c02 * c20) * dy * dy + 4.0 * det * c02
    root = np.sqrt(np.maximum(disc, 0.0))
    lo = np.ceil(cx + (c11 * dy - root) / c02)
    hi = np.where(disc >= 0.0, np.maximum(np.floor(cx + (c11 * dy + root) / c02) + 1.0, lo), lo)
    inbox = (rows >= 0) & (rows < h)
    r = rows[inbox]
    both = float(
        (cs[r, np.clip(hi[inbox], 0, w).astype(np.intp)] - cs[r, np.clip(lo[inbox], 0, w).astype(np.intp)]).sum()
    )
    return float((hi - lo).sum()), both


def _aspect(m: dict) -> float:
    """Length / width of the second-moment ellipse of a contour's moments."""
    a, b, c = m["mu20"], m["mu11"], m["mu02"]
    root = math.sqrt(max((a - c) ** 2 + 4.0 * b * b, 0.0))
    lo = 0.5 * (a + c - root)
    return math.sqrt((0.5 * (a + c + root)) / lo) if lo > 1e-12 else math.inf


def find_blobs(
    bgr: np.ndarray,
    spec: ColorSpec,
    gates: BlobGates,
    origin: tuple[int, int] = (0, 0),
    frame_size: tuple[int, int] | None = None,
    hsv: np.ndarray | None = None,
) -> list[Blob]:
    """All blobs of the colour passing the gates in a BGR image, or in a window of a frame.

    origin: (x0, y0) [px] of the window in the frame; frame_size: (width, height) [px] of the frame (the
    window's size when None), so that a blob cut by the window's inner edge is flagged ``clipped``; hsv:
    the image already converted by :func:`to_hsv` (several colour thresholds on one image).
    """
    import cv2

    if hsv is None:
        hsv = to_hsv(bgr)
    mask = blob_mask(bgr, spec, hsv)
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
        relax = _SMALL_RELAX if area < _SMALL_AREA_PX else 0.0
        perimeter = cv2.arcLength(c, True)
        circ = 4.0 * math.pi * area / (perimeter * perimeter)
        if circ < gates.min_circularity - relax:
            continue
        fit = ellipse_fit(c)
        if fit < gates.min_ellipse_fit - relax:
            continue
        bx, by, bw, bh = cv2.boundingRect(c)
        clipped = (
            (inner_left and bx <= 0)
            or (inner_top and by <= 0)
            or (inner_right and bx + bw >= w)
            or (inner_bottom and by + bh >= h)
        )
        sat = float(cv2.minMaxLoc(hsv[by : by + bh, bx : bx + bw, 1], mask[by : by + bh, bx : bx + bw])[1])
        out.append(Blob(m["m10"] / area + x0, m["m01"] / area + y0, area, circ, fit, clipped, sat, _aspect(m)))
    return out


_DETAIL_RADIUS_PX = (
    12.0  # [px] a ball keeping this radius in a shrunk image is measured there (centre to ≈ 0.1 px of it)
)


def detail_scale(min_radius_px: float | None) -> int:
    """Shrink factor (1, 2 or 4) at which a ball of at least min_radius_px [px] still keeps 12 px of radius: a ball a
    quarter of the frame is measured on a quarter or a sixteenth of the pixels."""
    if min_radius_px is None or min_radius_px < 2.0 * _DETAIL_RADIUS_PX:
        return 1
    return 4 if min_radius_px >= 4.0 * _DETAIL_RADIUS_PX else 2


def find_blobs_scaled(
    bgr: np.ndarray,
    spec: ColorSpec,
    gates: BlobGates,
    scale: int,
    origin: tuple[int, int] = (0, 0),
    frame_size: tuple[int, int] | None = None,
) -> list[Blob]:
    """:func:`find_blobs` on the image shrunk by ``scale`` (area averaging; arguments as there): for a ball large enough
    to keep its shape there (:func:`detail_scale`), at a fraction of the cost. Centres, areas and the ``clipped`` flag
    are in full-resolution terms (a shrunk pixel j covers the pixels j·scale … j·scale + scale − 1)."""
    import cv2

    if scale <= 1:
        return find_blobs(bgr, spec, gates, origin, frame_size)
    h, w = bgr.shape[:2]
    ox, oy = origin
    fw, fh = frame_size if frame_size is not None else (w + ox, h + oy)
    ws, hs = w // scale, h // scale
    if ws < 5 or hs < 5:
        return find_blobs(bgr, spec, gates, origin, frame_size)
    small = bgr[: hs * scale, : ws * scale]
    for _ in range(scale.bit_length() - 1):  # halvings: OpenCV's fast path of area averaging (scale a power of 2)
        small = cv2.resize(small, (small.shape[1] // 2, small.shape[0] // 2), interpolation=cv2.INTER_AREA)
    s2 = float(scale * scale)
    shrunk = replace(gates, min_area_px=gates.min_area_px / s2, max_area_px=gates.max_area_px / s2)
    x0, y0 = int(ox > 0), int(oy > 0)  # which edges of the window are inner ones (not the frame's)
    size = (x0 + ws + int(ox + w < fw), y0 + hs + int(oy + h < fh))
    return [
        replace(b, u=(b.u - x0 + 0.5) * scale - 0.5 + ox, v=(b.v - y0 + 0.5) * scale - 0.5 + oy, area_px=b.area_px * s2)
        for b in find_blobs(small, spec, shrunk, (x0, y0), size)
    ]


_COARSE_MAX_REGIONS = 24  # more candidate regions than this: search the full-resolution frame instead


_COARSE_MIN_RADIUS_PX = 6.0  # [px] the smallest ball sought keeps at least this radius in the shrunk image
_COARSE_MAX_FACTOR = 4


def coarse_factor(width_px: int, min_radius_px: float | None = None) -> int:
    """Downscaling factor of the first pass of a whole-frame search: 2 from 960 px wide, else 1 (none); when the
    smallest ball sought is known to be large (min_radius_px [px]), up to 4 as long as it keeps 6 px of radius."""
    base = 2 if width_px >= 960 else 1
    if min_radius_px is None or min_radius_px < 2.0 * _COARSE_MIN_RADIUS_PX:
        return base
    by_size = 1 << int(math.log2(min_radius_px / _COARSE_MIN_RADIUS_PX))
    return max(base, min(_COARSE_MAX_FACTOR, by_size))


def coarse_hsv(bgr: np.ndarray, factor: int) -> np.ndarray:
    """The image shrunk by ``factor`` in HSV: the first pass of :func:`find_blobs_coarse`. Area averaging by 2;
    by 4, the mean of the 2×2 central pixels of each 4×4 block (bilinear, 3× cheaper than area averaging there)."""
    import cv2

    h, w = bgr.shape[:2]
    how = cv2.INTER_AREA if factor <= 2 else cv2.INTER_LINEAR
    return cv2.cvtColor(cv2.resize(bgr, (w // factor, h // factor), interpolation=how), cv2.COLOR_BGR2HSV)


def find_blobs_coarse(
    bgr: np.ndarray,
    spec: ColorSpec,
    gates: BlobGates,
    factor: int,
    origin: tuple[int, int] = (0, 0),
    frame_size: tuple[int, int] | None = None,
    small_hsv: np.ndarray | None = None,
    refine: int = 1,
) -> list[Blob]:
    """:func:`find_blobs` on a whole frame (or a large window of one: ``origin``, ``frame_size`` as there) in two
    passes: the colour's pixels on the image shrunk by factor (area averaging, no morphology, so a ball of 2 px
    radius still shows), then the exact detection at full resolution in a window around each region found,
    skipping regions longer than the largest ball. Same result as one full-resolution pass at a fraction of the
    cost; falls back to it when the coarse pass finds very many regions or a blob is cut by a window.
    ``small_hsv``: :func:`coarse_hsv` of the image already (several colour thresholds on one image); ``refine``: the
    regions are measured on the image shrunk by this (:func:`find_blobs_scaled`; a ball known to be large).
    """
    import cv2

    h, w = bgr.shape[:2]
    ox, oy = origin
    size = frame_size or (w, h)
    if factor <= 1:
        return find_blobs_scaled(bgr, spec, gates, refine, origin, size)
    mask = color_mask(coarse_hsv(bgr, factor) if small_hsv is None else small_hsv, spec)
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    # regions longer than the largest ball (a cable, a big box) cannot hold one apart from them; tiny ones are noise
    longest = 1.5 * 2.0 * math.sqrt(gates.max_area_px / math.pi) / factor + 2.0
    least = 0.25 * gates.min_area_px / (factor * factor)
    boxes = [
        r
        for r, c in ((cv2.boundingRect(c), c) for c in contours)
        if max(r[2], r[3]) <= longest and max(cv2.contourArea(c), 1.0) >= least
    ]
    if len(boxes) > _COARSE_MAX_REGIONS:
        return find_blobs_scaled(bgr, spec, gates, refine, origin, size)
    out: list[Blob] = []
    for x, y, bw, bh in boxes:
        pad = 4 + min(max(bw, bh) // 2, 6)  # [coarse px] a blob cut by its window falls back to the full frame
        x0, y0 = max((x - pad) * factor, 0), max((y - pad) * factor, 0)
        x1, y1 = min((x + bw + pad) * factor, w), min((y + bh + pad) * factor, h)
        for b in find_blobs_scaled(bgr[y0:y1, x0:x1], spec, gates, refine, (x0 + ox, y0 + oy), size):
            if b.clipped:  # cut by a coarse window (or by the outer window, which the caller handles)
                return find_blobs_scaled(bgr, spec, gates, refine, origin, size)
            if all(abs(b.u - o.u) > 0.5 or abs(b.v - o.v) > 0.5 for o in out):
                out.append(b)
    return out


def too_dark(bgr: np.ndarray, min_value: int) -> bool:
    """No pixel of the BGR image reaches the HSV value min_value (V = max(B, G, R)): no colour band starting there can
    hold any of it, blurred, shrunk or not (a frame of a dark start: its whole-frame searches skipped)."""
    import cv2

    flat = (
        bgr.reshape(bgr.shape[0], -1) if bgr.flags.c_contiguous else np.ascontiguousarray(bgr).reshape(bgr.shape[0], -1)
    )
    return cv2.minMaxLoc(flat)[1] < min_value


TINY_MAX_AREA_PX = 40.0  # [px²] a blob up to this area is searched by :func:`find_tiny` (a disc of radius ≈ 3.5 px)
_TINY_MIN_SATURATION = 45  # a 3 px ball blurred by the lens and the codec keeps about half its saturation
_TINY_MIN_CONTRAST = 35  # ... and stands out by this much from the saturation of its surroundings


def _median(a: np.ndarray) -> float:
    """np.median of a small array, equal to it (the mean of the two middle values of an even count), without its
    overhead (≈ 15 µs a call, for every small region of a frame)."""
    flat = np.sort(a, axis=None)
    m = flat.size // 2
    return float(flat[m]) if flat.size % 2 else (float(flat[m - 1]) + float(flat[m])) / 2.0


def find_tiny(
    bgr: np.ndarray,
    spec: ColorSpec,
    origin: tuple[int, int] = (0, 0),
    frame_size: tuple[int, int] | None = None,
    min_saturation: int = _TINY_MIN_SATURATION,
    max_area_px: float = TINY_MAX_AREA_PX,
) -> list[Blob]:
    """Balls a few pixels across, which blur, morphology and shape measures would erase: the colour's hue at a
    lower saturation on the unblurred image, connected components of 1 to max_area_px pixels more saturated than
    their surroundings, each centred on its saturation-weighted centroid over its box grown by 2 px (sub-pixel). Shape measures are meaningless at this
    size (set to 1); a caller must judge such blobs by their motion. Same arguments as :func:`find_blobs`."""
    import cv2

    from .color import with_min_saturation

    hsv = cv2.cvtColor(bgr, cv2.COLOR_BGR2HSV)
    loose = with_min_saturation(spec, min(min_saturation, min(b.lower[1] for b in spec.bands)))
    mask = color_mask(hsv, loose)
    # the 8-connected regions by their outer contours: ≈ 50× cheaper than labelling a whole frame's components
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    h, w = mask.shape
    x0, y0 = origin
    fw, fh = frame_size if frame_size is not None else (w + x0, h + y0)
    sat_all = hsv[:, :, 1]  # (weighted by the mask per region below: not a whole frame's float copy)
    out: list[Blob] = []
    for c in contours:
        bx, by, bw, bh = cv2.boundingRect(c)
        if max(bw, bh) > 2.5 * math.sqrt(max_area_px):
            continue
        area = cv2.countNonZero(mask[by : by + bh, bx : bx + bw])
        if area > max_area_px:
            continue
        cx0, cy0 = max(bx - 2, 0), max(by - 2, 0)
        cx1, cy1 = min(bx + bw + 2, w), min(by + bh + 2, h)
        patch = sat_all[cy0:cy1, cx0:cx1].astype(np.float32) * (mask[cy0:cy1, cx0:cx1] > 0)
        total = float(patch.sum())
        if total <= 0:
            continue
        # area of the equivalent sharp disc: the saturation mass over the peak (a blurred dot spreads, not grows)
        peak = float(patch.max())
        rx0, ry0, rx1, ry1 = max(bx - 5, 0), max(by - 5, 0), min(bx + bw + 5, w), min(by + bh + 5, h)
        if peak - _median(sat_all[ry0:ry1, rx0:rx1]) < _TINY_MIN_CONTRAST:  # as saturated as its surroundings: a
            continue  # coloured surface (judged first: in a dark, noisy frame most regions end here)
        ys, xs = np.mgrid[cy0:cy1, cx0:cx1]
        u = float((patch * xs).sum() / total) + x0
        v = float((patch * ys).sum() / total) + y0
        clipped = (
            (x0 > 0 and bx <= 0)
            or (y0 > 0 and by <= 0)
            or (x0 + w < fw and bx + bw >= w)
            or (y0 + h < fh and by + bh >= h)
        )
        out.append(Blob(u, v, max(total / peak, float(area)), 1.0, 1.0, bool(clipped), peak))
    return out
