"""Obstacle boxes and the clearance of the swept ball."""

from __future__ import annotations

import numpy as np
import pytest

from planners.obstacles import Obstacle, ball_path, clearance

BOX = Obstacle("post", (0.0, 0.0, 0.0), (1.0, 2.0, 3.0))


def test_distance_to_a_box():
    pts = np.array([[0.5, 1.0, 1.0], [2.0, 1.0, 1.0], [-3.0, -4.0, 1.0], [2.0, 3.0, 4.0]])
    np.testing.assert_allclose(BOX.distance(pts), [0.0, 1.0, 5.0, np.sqrt(3.0)])


def test_clearance_reports_the_first_contact_over_all_lengths():
    t = np.arange(5) * 0.1
    pivot = np.column_stack([np.linspace(-1.0, -0.1, 5), np.full(5, 1.0), np.full(5, 2.0)])
    hanging = np.tile([0.0, 0.0, -1.0], (5, 1))
    tilted = np.tile([0.6, 0.0, -0.8], (5, 1))  # swung toward +x
    paths = {0.5: ball_path(pivot, hanging, 0.5), 0.6: ball_path(pivot, tilted, 0.6)}
    c = clearance(t, paths, (BOX,), radius=0.05)
    # the tilted string's ball is 0.36 m ahead of the pivot: it reaches the box (x ≥ 0) first
    assert c.touches and c.obstacle == "post" and c.length == pytest.approx(0.6)
    assert c.time == pytest.approx(0.3)  # pivot at x = −0.325, ball at x = +0.035
    assert c.position[0] == pytest.approx(-0.325 + 0.36)
    # the hanging ball alone clears it by 0.1 − 0.05 m
    c0 = clearance(t, {0.5: paths[0.5]}, (BOX,), radius=0.05)
    assert not c0.touches and c0.clearance == pytest.approx(0.05) and c0.time == pytest.approx(0.4)
    assert clearance(t, paths, (), 0.05) is None
