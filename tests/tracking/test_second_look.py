"""The second look: gaps before a confirmed stretch, the memory budget, and the backward chain on drawn frames."""

from __future__ import annotations

import math

import cv2
import numpy as np

from tracking.color import color_spec
from tracking.detect import BlobGates, find_blobs
from tracking.second_look import Gap, frames_needed, gaps, look_back
from tracking.tracker import BallTracker

RED = color_spec("red")


def test_gaps_are_the_misses_right_before_three_confident_fixes():
    found = np.array([0, 0, 1, 1, 1, 0, 1, 0, 0, 1, 1], bool)
    conf = np.where(found, 0.9, 0.0)
    conf[6] = 0.6
    assert gaps(found, conf, 0.5) == [Gap(0, 2)]  # 5 is followed by one fix only, 7–8 by two
    assert gaps(found, conf, 0.7, min_run=1) == [Gap(0, 2), Gap(7, 9)]  # frame 6 is not confident enough


def test_frames_needed_go_back_from_the_anchor_within_the_memory_budget():
    need = frames_needed([Gap(0, 5), Gap(20, 22)], frame_bytes=100 * 2**20)  # 2 frames fit in 256 MB
    assert need == {22: [21, 20]}  # the shorter gap first, the nearest frames to its anchor first


def _disc(u: float, v: float, r: float = 9.0, size=(320, 240), bgr=(30, 30, 220)) -> np.ndarray:
    img = np.full((size[1], size[0], 3), 60, np.uint8)
    s = 16  # sub-pixel drawing: 4 fractional bits
    cv2.circle(img, (round(u * s), round(v * s)), round(r * s), bgr, -1, cv2.LINE_AA, shift=4)
    return img


def _blob(img: np.ndarray):
    (b,) = find_blobs(img, RED, BlobGates())
    return b


def test_the_ball_is_followed_back_and_neither_a_jump_nor_a_smeared_ball_is_reported():
    dt = 1.0 / 60.0
    path = [(60.0 + 6.0 * k, 120.0 + 0.05 * (k - 15) ** 2) for k in range(30)]  # [px] frame k
    frames = [_disc(u, v) for u, v in path]
    frames[8] = _disc(path[8][0] + 30.0, path[8][1])  # an encoder's ghost where the ball is not: no fix there
    frames[4] = _disc(*path[4], bgr=(100, 100, 200))  # paler (a codec's smear): followed, not reported
    stretch = [(k * dt, _blob(frames[k])) for k in (20, 21, 22)]
    back = [(k, k * dt, frames[k], None) for k in range(19, -1, -1)]
    got = dict(look_back(BallTracker(RED), stretch, back, stretch[0][1].area_px))
    assert 8 not in got
    assert set(got) == set(range(20)) - {8, 4}  # the chain goes on past one miss and the pale frame
    err = [math.hypot(b.u - path[k][0], b.v - path[k][1]) for k, b in got.items()]
    assert max(err) < 0.3, err
