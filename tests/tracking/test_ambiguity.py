"""Choosing among ball-like candidates by pendulum motion, and θ in a metric plane (pure functions)."""

import math

import numpy as np

from tracking.ambiguity import choose_pendulum
from tracking.angle import plane_axes, plane_string_angle

PIVOT = np.array([300.0, 50.0])
L = 200.0


def pendulum(theta, pivot=PIVOT):
    return pivot + L * np.column_stack([np.sin(theta), np.cos(theta)])


def test_moving_ball_beats_static_disc_even_when_rounder():
    t = np.arange(30) / 60.0
    ball = pendulum(0.3 * np.sin(2 * math.pi * t))
    disc = np.tile([150.0, 230.0], (30, 1))
    pivots = np.tile(PIVOT, (30, 1))
    c = choose_pendulum([disc, ball], pivots, 6.0, [0.99, 0.9], [220.0, 210.0])
    assert c.index == 1 and "moving" in c.reason


def test_with_a_moving_pivot_the_steady_string_length_wins():
    """The pivot moves: a static disc then 'moves' relative to it; both candidates move in the image here
    (a ball and a ball-sized object on another path), the one at constant distance from the pivot wins."""
    t = np.arange(40) / 60.0
    pivots = np.column_stack([300 + 100 * t, np.full_like(t, 50.0)])
    ball = pendulum(0.2 * np.sin(2 * math.pi * t), pivots)
    other = np.column_stack([100 + 150 * t, 260 - 80 * t])
    c = choose_pendulum([other, ball], pivots, 6.0, [0.95, 0.95])
    assert c.index == 1 and "steadiest" in c.reason


def test_static_candidates_wait_then_hanging_one_wins_and_pale_ones_drop():
    pivots = np.tile(PIVOT, (20, 1))
    hanging = np.tile(pendulum(np.array([0.0]))[0], (20, 1))
    tilted = np.tile(pendulum(np.array([-0.12]))[0], (20, 1))
    assert choose_pendulum([tilted, hanging], pivots, 6.0, [0.99, 0.95], [220.0, 215.0]).index is None  # wait
    c = choose_pendulum([tilted, hanging], pivots, 6.0, [0.99, 0.95], [220.0, 215.0], final=True)
    assert c.index == 1 and "below the pivot" in c.reason
    c = choose_pendulum([tilted, hanging], pivots, 6.0, [0.99, 0.95], [220.0, 110.0], final=True)
    assert c.index == 0 and "paler" in c.reason


def test_undecided_without_pivot_until_final_and_flicker_is_not_motion():
    rng = np.random.default_rng(1)
    a = np.tile([100.0, 100.0], (20, 1))
    hopping = np.array([200.0, 100.0]) + rng.choice([-8.0, 8.0], size=(20, 2))  # a fragment flickering
    c = choose_pendulum([a, hopping], None, 6.0, [0.9, 0.95])
    assert c.index is None
    c = choose_pendulum([a, hopping], None, 6.0, [0.9, 0.95], final=True)
    assert c.index == 1 and "roundest" in c.reason
    gone = np.full((20, 2), np.nan)
    gone[:5] = 50.0
    assert choose_pendulum([a, gone], None, 6.0, [0.5, 0.99]).index == 0


def test_plane_axes_and_angle_under_a_homography():
    # image → plane: rotate by 180° and scale (a board whose first corner is bottom-right), plus perspective
    H = np.array([[-0.001, 0.0, 0.8], [0.0, -0.001, 0.6], [0.0, 0.00002, 1.0]])
    down, right = plane_axes(H, np.array([320.0, 240.0]))
    np.testing.assert_allclose(down, [0.0, -1.0])
    np.testing.assert_allclose(right, [-1.0, 0.0])
    pivot = np.array([0.3, 0.5])
    theta = np.radians([-40.0, 0.0, 25.0])
    ball = pivot + 0.25 * np.column_stack([np.sin(theta), np.cos(theta)]) @ np.vstack([right, down])
    np.testing.assert_allclose(plane_string_angle(ball, pivot, down, right), theta, atol=1e-12)
