"""The tracker on hard cases with ground truth (small rendered videos): no lock-in on a bad early fix, no
capture by a round red object, θ in the plane of a tilted camera, fast blurred swing-ups, a skin-coloured
hand beside an orange ball, an occluding rod, slow-motion timing."""

import numpy as np
import pytest

from tracking import scenarios
from tracking.color import color_spec
from tracking.pipeline import track_video


@pytest.mark.heavy
@pytest.mark.parametrize(
    "name",
    [
        "dark_start",
        "red_disc",
        "red_disc_start",
        "orange_hand",
        "occluding_rod",
        "swing_up_60",
        "swing_up_30_short",
        "compressed",
    ],
)
def test_found_without_false_fixes(name, run):
    sc, track, out = run(name)
    assert sc.counted.sum() >= 60
    assert out.false_fixes == 0, (name, out)
    assert out.found_percent >= 99.0, (name, out)
    heavy = name == "compressed"  # JPEG blocks (8 px, colour 16 px) as large as this 9 px ball
    assert out.centre_rms_px <= (1.5 if heavy else 1.0)
    if track.theta is not None:
        assert out.theta_rms_deg <= (0.6 if heavy else 0.5)


def test_dark_start_does_not_lock_out_the_ball(run):
    """A fragment seen in the dark first frames must not become the learned ball for good."""
    sc, track, out = run("dark_start")
    bright = sc.truth.t >= 0.7
    assert track.found[bright].mean() >= 0.99
    err = np.linalg.norm(track.uv - sc.truth.ball_uv, axis=1)
    assert np.all(err[track.found] <= 5.0)  # dark frames: found or not, never somewhere else


def test_static_red_disc_is_not_taken_and_it_is_said(run):
    sc, track, out = run("red_disc")
    assert out.false_fixes == 0 and out.found_percent >= 99.0
    assert len(track.notes) == 1 and "2 ball-like candidates" in track.notes[0], track.notes  # and it is said
    disc = sc.truth.distractors[0].points
    assert np.all(np.linalg.norm(track.uv[track.found] - disc, axis=1) > 10.0)


@pytest.mark.heavy
def test_tilted_camera_theta_in_the_plane(run):
    sc, track, out = run("tilted")
    assert track.theta_in_plane
    assert out.found_percent >= 99.0 and out.false_fixes == 0
    assert out.theta_rms_deg <= 0.2, out
    # without the plane, θ from image pixels is biased by the oblique view
    image_theta = np.arctan2(*(track.uv - sc.track_kwargs["pivot_uv"]).T)
    ok = track.found
    assert np.degrees(np.sqrt(np.mean((image_theta[ok] - sc.truth.theta[ok]) ** 2))) > 1.0
    # metres: the string is 25 cm long in the plane
    pivot_m = np.asarray(sc.truth.pivot_uv[0])  # image px of the pivot
    from tracking.calibration import to_plane

    cal = sc.track_kwargs["calibration"]
    r = np.linalg.norm(track.xy_m[ok] - to_plane(cal, pivot_m[None, :]), axis=1)
    assert np.allclose(r, 0.25, atol=0.002)


@pytest.mark.heavy
def test_slow_motion_fps_override(run):
    sc, track, out = run("slow_motion")
    assert out.found_percent >= 99.0
    np.testing.assert_allclose(track.t, sc.truth.t / sc.time_scale, atol=1e-9)
    assert track.t[1] == pytest.approx(1.0 / 240.0)


@pytest.mark.heavy
def test_long_exposure_swing_up_is_found_where_it_is_and_never_elsewhere(run):
    """30 fps with the shutter open the whole frame: a streak ≈ 30 radii long at the bottom. Found in most
    frames (reported, not a stated goal), and no fix is far off."""
    sc, track, out = run("swing_up_30_long", duration_s=3.0)
    assert sc.adversarial
    assert out.found_percent >= 70.0, out  # 76.9 % before the outlier check, which took 2 fixes out: 5.4 and 3.8 px off
    err = np.linalg.norm(track.uv - sc.truth.ball_uv, axis=1)[track.found]
    assert np.mean(err > 5.0) <= 0.02


def test_static_red_disc_without_pivot_ball_chosen_once_it_moves(run):
    """No pivot given: both are still at first; the choice waits until the ball moves, then the frames
    shown meanwhile are revised to the ball."""
    sc, _, _ = run("red_disc")
    track = track_video(sc.path, color_spec("red"))
    out = scenarios.score(sc, track)
    assert out.false_fixes == 0 and out.found_percent >= 99.0, out
    assert "moving" in track.notes[0]
