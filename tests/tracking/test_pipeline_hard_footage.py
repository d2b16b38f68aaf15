"""A real lab's footage (issue #35): clutter in the ball's colour, H.264 at 100 kbit/s, a 3 px ball, a ball a quarter
of the frame, and a lock on a static object that must be dropped. Small rendered videos with exact ground truth."""

import math

import numpy as np
import pytest

from tracking.color import color_spec
from tracking.pipeline import track_video
from tracking.synthetic import Distractor, render_pendulum_video
from tracking.trackfile import read_track_csv, write_track_csv

SIZE = (480, 270)


@pytest.mark.heavy
@pytest.mark.parametrize(
    "name,min_found",
    [("clutter", 99.0), ("h264_clutter", 90.0), ("tiny_ball", 97.0), ("big_ball", 99.0), ("h264_100k", 90.0)],
)
def test_no_false_fix_and_found(name, min_found, run):
    sc, track, out = run(name)
    assert out.false_fixes == 0, out
    assert out.found_percent >= min_found, out
    assert out.centre_rms_px <= (1.5 if "h264" in name else 1.0), out


def test_ball_size_is_learned_from_3_px_to_a_quarter_of_the_frame(run):
    for name in ("tiny_ball", "big_ball"):
        sc, track, _ = run(name)
        r = float(np.nanmedian(track.radius_px))
        assert abs(r - sc.truth.ball_radius_px) <= max(1.0, 0.2 * sc.truth.ball_radius_px), (name, r)


@pytest.mark.heavy
def test_lock_on_a_static_object_is_dropped_and_its_frames_withdrawn(tmp_path):
    """The issue's failure: the ball hidden at first, a red disc as round as it in view — the tracker may hold
    the disc, but never reports it as found, and takes the ball once it shows, swinging."""
    import cv2

    piv, L, r = (240.0, 40.0), 160.0, 5.0
    t = np.arange(0.0, 2.5, 0.001)
    th = np.radians(30) * np.sin(2 * np.pi * t / 1.0)
    disc = Distractor("disc", np.array([90.0, 200.0]), radius_px=r)

    def cover(frame, tk, ball):  # a grey board hides the swing for the first 0.6 s
        if tk < 0.6:
            cv2.rectangle(frame, (130, 120), (350, 240), (150, 152, 155), -1)

    gt = render_pendulum_video(
        tmp_path / "v.mp4", t, th, piv, L, r, SIZE, 60.0, distractors=[disc], foreground=[cover], seed=4
    )
    track = track_video(tmp_path / "v.mp4", color_spec("red"), pivot_uv=piv)
    err = np.linalg.norm(track.uv - gt.ball_uv, axis=1)
    assert not np.any(track.found & (err > 5.0))  # the disc is never reported as the ball
    shown = gt.t >= 0.6
    assert track.found[shown].mean() >= 0.93  # the tentative lock looks for others every 0.1 s
    assert np.all(np.linalg.norm(track.uv[track.found] - disc.points, axis=1) > 10.0)
    assert not (track.unsure & track.found).any()  # an unsure frame is never a found one
    path = tmp_path / "t.csv"
    write_track_csv(path, track)
    back = read_track_csv(path)
    np.testing.assert_array_equal(back.unsure, track.unsure)
    assert np.all(back.confidence[back.found] >= 0.5) and np.all(np.isnan(back.uv[back.unsure]))


@pytest.mark.heavy
def test_beyond_the_string_is_not_the_ball(tmp_path):
    """A red disc as round as the ball, outside the string's reach, appears while the ball is hidden by a rod:
    with the pivot known, it is never taken."""
    import cv2

    piv, L, r = (240.0, 30.0), 120.0, 5.0
    t = np.arange(0.0, 2.0, 0.001)
    th = np.radians(25) * np.sin(2 * np.pi * t / 0.8)

    def flash(frame, tk, ball):  # the disc shows from 1 s on, far outside the string's reach
        if tk >= 1.0:
            cv2.circle(frame, (440, 240), int(r), (35, 30, 205), -1, cv2.LINE_AA)

    gt = render_pendulum_video(
        tmp_path / "s.mp4", t, th, piv, L, r, SIZE, 60.0, distractors=None, foreground=[flash], seed=6
    )
    track = track_video(tmp_path / "s.mp4", color_spec("red"), pivot_uv=piv)
    err = np.linalg.norm(track.uv - gt.ball_uv, axis=1)
    assert not np.any(track.found & (err > 5.0))
    assert track.found.mean() >= 0.99
    assert math.isfinite(track.found_fraction)
