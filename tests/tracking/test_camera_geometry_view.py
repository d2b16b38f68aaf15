"""What one camera can tell of a pendulum: the string's length from the hanging ball, how far a 1° tilt moves the
ball in the image along each base axis, whether the ball stays in view, and a pose that sees a whole path."""

import math

import numpy as np
import pytest

from tracking.camera_geometry import (
    CameraGeometry,
    camera_pose_for,
    hanging_length,
    string_direction,
    sway_view,
    tilt_from_pixel,
)

PIVOT = np.array([0.5, 0.1, 0.45])


@pytest.mark.parametrize("position", [(1.3, 0.8, 0.8), (0.2, -0.9, 1.1), (1.5, 0.1, 0.3)])
@pytest.mark.parametrize("length", [0.2, 0.3])
def test_the_hanging_ball_gives_the_string_length(position, length):
    g = CameraGeometry.from_pose(position, (0.5, 0.0, 0.2), 50.0, (640, 480))
    uv = g.project(PIVOT - [0.0, 0.0, length])[0] + np.array([0.1, -0.1])  # a tenth of a pixel of tracking error
    L, gap, angle = hanging_length(g, uv, PIVOT)
    assert abs(L - length) < 2e-3 and gap < 1e-3 and angle > math.radians(30)


def test_a_camera_looking_straight_down_cannot_tell_the_length():
    g = CameraGeometry.from_pose((0.5, 0.1, 2.0), (0.5, 0.1, 0.0), 50.0, (640, 480))
    L, _, angle = hanging_length(g, g.project(PIVOT - [0.0, 0.0, 0.3])[0], PIVOT)
    assert angle < math.radians(1) and not (math.isfinite(L) and angle > math.radians(15))


def test_the_view_of_each_sway_axis():
    # looking along −x, level with the ball: a tilt toward y crosses the image, one toward x only comes closer
    level = CameraGeometry.from_pose((1.6, 0.1, 0.15), (0.5, 0.1, 0.15), 50.0, (640, 480))
    v = sway_view(level, PIVOT[None], 0.3)
    assert v.px_per_deg[0] < 0.1 and v.px_per_deg[1] > 1.5 and v.outside is None
    # from 35° above, 45° around: both axes show, each by about the same
    raised = CameraGeometry.from_pose(PIVOT - [0, 0, 0.3] + 1.2 * np.array([0.58, 0.58, 0.57]), PIVOT - [0, 0, 0.3],
                                      50.0, (640, 480))  # fmt: skip
    v = sway_view(raised, PIVOT[None], 0.3)
    assert min(v.px_per_deg) > 1.0 and max(v.px_per_deg) / min(v.px_per_deg) < 1.5
    # pixels per degree: the string's arc of 1° (L·π/180) seen at the camera's focal length and distance, at most
    f = raised.camera_matrix[0, 0]
    assert max(v.px_per_deg) <= f * 0.3 * math.pi / 180 / 1.1


def test_a_ball_out_of_the_image_is_found():
    g = CameraGeometry.from_pose((1.3, 0.8, 0.8), (0.5, 0.0, 0.2), 10.0, (640, 480))
    path = np.array([[0.5, y, 0.45] for y in np.linspace(-0.3, 0.3, 13)])
    v = sway_view(g, path, 0.25)
    assert v.outside is not None
    inside = g.project(path[v.outside] - [0, 0, 0.25])[0]
    assert not (0 <= inside[0] <= 640 and 0 <= inside[1] <= 480)


def test_a_pose_for_a_path_sees_the_whole_path_and_both_axes():
    path = np.array([[0.4 + 0.2 * s, -0.3 + 0.6 * s, 0.45] for s in np.linspace(0, 1, 30)])
    sway = np.radians(np.column_stack([6 * np.sin(np.linspace(0, 9, 30)), 6 * np.cos(np.linspace(0, 9, 30))]))
    pos, look = camera_pose_for(path, 0.25, sway, 50.0, (320, 240))
    g = CameraGeometry.from_pose(pos, look, 50.0, (320, 240))
    v = sway_view(g, path, 0.25, sway, margin_px=0.08 * 320)
    assert v.outside is None and min(v.px_per_deg) > 0.5
    assert g.elevation_deg == pytest.approx(30.0, abs=3.0)
    # and not farther than needed: 20 % closer, some of the path leaves the frame
    g2 = CameraGeometry.from_pose(look + 0.8 * (pos - look), look, 50.0, (320, 240))
    assert sway_view(g2, path, 0.25, sway, margin_px=0.08 * 320).outside is not None


def test_the_tilt_back_from_the_pixel_with_the_measured_length():
    g = CameraGeometry.from_pose((1.3, 0.8, 0.8), (0.5, 0.0, 0.2), 50.0, (640, 480))
    for tx, ty in ((0.1, -0.05), (-0.08, 0.12)):
        ball = PIVOT + 0.3 * string_direction(tx, ty)
        est = tilt_from_pixel(g, g.project(ball)[0], PIVOT, 0.3)
        assert est.theta_x == pytest.approx(tx, abs=1e-6) and est.theta_y == pytest.approx(ty, abs=1e-6)
