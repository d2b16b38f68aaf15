"""A slack string in a track (position kept, no angle) and the position comparison over the flight."""

import math

import numpy as np
import pytest

from tracking.compare_positions import compare_positions
from tracking.slack import slack_frames, string_length_px
from tracking.synthetic import render_pendulum_video


def test_slack_frames_are_the_ones_nearer_than_the_string():
    rng = np.random.default_rng(3)
    n = 200
    pivot = np.column_stack([300 + 20 * np.sin(np.arange(n) / 9.0), 100 + 0 * np.arange(n)])
    dist = np.full(n, 320.0) + rng.normal(0, 0.6, n)
    dist[120:160] = np.linspace(220, 60, 40)  # the ball flies in toward the pivot
    ang = np.linspace(-1.0, 2.0, n)
    ball = pivot + dist[:, None] * np.column_stack([np.sin(ang), np.cos(ang)])
    ball[50] = np.nan  # a lost frame stays unknown
    mask, d, length = slack_frames(ball, pivot)
    assert length == pytest.approx(320.0, abs=1.5)
    assert mask[121:160].all() and not mask[:120].any() and not mask[160:].any() and not mask[50]
    assert math.isnan(string_length_px([np.nan]))


def test_positions_are_compared_on_the_models_clock_and_scale():
    t = np.arange(0.0, 1.0, 0.001)
    rel = np.column_stack([0.2 * np.cos(3 * t), 0.15 * np.sin(2 * t) - 0.1])
    slack = (t > 0.4) & (t < 0.7)
    scale, lag = 1300.0, 0.12
    tt = np.arange(0.0, 1.1, 1 / 60)
    truth = np.column_stack([np.interp(tt - lag, t, rel[:, 0]), np.interp(tt - lag, t, rel[:, 1])])
    px = np.column_stack([truth[:, 0], -truth[:, 1]]) * scale
    got = compare_positions(t, rel, slack, 0.25, tt, px, 0.25 * scale, lag)
    assert got.frames == pytest.approx(0.3 * 60, abs=2) and got.rms_m < 1e-4 and got.px_per_m == pytest.approx(scale)
    off = compare_positions(t, rel, slack, 0.25, tt, px + np.array([0.0, 0.002 * scale]), 0.25 * scale, lag)
    assert off.rms_m == pytest.approx(0.002, rel=0.05)  # a 2 mm error shows as 2 mm
    mirrored = compare_positions(t, rel, slack, 0.25, tt, px * np.array([-1.0, 1.0]), 0.25 * scale, lag, flip=True)
    assert mirrored.rms_m < 1e-4


@pytest.mark.heavy
def test_a_rendered_flight_on_a_slack_string_is_tracked_by_position(tmp_path):
    """The renderer's slack string (a ball path instead of an angle) seen by the tracker: the ball is followed where
    the string sags, within a pixel, and those frames are slack."""
    from tracking.pipeline import track_video
    from tracking.color import color_spec

    fps, n = 60.0, 50
    t = np.arange(n) / fps
    pivot = np.array([240.0, 60.0])
    ang = np.where(t < 0.4, 0.9, 0.9 + 3 * (t - 0.4))
    r = np.where(t < 0.4, 150.0, 150.0 - 300 * (t - 0.4))  # taut, then flying inward
    ball = pivot + r[:, None] * np.column_stack([np.sin(ang), np.cos(ang)])
    video = tmp_path / "flight.mp4"
    truth = render_pendulum_video(
        video,
        t,
        np.zeros(n),
        pivot,
        string_px=150.0,
        ball_radius_px=8.0,
        size=(480, 360),
        fps=fps,
        ball_path=ball,
        pivot_marker="green",
        distractors=None,
        seed=2,
    )
    track = track_video(video, color_spec("red"), pivot_color=color_spec("green"))
    assert track.found.all()
    assert np.abs(track.uv - truth.ball_uv).max() < 1.0
    mask, _, length = slack_frames(track.uv, track.pivot_uv)
    assert length == pytest.approx(150.0, abs=1.5)
    assert mask[t > 0.6].all() and not mask[t < 0.5].any()
