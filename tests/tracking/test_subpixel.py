"""The ball's centre from its matte: continuous in sub-pixel shifts where the thresholded blob's centre steps."""

from __future__ import annotations

import math

import numpy as np

from tracking.color import color_spec
from tracking.detect import BlobGates, find_blobs
from tracking.subpixel import matte_centre, refine_centre
from tracking.synthetic import draw_pendulum, lab_background
from tests.helpers.frames import canvas, draw_disc


def _frame(uv: np.ndarray, radius: float, rng: np.random.Generator) -> np.ndarray:
    import cv2

    frame = lab_background((160, 120), 3).copy()
    draw_pendulum(frame, uv - [0.0, 40.0], uv[None, :], radius)
    noisy = cv2.add(frame, rng.normal(0.0, 2.0, frame.shape).round().astype(np.int16), dtype=cv2.CV_8U)
    return cv2.GaussianBlur(noisy, (0, 0), 0.5)


def test_a_small_ball_moved_by_tenths_of_a_pixel_is_followed_to_a_few_hundredths():
    rng = np.random.default_rng(0)
    spec = color_spec("red", "ball")
    blob_err, matte_err = [], []
    for k in range(40):
        uv = np.array([80.0 + 0.05 * k, 60.0 + 0.03 * k])
        frame = _frame(uv, 4.0, rng)
        (blob,) = find_blobs(frame, spec, BlobGates())[:1]
        u, v = matte_centre(frame, blob.u, blob.v, blob.radius_px)
        blob_err.append(np.hypot(blob.u - uv[0], blob.v - uv[1]))
        matte_err.append(np.hypot(u - uv[0], v - uv[1]))
    assert np.sqrt(np.mean(np.square(matte_err))) < 0.06
    assert np.sqrt(np.mean(np.square(matte_err))) < 0.5 * np.sqrt(np.mean(np.square(blob_err)))


def test_the_blob_s_centre_is_kept_where_no_matte_can_be_made():
    frame = _frame(np.array([3.0, 60.0]), 4.0, np.random.default_rng(1))
    assert matte_centre(frame, 3.2, 60.1, 4.0) == (3.2, 60.1)  # the ring would leave the image
    flat = np.full((120, 160, 3), 128, np.uint8)
    assert matte_centre(flat, 80.0, 60.0, 4.0) == (80.0, 60.0)  # nothing there: no contrast
    assert matte_centre(frame, float("nan"), 60.0, 4.0)[1] == 60.0


def test_a_motion_blurred_streak_keeps_the_outline_s_centre():
    import cv2

    frame = lab_background((160, 120), 3).copy()
    centres = np.stack([np.linspace(70.0, 90.0, 12), np.full(12, 60.0)], axis=1)  # 20 px of motion in the exposure
    draw_pendulum(frame, np.array([80.0, 20.0]), centres, 4.0)
    frame = cv2.GaussianBlur(frame, (0, 0), 0.5)
    assert matte_centre(frame, 80.3, 60.2, 6.0) == (80.3, 60.2)


def test_refined_centre_sees_through_a_codec_s_blocks_and_ignores_a_cable_beside_the_ball():
    """JPEG at quality 8 turns the ball's edge into 8×8 blocks: the thresholded outline's centroid moves, the
    saturation-weighted centre less (≈ 13 % here; 10–25 % on the H.264 benchmark videos); a red cable 4.5 px from the ball's edge does not pull it."""
    import cv2

    rng = np.random.default_rng(5)
    red = color_spec("red")
    blob_err, refined_err = [], []
    for _ in range(12):
        cx, cy = 100.0 + rng.uniform(-4, 4), 75.0 + rng.uniform(-4, 4)
        img = canvas()
        draw_disc(img, cx, cy, 9.0, (40, 40, 210))
        img = cv2.imdecode(cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, 8])[1], cv2.IMREAD_COLOR)
        (b,) = find_blobs(img, red, BlobGates(min_circularity=0.3, min_ellipse_fit=0.6))  # the tracker's relaxed gates
        u, v = refine_centre(img, red, b)
        blob_err.append(math.hypot(b.u - cx, b.v - cy))
        refined_err.append(math.hypot(u - cx, v - cy))
    assert np.sqrt(np.mean(np.square(refined_err))) < 0.95 * np.sqrt(np.mean(np.square(blob_err))), (
        blob_err,
        refined_err,
    )
    img = canvas()
    draw_disc(img, 100.0, 75.0, 9.0, (40, 40, 210))
    cv2.line(img, (115, 20), (115, 130), (40, 40, 210), 3)  # 4.5 px from the ball's edge
    (b,) = [b for b in find_blobs(img, red, BlobGates()) if abs(b.u - 100.0) < 3]
    u, v = refine_centre(img, red, b)
    assert math.hypot(u - 100.0, v - 75.0) < 0.1
