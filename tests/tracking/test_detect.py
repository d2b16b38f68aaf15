"""Blob detection: sub-pixel centres of anti-aliased discs, both red hue bands, shape gates against red non-balls."""

import math

import numpy as np
import pytest

from trajectories.errors import OptionError, SettingError
from tracking.color import COLORS, color_spec
from tracking.detect import BlobGates, find_blobs
from tests.helpers.frames import canvas, draw_disc

RED = COLORS["red"]


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
    cut = find_blobs(
        img[60:140, 148:228],
        RED,
        BlobGates(min_circularity=0.3, min_ellipse_fit=0.0),
        origin=(148, 60),
        frame_size=(300, 200),
    )
    assert len(cut) == 1 and cut[0].clipped


def test_colour_names_and_hue_ranges():
    assert len(color_spec("red").bands) == 2
    assert len(color_spec("Green").bands) == 1
    assert len(color_spec("170-10").bands) == 2  # wraps through 0
    assert color_spec("40-80").bands[0].lower[0] == 40
    for bad in ("purple-ish", "10-200", "x-y", ""):
        with pytest.raises(OptionError):
            color_spec(bad)
    with pytest.raises(SettingError, match="unknown colour 'mauve'") as err:  # the setting named, never a flag
        color_spec("mauve", "CameraSensor.color")
    assert err.value.setting == "CameraSensor.color" and "--" not in str(err.value)


def _wide_scene(rng):
    """A 1920×1080 frame with five red balls (radius 5–25 px), a long red bar and speckle noise."""
    img = canvas(1920, 1080, 150)
    img += rng.integers(0, 12, img.shape, dtype=np.uint8)
    balls = [(rng.uniform(60, 1860), rng.uniform(60, 1020), r) for r in (5.0, 8.0, 12.0, 18.0, 25.0)]
    for cx, cy, r in balls:
        x0, y0 = int(cx - r - 2), int(cy - r - 2)
        draw_disc(img[y0 : y0 + int(2 * r + 5), x0 : x0 + int(2 * r + 5)], cx - x0, cy - y0, r, (35, 30, 205))
    img[500:512, 100:700] = (35, 30, 205)  # a red bar: no ball
    return img, balls


def _same(a, b):
    key = lambda x: (round(x.u), round(x.v))  # noqa: E731
    a, b = sorted(a, key=key), sorted(b, key=key)
    assert len(a) == len(b)
    for p, q in zip(a, b):
        assert abs(p.u - q.u) < 1e-9 and abs(p.v - q.v) < 1e-9 and p.area_px == q.area_px and p.clipped == q.clipped


@pytest.mark.heavy
def test_coarse_whole_frame_search_finds_what_the_full_resolution_pass_finds():
    from tracking.detect import coarse_factor, find_blobs_coarse

    rng = np.random.default_rng(11)
    gates = BlobGates(min_area_px=40.0, max_area_px=4000.0)
    for _ in range(3):
        img, balls = _wide_scene(rng)
        full = find_blobs(img, RED, gates)
        assert len(full) == len(balls)
        _same(find_blobs_coarse(img, RED, gates, coarse_factor(1920)), full)


def test_coarse_search_of_a_window_keeps_frame_coordinates_and_flags_a_ball_cut_by_its_edge():
    from tracking.detect import coarse_hsv, find_blobs_coarse

    rng = np.random.default_rng(12)
    gates = BlobGates(min_area_px=40.0, max_area_px=4000.0)
    img, balls = _wide_scene(rng)
    cx, cy, r = balls[-1]  # the largest ball, cut by the window's right edge
    x0, y0, x1, y1 = max(int(cx) - 700, 0), max(int(cy) - 300, 0), int(cx + r) - 2, min(int(cy) + 300, 1080)
    sub = img[y0:y1, x0:x1]
    full = find_blobs(sub, RED, gates, (x0, y0), (1920, 1080))
    coarse = find_blobs_coarse(sub, RED, gates, 2, (x0, y0), (1920, 1080), coarse_hsv(sub, 2))
    assert any(b.clipped for b in full)
    assert any(b.clipped for b in coarse)  # the caller then measures it on the whole frame
    inside = [b for b in full if not b.clipped]
    assert all(x0 <= b.u < x1 and y0 <= b.v < y1 for b in inside)


@pytest.mark.parametrize("scale", [2, 4])
def test_a_large_ball_measured_on_a_shrunk_image(scale):
    """A ball of 60 px radius measured at a half or a quarter of the resolution: its centre within 0.12 px × the scale
    and its area within 6 % of the truth, in full-resolution coordinates; cut by an inner window edge it is flagged."""
    from tracking.detect import detail_scale, find_blobs_scaled

    assert detail_scale(20.0) == 1 and detail_scale(30.0) == 2 and detail_scale(50.0) == 4
    rng = np.random.default_rng(3)
    for _ in range(5):
        cx, cy = 200 + 7 * rng.random(), 150 + 7 * rng.random()
        img = canvas(400, 300)
        draw_disc(img, cx, cy, 60.0, (35, 30, 205))
        (b,) = find_blobs_scaled(img[20:290, 30:390], RED, BlobGates(max_area_px=2e4), scale, (30, 20), (400, 300))
        assert math.hypot(b.u - cx, b.v - cy) < 0.12 * scale and not b.clipped
        assert b.area_px == pytest.approx(math.pi * 60.0**2, rel=0.06)
    (cut,) = find_blobs_scaled(img[0:300, 0:256], RED, BlobGates(max_area_px=2e4), scale, (0, 0), (400, 300))
    assert cut.clipped


def test_too_dark_is_a_frame_where_no_pixel_reaches_the_colours_value_and_nothing_of_it_is_found():
    import cv2
    import numpy as np

    from tracking.color import color_spec
    from tracking.detect import BlobGates, find_blobs, find_tiny, too_dark

    red = color_spec("red")
    low = min(b.lower[2] for b in red.bands)
    frame = np.full((120, 160, 3), 5, np.uint8)
    cv2.circle(frame, (80, 60), 8, (0, 0, low - 1), -1)  # a red ball just too dark to have a hue band's value
    cv2.circle(frame, (30, 30), 2, (0, 0, low - 1), -1)
    assert too_dark(frame, low) and not too_dark(frame, low - 1)
    assert find_blobs(frame, red, BlobGates()) == [] and find_tiny(frame, red) == []
    frame[60, 80] = (0, 0, low)  # one pixel bright enough: the search must run
    assert not too_dark(frame, low)
    assert too_dark(frame[:, 100:], low)  # a window of a frame (not contiguous)
