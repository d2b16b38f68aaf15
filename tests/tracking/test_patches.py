"""Patches kept around the fixes: a copy of the frame's pixels, what they cover, none for a ball too large; the model
look answers from them without decoding the video again, as it would from the whole frames."""

from __future__ import annotations

import cv2
import numpy as np

from tracking.color import color_spec
from tracking.model_look import integrate, recover, shows_ball
from tracking.patches import Patch, patch_around
from tracking.tracker import BallTracker

RED = color_spec("red")
FPS = 60.0
PIVOT = (320.0, 40.0)  # [px]
LENGTH = 180.0  # [px]


def _ball(img: np.ndarray, u: float, v: float, r: float, bgr) -> None:
    s = 16
    cv2.circle(img, (round(u * s), round(v * s)), round(r * s), bgr, -1, cv2.LINE_AA, shift=4)


def test_a_patch_is_a_copy_around_the_fix_and_covers_only_its_box():
    frame = np.random.default_rng(0).integers(0, 255, (360, 640, 3), np.uint8)
    p = patch_around(frame, 100.4, 50.7, 5.0)  # reach 3·5 + 16 = 31 px
    assert (p.x0, p.y0) == (69, 19) and p.pixels.shape == (63, 63, 3)
    assert np.array_equal(p.pixels, frame[19:82, 69:132])
    frame[:] = 0  # the frame's buffer decoded into again: the patch keeps its pixels
    assert p.pixels.any()
    assert p.covers(69, 19, 132, 82) and not p.covers(68, 19, 132, 82) and not p.covers(69, 19, 133, 82)
    edge = patch_around(frame, 3.0, 2.0, 5.0)  # cut by the frame's corner
    assert (edge.x0, edge.y0) == (0, 0) and edge.pixels.shape == (34, 35, 3)
    assert patch_around(frame, 300.0, 180.0, 40.0) is None  # 2·136 px square: more than an eighth of the frame


def test_shows_ball_on_a_patch_answers_as_on_the_whole_frame():
    img = np.full((260, 640, 3), 90, np.uint8)
    _ball(img, 200.3, 120.6, 7.0, (30, 30, 220))
    p = patch_around(img, 200.0, 120.0, 7.0)
    for u, v in ((200.3, 120.6), (203.0, 121.0), (209.0, 120.0), (150.0, 100.0)):
        assert shows_ball(p.pixels, RED, u, v, 7.0, (p.x0, p.y0)) == shows_ball(img, RED, u, v, 7.0)
    assert shows_ball(img, RED, 200.3, 120.6, 7.0)
    assert not shows_ball(p.pixels, RED, 200.3, 150.0, 30.0, (p.x0, p.y0))  # the disc reaches out of the patch


def test_the_model_look_answers_from_patches_without_decoding_the_video_again(tmp_path):
    n, r = 120, 7.0
    th = integrate(0.45, 0.0, 39.0, 0.1, 1.0 / FPS, n - 1)
    uv = np.column_stack([PIVOT[0] + LENGTH * np.sin(th), PIVOT[1] + LENGTH * np.cos(th)])
    frames = {}
    for k in range(n):
        img = np.full((260, 640, 3), 90, np.uint8)
        _ball(img, *uv[k], r, (30, 30, 220))
        frames[k] = img
    trusted = np.ones(n, bool)
    trusted[60:64] = False  # fixes judged off the motion after the first pass: found there, so not kept whole
    whole = recover(BallTracker(RED), str(tmp_path / "x.mp4"), FPS, uv, trusted, PIVOT, r, kept=frames)
    assert [k for k, _ in whole] == [60, 61, 62, 63]
    patches: dict[int, Patch] = {k: patch_around(f, *(uv[k] + 3.0), r) for k, f in frames.items()}  # fixes 4 px off
    missing = tmp_path / "gone.mp4"  # decoding anything would fail: there is no video
    got = recover(BallTracker(RED), str(missing), FPS, uv, trusted, PIVOT, r, kept={}, patches=patches)
    assert [(k, b.u, b.v) for k, b in got] == [(k, b.u, b.v) for k, b in whole]
