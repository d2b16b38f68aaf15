"""Checkerboard calibration on synthetic views of a known camera; undistortion; the metric plane; the JSON file."""

import json

import numpy as np
import pytest

from trajectories.errors import InputError
from tracking.calibration import (
    CameraCalibration,
    board_object_points,
    calibrate_camera,
    find_board,
    load_calibration,
    plane_from_corners,
    save_calibration,
    to_plane,
    undistort_points,
)
from tracking.synthetic import render_board_views

K_TRUE = np.array([[600.0, 0.0, 322.0], [0.0, 605.0, 236.0], [0.0, 0.0, 1.0]])
D_TRUE = np.array([-0.25, 0.08, 0.001, -0.0005, 0.0])  # a wide-angle USB camera's barrel distortion
BOARD = (9, 6)
SQUARE = 0.025  # [m]


def poses(n, seed=0):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        rvec = np.radians(rng.uniform(-35, 35, 3)) * np.array([1.0, 1.0, 0.3])
        tvec = np.array([-0.1 + rng.uniform(-0.08, 0.08), -0.07 + rng.uniform(-0.06, 0.06), rng.uniform(0.35, 0.6)])
        out.append((rvec, tvec))
    return out


@pytest.fixture(scope="module")
def calibration():
    views = [find_board(img, BOARD) for img in render_board_views(K_TRUE, D_TRUE, poses(10), BOARD, SQUARE)]
    assert all(v is not None for v in views)
    return calibrate_camera(views, (640, 480), BOARD, SQUARE)


@pytest.mark.heavy
def test_intrinsics_recovered(calibration):
    cal = calibration
    assert cal.rms_px < 0.15
    K = cal.camera_matrix
    assert K[0, 0] == pytest.approx(600.0, rel=0.01) and K[1, 1] == pytest.approx(605.0, rel=0.01)
    assert abs(K[0, 2] - 322.0) < 2.0 and abs(K[1, 2] - 236.0) < 2.0
    assert cal.dist_coeffs[0] == pytest.approx(-0.25, abs=0.03)


def test_undistorted_points_match_the_ideal_camera():
    """Points projected through the distorting lens come back where a distortion-free camera puts them."""
    import cv2

    calibration = CameraCalibration(K_TRUE, D_TRUE, (640, 480), 0.0, BOARD, SQUARE, 10)
    rng = np.random.default_rng(1)
    pts3 = np.column_stack([rng.uniform(-0.25, 0.25, 200), rng.uniform(-0.18, 0.18, 200), np.full(200, 0.6)])
    distorted, _ = cv2.projectPoints(pts3, np.zeros(3), np.zeros(3), K_TRUE, D_TRUE)
    ideal, _ = cv2.projectPoints(pts3, np.zeros(3), np.zeros(3), calibration.camera_matrix, np.zeros(5))
    und = undistort_points(calibration, distorted.reshape(-1, 2))
    err = np.linalg.norm(und - ideal.reshape(-1, 2), axis=1)
    raw = np.linalg.norm(distorted.reshape(-1, 2) - ideal.reshape(-1, 2), axis=1)
    assert raw.max() > 10.0  # the distortion is real …
    assert err.max() < 1e-3  # … and undone (iterated to convergence, even in the corners)
    assert np.isnan(undistort_points(calibration, np.array([np.nan, 1.0]))).all()


def test_plane_gives_metres(calibration):
    """A board in the plane of motion: its corners map back to their positions on the board [m]."""
    rvec, tvec = np.radians([5.0, -8.0, 2.0]), np.array([-0.1, -0.07, 0.5])
    img = render_board_views(K_TRUE, D_TRUE, [(rvec, tvec)], BOARD, SQUARE, seed=4)[0]
    corners = find_board(img, BOARD)
    cal = calibration.with_plane(plane_from_corners(calibration, corners))
    xy = to_plane(cal, corners)
    err = np.linalg.norm(xy - board_object_points(BOARD, SQUARE)[:, :2], axis=1)
    assert err.max() < 0.5e-3  # [m]
    assert cal.plane.metres_per_px == pytest.approx(0.5 / 600.0, rel=0.05)  # distance / focal length


def test_json_round_trip_and_bad_files(calibration, tmp_path):
    p = tmp_path / "cam.json"
    save_calibration(p, calibration)
    back = load_calibration(p)
    np.testing.assert_allclose(back.camera_matrix, calibration.camera_matrix)
    np.testing.assert_allclose(back.dist_coeffs, calibration.dist_coeffs)
    assert back.image_size == (640, 480) and back.board == BOARD and back.plane is None
    d = json.loads(p.read_text())
    d["camera_matrix"] = [[1, 0], [0, 1]]
    p.write_text(json.dumps(d))
    with pytest.raises(InputError, match="camera_matrix"):
        load_calibration(p)
    p.write_text("{not json")
    with pytest.raises(InputError, match="not JSON"):
        load_calibration(p)
    with pytest.raises(InputError, match="file not found"):
        load_calibration(tmp_path / "missing.json")


def test_too_few_views():
    with pytest.raises(InputError, match="at least 3"):
        calibrate_camera([np.zeros((54, 2), np.float32)] * 2, (640, 480), BOARD, SQUARE)
