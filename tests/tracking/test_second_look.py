"""The second look: gaps before a confirmed stretch, the memory budget, and the backward chain on drawn frames."""

from __future__ import annotations

import math

import cv2
import numpy as np

from tracking.color import color_spec
from tracking.detect import Blob, BlobGates, find_blobs
from tracking.second_look import Gap, frames_needed, gaps, look_back, sharp_area
from tracking.tracker import CONFIRMED, BallTracker

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


def _fix(u: float, v: float, area: float) -> Blob:
    return Blob(u, v, area, 0.9, 0.95, False)


def test_sharp_area_is_the_median_over_the_slow_confirmed_fixes():
    # a ball of 113 px² that hangs, is swung (streaks of 300 px² moving 40 px per frame), and stops again
    blobs = [_fix(100.0 + 0.5 * k, 200.0, 113.0 + k) for k in range(5)]
    blobs += [_fix(110.0 + 40.0 * k, 200.0, 300.0) for k in range(12)]
    blobs += [None, _fix(600.0, 200.0, 118.0), _fix(601.0, 200.0, 120.0)]
    conf = np.array([CONFIRMED if b is not None else 0.0 for b in blobs])
    assert sharp_area(blobs, conf) == 116.0  # the four slow fixes after the first: 114–117; never the streaks
    conf[1:5] = 0.5  # not confirmed: only the pair after the re-acquisition
    assert sharp_area(blobs, conf) == 120.0
    assert sharp_area(blobs[5:17], np.full(12, CONFIRMED)) is None  # nothing slow


def test_a_still_sharp_ball_is_held_in_reserve_when_the_track_s_area_is_of_streaks():
    # a fast video's area on the track is of motion-blurred streaks (here 1.6 × the ball's); where the chain finds
    # the ball still (a string re-tensioned), its fixes are the sharp ball's: held in reserve, not reported
    dt = 1.0 / 60.0
    path = [(150.0 + 0.2 * k, 120.0) for k in range(12)]
    frames = [_disc(u, v) for u, v in path]
    stretch = [(k * dt, _blob(frames[k])) for k in (8, 9, 10)]
    back = [(k, k * dt, frames[k], None) for k in range(7, -1, -1)]
    ball = stretch[0][1].area_px
    reserve: list = []
    got = look_back(BallTracker(RED), stretch, back, 1.6 * ball, ball, reserve)
    assert got == [] and [k for k, _ in reserve] == list(range(7, -1, -1))
    assert max(math.hypot(b.u - path[k][0], b.v - path[k][1]) for k, b in reserve) < 0.3
    assert look_back(BallTracker(RED), stretch, back, 1.6 * ball) == []  # without the sharp area: nothing
    # a ball moving a radius or more per frame is not the still ball: nothing in reserve
    fast = [(150.0 + 12.0 * k, 120.0) for k in range(12)]
    frames = [_disc(u, v) for u, v in fast]
    stretch = [(k * dt, _blob(frames[k])) for k in (8, 9, 10)]
    reserve = []
    look_back(BallTracker(RED), stretch, [(k, k * dt, frames[k], None) for k in range(7, -1, -1)], 1.6 * ball,
              ball, reserve)  # fmt: skip
    assert reserve == []
