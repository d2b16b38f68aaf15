"""Tracking accuracy on synthetic 720p 60 FPS videos with known ground truth (blur, noise, mp4v, red distractors)."""

import math

import numpy as np
import pytest

from tracking.color import color_spec
from tracking.pipeline import track_video
from tracking.synthetic import render_pendulum_video
from tracking.tracker import BallTracker
from tracking.video import iter_frames, probe_video

PIVOT = (640.0, 130.0)  # [px]
STRING_PX = 380.0
BALL_RADIUS_PX = 6.5  # a 13 px ball


def swing(duration_s, amplitude_deg=30.0, period_s=1.0, rate_hz=1000.0):
    t = np.arange(int(duration_s * rate_hz) + 1) / rate_hz
    return t, np.radians(amplitude_deg) * np.exp(-0.15 * t) * np.cos(2 * np.pi * t / period_s)


@pytest.fixture(scope="module")
def video_720p(tmp_path_factory):
    """2.5 s, 1280x720, 60 FPS, a 13 px red ball on a 380 px string, a green pivot marker, a red box and cable."""
    path = tmp_path_factory.mktemp("video") / "swing.mp4"
    t, theta = swing(2.5)
    gt = render_pendulum_video(path, t, theta, PIVOT, STRING_PX, BALL_RADIUS_PX, pivot_marker="green", seed=3)
    assert {d.kind for d in gt.distractors} == {"box", "cable"}
    return path, gt


def centre_errors(track, gt):
    return np.linalg.norm(track.uv - gt.ball_uv, axis=1)


@pytest.mark.heavy
def test_goals_fixed_pivot(video_720p):
    path, gt = video_720p
    track = track_video(path, color_spec("red"), pivot_uv=PIVOT)
    assert len(track.t) == len(gt.t)
    err = centre_errors(track, gt)[track.found]
    assert track.found_fraction >= 0.99
    assert math.sqrt(np.mean(err**2)) <= 0.5  # [px]
    assert err.max() < 2.0  # never a distractor
    dtheta = np.degrees(track.theta - gt.theta)[track.found]
    assert math.sqrt(np.mean(dtheta**2)) <= 0.2  # [deg]
    assert track.full_frame_searches <= 3  # the window search holds the ball


@pytest.mark.heavy
def test_goals_tracked_pivot_marker(video_720p):
    path, gt = video_720p
    track = track_video(path, color_spec("red"), pivot_color=color_spec("green"))
    ok = track.found & np.all(np.isfinite(track.pivot_uv), axis=1)
    assert ok.mean() >= 0.99
    assert np.max(np.linalg.norm(track.pivot_uv[ok] - gt.pivot_uv[ok], axis=1)) < 0.5
    dtheta = np.degrees(track.theta - gt.theta)[ok]
    assert math.sqrt(np.mean(dtheta**2)) <= 0.2


def test_timestamps_are_decoder_times(tmp_path):
    path = tmp_path / "small.mp4"  # (a small video of its own: the module's 720p one is for the heavy goal tests)
    t, theta = swing(0.6)
    gt = render_pendulum_video(path, t, theta, (160.0, 20.0), 120.0, 5.0, (320, 180), 60.0, seed=3)
    info = probe_video(path)
    assert info.size == (320, 180) and info.fps == pytest.approx(60.0)
    t = np.array([tk for _, tk, _ in iter_frames(path)])
    assert len(t) == len(gt.t) > 30
    np.testing.assert_allclose(t, gt.t, atol=1e-6)


@pytest.mark.heavy
def test_moving_pivot_and_lost_frames_not_invented(tmp_path):
    """The pivot moves (as the robot's flange does) and the ball leaves the image: those frames are not found."""
    size = (640, 360)
    t = np.linspace(0.0, 2.0, 2001)
    pivot = np.column_stack([320 + 290 * np.sin(np.pi * t / 2.0) ** 2, np.full_like(t, 40.0)])  # moves right
    theta = np.radians(35) * np.sin(2 * np.pi * t / 0.9)
    gt = render_pendulum_video(tmp_path / "out.mp4", t, theta, pivot, 200.0, 6.0, size, pivot_marker="blue", seed=5)
    track = track_video(tmp_path / "out.mp4", color_spec("red"), pivot_color=color_spec("blue"))
    u = gt.ball_uv[:, 0]
    gone = u - gt.ball_radius_px > size[0] + 1  # ball entirely outside the image
    inside = gt.in_frame
    assert gone.sum() >= 5 and inside.sum() >= 60
    assert not track.found[gone].any()
    assert np.all(np.isnan(track.uv[gone])) and np.all(np.isnan(track.theta[gone]))
    assert track.found[inside].mean() >= 0.99
    err = centre_errors(track, gt)[inside & track.found]
    assert math.sqrt(np.mean(err**2)) <= 0.5
    ok = inside & track.found & np.all(np.isfinite(track.pivot_uv), axis=1)
    assert math.sqrt(np.mean(np.degrees(track.theta[ok] - gt.theta[ok]) ** 2)) <= 0.3


def test_tracker_ignores_jumps_then_reacquires():
    """A red disc far from the prediction is not the ball while the ball was just seen (balls do not jump);
    after the coasting time the whole frame is searched and it is found."""
    import cv2

    blank = np.full((360, 640, 3), 160, np.uint8)

    def frame(cx, cy):
        img = blank.copy()
        cv2.circle(img, (int(cx * 16), int(cy * 16)), 7 * 16, (35, 30, 205), -1, cv2.LINE_AA, 4)
        return img

    tr = BallTracker(color_spec("red"))
    for k in range(5):
        b = tr.update(frame(100 + 5 * k, 100), k / 60)
        assert b is not None and abs(b.u - (100 + 5 * k)) < 0.2
    assert tr.update(frame(500, 300), 5 / 60) is None  # a jump of 400 px in one frame: not the ball
    assert tr.update(blank, 6 / 60) is None  # gone: not found, nothing invented
    searches = tr.full_frame_searches
    b = tr.update(frame(500, 300), 4 / 60 + 0.3)  # after max_coast_s (0.25 s) without a fix
    assert b is not None and abs(b.u - 500) < 0.2 and abs(b.v - 300) < 0.2
    assert tr.full_frame_searches == searches + 1


def test_ball_sized_candidates_are_followed_before_fragments():
    """Eight round specks (a codec's fragments of clutter, too small for their shape to tell) and a still ball: the
    ball is among the candidates followed although the specks look rounder, and it is the one taken once it moves."""
    import cv2

    blank = np.full((360, 640, 3), 160, np.uint8)
    for k in range(8):  # perfect discs of 56 px² (ellipse fit 1.0)
        cv2.circle(blank, ((40 + 70 * k) * 16, 40 * 16), 4 * 16, (35, 30, 205), -1, cv2.LINE_AA, 4)

    def frame(cx):  # a ball with a bite out of it (fit ≈ 0.92): the rounder specks came first, and only 6 are followed
        img = blank.copy()
        cv2.circle(img, (int(cx * 16), 250 * 16), 10 * 16, (35, 30, 205), -1, cv2.LINE_AA, 4)
        cv2.rectangle(img, (int(cx) + 6, 240), (int(cx) + 13, 246), (160, 160, 160), -1)
        return img

    tr = BallTracker(color_spec("red"))
    xs = [320.0] * 6 + [320.0 + 4.0 * k for k in range(1, 40)]
    for k, x in enumerate(xs):
        b = tr.update(frame(x), k / 60)
    assert b is not None and abs(b.u - xs[-1]) < 1.0 and abs(b.v - 250) < 1.0 and tr.confidence >= 0.5  # (the bite)
    assert any("took the one at (320, 250)" in n for n in tr.notes), tr.notes


def _distance_to_polyline(p, line):
    a, b = line[:-1], line[1:]
    ab = b - a
    s = np.clip(np.einsum("kj,kj->k", p[None, :] - a, ab) / np.einsum("kj,kj->k", ab, ab), 0, 1)
    return float(np.min(np.linalg.norm(a + s[:, None] * ab - p, axis=1)))


@pytest.mark.heavy
def test_ball_crossing_a_red_cable_next_to_a_red_box(tmp_path):
    """Where the ball merges with a red cable it is lost (not found), and it is never swapped for the cable
    or a red box next to its path; away from the cable it is always found."""
    from tracking.synthetic import Distractor

    cable = np.array([[60.0, 140.0], [200.0, 190.0], [320.0, 215.0], [450.0, 230.0], [620.0, 280.0]])
    box = np.array([[380.0, 165.0], [410.0, 188.0]])  # a small box 20 px off the ball's path
    t = np.linspace(0.0, 2.0, 2001)
    theta = np.radians(40) * np.cos(2 * np.pi * t / 0.9)
    gt = render_pendulum_video(
        tmp_path / "cable.mp4",
        t,
        theta,
        (320, 30),
        200.0,
        6.0,
        (640, 360),
        distractors=[Distractor("cable", cable), Distractor("box", box)],
        seed=9,
    )
    track = track_video(tmp_path / "cable.mp4", color_spec("red"), pivot_uv=(320, 30))
    err = centre_errors(track, gt)
    assert np.nanmax(err) < 2.0  # never a distractor
    clear = np.array([_distance_to_polyline(p, cable) > 6.0 + 3 * 2.5 + 3 for p in gt.ball_uv])
    assert (~clear).sum() >= 5  # the ball does cross the cable
    assert track.found[clear].all()
    assert not track.found[~clear].all()  # merged with the cable: reported lost, not invented


def test_bad_first_fix_does_not_lock_out_the_ball():
    """A fragment (r ≈ 2 px) taken as the ball in the first frames, then the real ball (r = 12 px, 30× the area)
    at the same place: relearned within a few frames, not rejected for good."""
    import cv2

    blank = np.full((360, 640, 3), 160, np.uint8)

    def frame(cx, cy, r):
        img = blank.copy()
        cv2.circle(img, (int(cx * 16), int(cy * 16)), int(r * 16), (35, 30, 205), -1, cv2.LINE_AA, 4)
        return img

    tr = BallTracker(color_spec("red"))
    for k in range(5):
        assert tr.update(frame(200, 150, 2.3), k / 60) is not None
    found = [tr.update(frame(200 + k, 150, 12.0), (5 + k) / 60) for k in range(20)]
    first = next(i for i, b in enumerate(found) if b is not None)
    assert first <= 3
    assert all(b is not None and abs(b.u - (200 + i)) < 0.3 for i, b in enumerate(found) if i >= first)
    assert tr.predict(25 / 60) is not None and abs(tr._current().radius() - 12.0) < 1.0


def test_start_point_names_the_ball_among_two():
    import cv2

    from tracking.tracker import TrackerOptions

    img = np.full((360, 640, 3), 160, np.uint8)
    for c in ((100, 100), (400, 250)):
        cv2.circle(img, c, 9, (35, 30, 205), -1, cv2.LINE_AA)
    tr = BallTracker(color_spec("red"), TrackerOptions(start_uv=(390.0, 260.0)))
    b = tr.update(img, 0.0)
    assert abs(b.u - 400) < 0.5 and abs(b.v - 250) < 0.5 and not tr.resolving
    far = BallTracker(color_spec("red"), TrackerOptions(start_uv=(600.0, 30.0)))
    assert far.update(img, 0.0) is None  # nothing near the start point: not found rather than another blob


def _reported(tr, frames, pivot):
    """Run the tracker over (frame, t) pairs; the per-frame centre it finally reports (revisions applied), or None."""
    out = []
    for k, (img, t) in enumerate(frames):
        b = tr.update(img, t, pivot)
        out.append((b, tr.confidence if b is not None else 0.0))
        for j, rb, c in tr.pop_revision():
            out[j] = (rb, c)
    tr.finish()
    for j, rb, c in tr.pop_revision():
        out[j] = (rb, c)
    return [b if b is not None and c >= tr.options.min_confidence else None for b, c in out]


@pytest.mark.heavy
@pytest.mark.parametrize("decoy", [False, True])
def test_a_codec_ghost_left_where_the_ball_hung_is_not_reported(decoy):
    """A low-bitrate encoder leaves the first frame's ball standing still below the pivot for a few frames while
    the real ball has already swung away (then blocks it out): those still frames are not reported, alone or with
    a second candidate to choose from; the swinging ball after them is."""
    import cv2

    pivot = (640.0, 80.0)
    blank = np.full((720, 1280, 3), 150, np.uint8)

    def frame(*balls):
        img = blank.copy()
        for cx, cy in balls:
            cv2.circle(img, (int(cx * 16), int(cy * 16)), 8 * 16, (35, 30, 205), -1, cv2.LINE_AA, 4)
        return img

    def ball(k):  # swinging on a 400 px string, the ghost's frames included
        th = 0.6 * math.sin(2 * math.pi * k / 60 + 0.3)
        return pivot[0] + 400 * math.sin(th), pivot[1] + 400 * math.cos(th)

    ghost = (pivot[0], pivot[1] + 400.0)
    frames = [(frame(ghost, (1100.0, 150.0)) if decoy and k == 0 else frame(ghost), k / 60) for k in range(5)]
    frames += [(blank, k / 60) for k in range(5, 10)]
    frames += [(frame(ball(k)), k / 60) for k in range(10, 70)]
    got = _reported(BallTracker(color_spec("red")), frames, pivot)
    assert all(b is None for b in got[:10])  # the ghost never reported as the ball
    later = [(b, ball(k)) for k, b in enumerate(got) if k >= 14]
    assert sum(b is not None for b, _ in later) >= 0.95 * len(later)
    assert all(math.hypot(b.u - u, b.v - v) < 0.5 for b, (u, v) in later if b is not None)


@pytest.mark.heavy
def test_a_ball_5_px_across_is_held_at_its_turning_points(tmp_path):
    """A ball 5 px across (defocused, a short exposure, mp4v) outlines less area when it is sharp and still for a
    moment — at a turning point — than while it moves: neither the blob gates' floor nor the learned area may drop
    it there (on main it was lost at the first turning point)."""
    from tracking import scenarios

    sc = scenarios.tiny_ball(tmp_path / "ball5.mp4", (960, 540), 2.0, seed=29, radius_px=2.5)
    track = track_video(sc.path, color_spec("red"), **sc.track_kwargs)
    err = np.linalg.norm(track.uv - sc.truth.ball_uv, axis=1)
    assert not np.any(track.found & (err > 5.0))
    later = sc.counted & (track.t >= 0.2)  # the first frames: a red box is followed until the ball is told apart
    assert track.found[later].all()
    assert np.sqrt(np.mean(err[track.found] ** 2)) < 0.6


def _stretch(first: tuple[float, float], gap: int, start: tuple[float, float], step: tuple[float, float], n: int):
    """A followed candidate's centres: one fix at ``first``, ``gap`` frames not seen, then n fixes from ``start``
    moving by ``step`` [px/frame]."""
    nan = (math.nan, math.nan)
    return [first] + [nan] * gap + [(start[0] + k * step[0], start[1] + k * step[1]) for k in range(n)]


def test_a_follower_that_started_on_an_object_and_went_on_with_the_ball_is_cut_at_the_jump():
    from tracking.tracker import _last_jump

    # judge 4's H.264 70 kbit/s pendulum: a follower started on a red cable at (1236, 364), lost it for 7 frames,
    # then followed the ball from (991, 360); the cable's fix was confirmed with the ball's (350 px off, 0.9)
    assert _last_jump(_stretch((1235.6, 363.7), 7, (990.8, 359.8), (0.3, -2.5), 16), 6.8) == 8
    # the same follower without the gap: judged by the velocity, as before
    assert _last_jump(_stretch((1235.6, 363.7), 0, (990.8, 359.8), (0.3, -2.5), 16), 6.8) == 1
    # a ball seen once, then after a gap where its velocity takes it: one stretch
    moving = _stretch((900.0, 450.0), 4, (920.0, 434.0), (4.0, -3.2), 10)
    assert _last_jump(moving, 6.8) == 0
    # no gap, no jump: one stretch
    assert _last_jump(_stretch((990.0, 360.0), 0, (990.5, 359.0), (0.5, -1.0), 10), 6.8) == 0


def _disc_frame(blank, discs):
    """A copy of blank with red discs (u, v, radius) [px] drawn antialiased at 1/16 px."""
    import cv2

    img = blank.copy()
    for cx, cy, r in discs:
        cv2.circle(img, (int(cx * 16), int(cy * 16)), int(r * 16), (35, 30, 205), -1, cv2.LINE_AA, 4)
    return img


def _swinging(k: int, pivot: tuple[float, float]) -> tuple[float, float]:
    """A ball swinging ±0.9 rad on a 400 px string with a 1.1 s period, frame k at 60 fps [px]."""
    th = 0.9 * math.cos(2 * math.pi * k / 66)
    return pivot[0] + 400 * math.sin(th), pivot[1] + 400 * math.cos(th)


def test_a_tentative_lock_on_a_speck_that_vanished_gives_way_to_the_ball():
    """A low-bitrate encoder's speck of a red cable (r ≈ 2.2 px, round) is all there is in the first frames: a
    tentative lock takes it. When it vanishes and the ball (12× its area) swings far from it, the lock is not
    coasted on (the ball rejected for its area while the gate grows): the whole frame is searched again at once
    (judge 7's H.264 80 kbit/s pendulum from 85°: 73 % of its frames found before)."""
    pivot = (640.0, 80.0)
    blank = np.full((720, 1280, 3), 150, np.uint8)
    frames = [(_disc_frame(blank, [(1228.0, 404.0, 2.2)]), k / 60) for k in range(3)]
    frames += [(_disc_frame(blank, [(*_swinging(k, pivot), 7.0)]), k / 60) for k in range(3, 60)]
    got = _reported(BallTracker(color_spec("red")), frames, pivot)
    assert all(b is None for b in got[:3])  # the speck never reported
    later = [(b, _swinging(k, pivot)) for k, b in enumerate(got) if k >= 6]
    assert all(b is not None and math.hypot(b.u - u, b.v - v) < 0.5 for b, (u, v) in later)


def test_more_objects_than_followers_appearing_beside_a_still_lock_are_judged_without_error():
    """A still ball, locked, and then seven more red discs: only max_candidates are followed, and the recheck's
    candidates are cut to them alike (judge 9's H.264 55 kbit/s pendulum ended in an IndexError)."""
    blank = np.full((360, 640, 3), 150, np.uint8)
    ball = (320.0, 200.0, 7.0)
    others = [(60.0 + 75.0 * k, 60.0, 7.0) for k in range(7)]
    tr = BallTracker(color_spec("red"))
    assert len(others) > tr.options.max_candidates
    frames = [(_disc_frame(blank, [ball]), k / 60) for k in range(45)]
    frames += [(_disc_frame(blank, [ball, *others]), k / 60) for k in range(45, 150)]
    got = _reported(tr, frames, None)
    assert any("ball-like candidates" in n for n in tr.notes)  # the recheck followed candidates and judged them
    assert all(b is not None and abs(b.u - ball[0]) < 0.5 and abs(b.v - ball[1]) < 0.5 for b in got[:45])


@pytest.mark.parametrize("ghost_frame", [18, 28, 31])
def test_a_ghost_of_the_ball_found_after_a_gap_far_from_its_last_fix_is_not_reported(ghost_frame):
    """A confirmed lock misses the ball for four frames (a low-bitrate encoder erased it), then the only red blob in
    the gate is a ghost of the ball's place at another frame, on its path and 130-170 px from it: that fix must earn
    the confirmation again and is reported unsure (judge 9's HEVC 45 kbit/s: such fixes 400-500 px off at confidence
    1); the ball after it is found again."""
    pivot = (640.0, 80.0)
    blank = np.full((720, 1280, 3), 150, np.uint8)
    frames = [(_disc_frame(blank, [(*_swinging(k, pivot), 8.0)]), k / 60) for k in range(40)]
    frames += [(blank, k / 60) for k in range(40, 44)]
    frames += [(_disc_frame(blank, [(*_swinging(ghost_frame, pivot), 8.0)]), 44 / 60)]
    frames += [(_disc_frame(blank, [(*_swinging(k, pivot), 8.0)]), k / 60) for k in range(45, 90)]
    got = _reported(BallTracker(color_spec("red")), frames, pivot)
    assert got[44] is None
    later = [(b, _swinging(k, pivot)) for k, b in enumerate(got) if k >= 48]
    assert sum(b is not None and math.hypot(b.u - u, b.v - v) < 0.5 for b, (u, v) in later) >= 0.85 * len(later)
