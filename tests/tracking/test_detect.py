"""Blob detection: sub-pixel centres of anti-aliased discs, both red hue bands, shape gates against red non-balls."""

import math

import numpy as np
import pytest

from trajectories.errors import OptionError
from tracking.color import COLORS, color_spec
from tracking.detect import BlobGates, find_blobs

RED = COLORS["red"]


def canvas(w=200, h=150, value=170):
    return np.full((h, w, 3), value, np.uint8)


def draw_disc(img, cx, cy, r, bgr):
    """Anti-aliased disc by exact-ish pixel coverage (independent of OpenCV's drawing)."""
    h, w = img.shape[:2]
    ys, xs = np.mgrid[0:h, 0:w]
    a = np.clip(r + 0.5 - np.hypot(xs - cx, ys - cy), 0, 1)[:, :, None]
    img[:] = np.round(img * (1 - a) + np.array(bgr, float) * a).astype(np.uint8)


@pytest.mark.parametrize("r,rms_px", [(4.0, 0.15), (6.5, 0.1), (15.0, 0.08)])
def test_centre_is_subpixel(r, rms_px):
    rng = np.random.default_rng(7)
    err = []
    for _ in range(30):
        cx, cy = 100 + 10 * rng.random(), 70 + 10 * rng.random()
        img = canvas()
        draw_disc(img, cx, cy, r, (35, 30, 205))
        blobs = find_blobs(img, RED, BlobGates())
        assert len(blobs) == 1
        b = blobs[0]
        err.append(math.hypot(b.u - cx, b.v - cy))
        assert b.radius_px == pytest.approx(r, abs=1.0)
        assert b.ellipse_fit > 0.9
    assert np.sqrt(np.mean(np.square(err))) < rms_px
    assert max(err) < 2.5 * rms_px


@pytest.mark.parametrize("bgr", [(40, 40, 200), (60, 20, 200), (20, 60, 200)])  # hue ≈ 0, ≈ 175 (wraps), ≈ 6
def test_both_red_hue_bands(bgr):
    import cv2

    img = canvas()
    draw_disc(img, 100, 70, 8, bgr)
    hue = cv2.cvtColor(np.uint8([[bgr]]), cv2.COLOR_BGR2HSV)[0, 0, 0]
    assert len(find_blobs(img, RED, BlobGates())) == 1, f"hue {hue}"


@pytest.mark.parametrize("angle_deg", [0.0, 30.0, 45.0])
def test_red_box_cable_and_other_colours_are_not_the_ball(angle_deg):
    import cv2

    img = canvas(400, 300)
    for centre, size in (((55, 43), (70, 46)), ((320, 50), (40, 40)), ((250, 250), (20, 20)), ((60, 220), (30, 12))):
        box = cv2.boxPoints((centre, size, angle_deg))  # boxes and squares of several sizes, rotated
        cv2.fillPoly(img, [np.round(box * 16).astype(np.int32)], (35, 30, 205), cv2.LINE_AA, 4)
    ys = np.linspace(100, 290, 30)
    cable = np.column_stack([380 + 8 * np.sin(ys / 20), ys]).astype(np.int32)
    cv2.polylines(img, [cable.reshape(-1, 1, 2)], False, (35, 30, 205), 5, cv2.LINE_AA)  # a cable
    draw_disc(img, 150, 200, 7, (60, 170, 40))  # a green ball
    draw_disc(img, 200.3, 120.6, 6.5, (35, 30, 205))  # the red ball
    blobs = find_blobs(img, RED, BlobGates())
    assert len(blobs) == 1
    assert math.hypot(blobs[0].u - 200.3, blobs[0].v - 120.6) < 0.15
    green = find_blobs(img, color_spec("green"), BlobGates())
    assert len(green) == 1 and abs(green[0].u - 150) < 0.15


def test_area_gates_for_radius():
    img = canvas(300, 200)
    draw_disc(img, 60, 60, 5, (35, 30, 205))
    draw_disc(img, 200, 100, 20, (35, 30, 205))
    big = find_blobs(img, RED, BlobGates.for_radius(20))
    small = find_blobs(img, RED, BlobGates.for_radius(5))
    assert [round(b.u) for b in big] == [200]
    assert [round(b.u) for b in small] == [60]


def test_window_origin_and_clipped_flag():
    img = canvas(300, 200)
    draw_disc(img, 150.25, 100.5, 8, (35, 30, 205))
    inside = find_blobs(img[60:140, 110:190], RED, BlobGates(), origin=(110, 60), frame_size=(300, 200))
    assert len(inside) == 1 and not inside[0].clipped
    assert abs(inside[0].u - 150.25) < 0.1 and abs(inside[0].v - 100.5) < 0.1
    cut = find_blobs(img[60:140, 148:228], RED, BlobGates(min_circularity=0.3, min_ellipse_fit=0.0), origin=(148, 60), frame_size=(300, 200))
    assert len(cut) == 1 and cut[0].clipped


def test_colour_names_and_hue_ranges():
    assert len(color_spec("red").bands) == 2
    assert len(color_spec("Green").bands) == 1
    assert len(color_spec("170-10").bands) == 2  # wraps through 0
    assert color_spec("40-80").bands[0].lower[0] == 40
    for bad in ("purple-ish", "10-200", "x-y", ""):
        with pytest.raises(OptionError):
            color_spec(bad)
