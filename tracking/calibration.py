"""Camera calibration from checkerboard views (OpenCV), undistortion of tracked points, metric plane.

findChessboardCorners → cornerSubPix → calibrateCamera gives the intrinsics and lens distortion; only the
tracked points are undistorted (undistortPoints), never whole frames. A board lying in the plane of motion
(solvePnP) maps undistorted pixels to metres in that plane: x along the board's rows of inner corners, y
along its columns, origin at the first inner corner.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Iterator, Sequence

import numpy as np

from trajectories.errors import InputError

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp")


@dataclass(frozen=True)
class PlaneCalibration:
    """The plane of motion: homography from undistorted pixels to plane metres, scale at the board centre."""

    homography: np.ndarray  # (3, 3) undistorted image px → plane (x, y) [m]
    metres_per_px: float  # [m/px] at the board's centre
    rvec: np.ndarray  # (3,) board orientation in the camera frame (Rodrigues) [rad]
    tvec: np.ndarray  # (3,) board origin in the camera frame [m]


@dataclass(frozen=True)
class CameraCalibration:
    """Pinhole intrinsics with OpenCV's distortion model, from `views` checkerboard images."""

    camera_matrix: np.ndarray  # (3, 3) [px]
    dist_coeffs: np.ndarray  # (k,) OpenCV order k1, k2, p1, p2, k3, ...
    image_size: tuple[int, int]  # (width, height) [px]
    rms_px: float  # RMS reprojection error over all corners [px]
    board: tuple[int, int]  # inner corners (columns, rows)
    square_m: float  # square side [m]
    views: int
    plane: PlaneCalibration | None = None

    def with_plane(self, plane: PlaneCalibration | None) -> "CameraCalibration":
        from dataclasses import replace

        return replace(self, plane=plane)


def board_object_points(board: tuple[int, int], square_m: float) -> np.ndarray:
    """(cols·rows, 3) inner-corner positions on the board [m], row by row, z = 0."""
    cols, rows = board
    grid = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2) * square_m
    return np.column_stack([grid, np.zeros(len(grid))]).astype(np.float32)


def find_board(image: np.ndarray, board: tuple[int, int], fast: bool = False) -> np.ndarray | None:
    """Sub-pixel inner corners (cols·rows, 2) [px] of the checkerboard in a BGR or grey image, or None."""
    import cv2

    gray = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE | (cv2.CALIB_CB_FAST_CHECK if fast else 0)
    ok, corners = cv2.findChessboardCorners(gray, board, flags=flags)
    if not ok:
        return None
    # search window ≈ a third of the smallest corner spacing, at least 2 px
    c = corners.reshape(-1, 2)
    spacing = np.min(np.linalg.norm(np.diff(c.reshape(board[1], board[0], 2), axis=1), axis=2))
    win = int(max(2, min(11, spacing / 3)))
    criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_MAX_ITER, 40, 1e-3)  # 40 iterations or 0.001 px
    corners = cv2.cornerSubPix(gray, corners, (win, win), (-1, -1), criteria)
    return corners.reshape(-1, 2).astype(np.float32)


def calibrate_camera(
    views: Sequence[np.ndarray], image_size: tuple[int, int], board: tuple[int, int], square_m: float
) -> CameraCalibration:
    """Intrinsics and distortion (k1, k2, p1, p2, k3) from ≥ 3 views of detected inner corners [px]."""
    import cv2

    if len(views) < 3:
        raise InputError(f"need at least 3 views with the {board[0]}x{board[1]} board found, got {len(views)}")
    obj = board_object_points(board, square_m)
    rms, K, D, _, _ = cv2.calibrateCamera(
        [obj] * len(views), [v.reshape(-1, 1, 2) for v in views], tuple(image_size), None, None
    )
    return CameraCalibration(
        camera_matrix=np.asarray(K, float),
        dist_coeffs=np.asarray(D, float).ravel(),
        image_size=(int(image_size[0]), int(image_size[1])),
        rms_px=float(rms),
        board=(int(board[0]), int(board[1])),
        square_m=float(square_m),
        views=len(views),
    )


def undistort_exact(pts: np.ndarray, K: np.ndarray, D: np.ndarray, P: np.ndarray | None = None) -> np.ndarray:
    """cv2.undistortPoints iterated to convergence (the default 5 iterations leave ~0.1 px at strong distortion).

    pts (n, 1, 2) [px] → (n, 1, 2): normalised coordinates, or pixels of camera matrix P when given.
    """
    import cv2

    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)
    pts = np.ascontiguousarray(pts, dtype=np.float64)
    if hasattr(cv2, "undistortPointsIter"):  # OpenCV 4
        return cv2.undistortPointsIter(pts, K, D, None, P, criteria)
    return cv2.undistortPoints(pts, K, D, None, None, P, criteria)


def undistort_points(cal: CameraCalibration, uv: np.ndarray) -> np.ndarray:
    """Undistorted pixel coordinates (same camera matrix) of (n, 2) or (2,) points [px]; NaN stays NaN."""
    pts = np.asarray(uv, dtype=float)
    flat = pts.reshape(-1, 2)
    out = np.full_like(flat, np.nan)
    ok = np.all(np.isfinite(flat), axis=1)
    if ok.any():
        und = undistort_exact(flat[ok].reshape(-1, 1, 2), cal.camera_matrix, cal.dist_coeffs, cal.camera_matrix)
        out[ok] = und.reshape(-1, 2)
    return out.reshape(pts.shape)


def plane_from_corners(cal: CameraCalibration, corners: np.ndarray) -> PlaneCalibration:
    """The plane of a board view (solvePnP): homography undistorted px → plane [m] and the scale [m/px]."""
    import cv2

    obj = board_object_points(cal.board, cal.square_m)
    ok, rvec, tvec = cv2.solvePnP(obj, corners.reshape(-1, 1, 2), cal.camera_matrix, cal.dist_coeffs)
    if not ok:
        raise InputError("solvePnP failed on the plane view")
    R, _ = cv2.Rodrigues(rvec)
    plane_to_img = cal.camera_matrix @ np.column_stack([R[:, 0], R[:, 1], tvec.ravel()])
    H = np.linalg.inv(plane_to_img)
    H /= H[2, 2]
    centre = undistort_points(cal, corners.reshape(-1, 2)).mean(axis=0)
    pts = np.array([centre, centre + (1.0, 0.0), centre + (0.0, 1.0)])
    xy = apply_homography(H, pts)
    J = np.column_stack([xy[1] - xy[0], xy[2] - xy[0]])
    return PlaneCalibration(
        homography=H, metres_per_px=float(math.sqrt(abs(np.linalg.det(J)))), rvec=rvec.ravel(), tvec=tvec.ravel()
    )


def apply_homography(H: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Points (n, 2) mapped by the 3×3 homography H."""
    pts = np.asarray(pts, float).reshape(-1, 2)
    p = np.column_stack([pts, np.ones(len(pts))]) @ np.asarray(H, float).T
    return p[:, :2] / p[:, 2:3]


def to_plane(cal: CameraCalibration, uv: np.ndarray) -> np.ndarray:
    """Plane coordinates (n, 2) [m] of raw (distorted) image points (n, 2) [px]; needs a plane calibration."""
    if cal.plane is None:
        raise ValueError("calibration has no plane")
    und = undistort_points(cal, np.asarray(uv, float).reshape(-1, 2))
    return apply_homography(cal.plane.homography, und)


# ---------------------------------------------------------------- files


def _list(a: np.ndarray) -> list:
    return np.asarray(a, float).tolist()


def calibration_to_dict(cal: CameraCalibration) -> dict:
    d = {
        "image_size": list(cal.image_size),
        "camera_matrix": _list(cal.camera_matrix),
        "dist_coeffs": _list(cal.dist_coeffs),
        "rms_px": cal.rms_px,
        "board": list(cal.board),
        "square_m": cal.square_m,
        "views": cal.views,
    }
    if cal.plane is not None:
        d["plane"] = {
            "homography": _list(cal.plane.homography),
            "metres_per_px": cal.plane.metres_per_px,
            "rvec": _list(cal.plane.rvec),
            "tvec": _list(cal.plane.tvec),
        }
    return d


def save_calibration(path: str | Path, cal: CameraCalibration) -> None:
    """Write the calibration as JSON (atomically: a temporary name renamed when complete)."""
    from trajectories.atomic import atomic_open

    with atomic_open(path) as fh:
        fh.write(json.dumps(calibration_to_dict(cal), indent=2) + "\n")


def _array(d: dict, key: str, shape: tuple[int, ...] | None, spath: str) -> np.ndarray:
    if key not in d:
        raise InputError(f"missing field '{key}'", file=spath)
    try:
        a = np.asarray(d[key], dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"field '{key}' is not numeric", file=spath) from None
    if shape is not None and a.shape != shape:
        raise InputError(f"field '{key}' must have shape {shape}, got {a.shape}", file=spath)
    if not np.all(np.isfinite(a)):
        raise InputError(f"field '{key}' has non-finite values", file=spath)
    return a


def _scalar(d: dict, key: str, default: float, spath: str) -> float:
    value = d.get(key, default)
    if value is None:
        return default
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"field '{key}' must be a number", file=spath)
    try:
        return float(value)
    except OverflowError:
        raise InputError(f"field '{key}' is out of range", file=spath) from None


def load_calibration(path: str | Path) -> CameraCalibration:
    """Read a calibration JSON written by :func:`save_calibration`; InputError naming the field if malformed."""
    from trajectories.inputs import MAX_SMALL_BYTES, read_text_input

    spath = str(path)
    text = read_text_input(path, MAX_SMALL_BYTES)
    try:
        d = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"not JSON: {exc.msg}", file=spath, row=exc.lineno) from None
    except RecursionError:
        raise InputError("not a calibration: nested too deeply", file=spath) from None
    if not isinstance(d, dict):
        raise InputError("not a calibration object", file=spath)
    K = _array(d, "camera_matrix", (3, 3), spath)
    D = _array(d, "dist_coeffs", None, spath).ravel()
    if len(D) not in (4, 5, 8, 12, 14):
        raise InputError(f"field 'dist_coeffs' must have 4, 5, 8, 12 or 14 values, got {len(D)}", file=spath)
    size = _array(d, "image_size", (2,), spath)
    if not np.all((size >= 1) & (size <= 100_000) & (size == np.round(size))):
        raise InputError("field 'image_size' must be two whole numbers of pixels (1..100000)", file=spath)
    board = _array(d, "board", (2,), spath) if "board" in d else np.array([0, 0])
    if not np.all((board >= 0) & (board <= 1000)):
        raise InputError("field 'board' must be two counts of inner corners (0..1000)", file=spath)
    views = _scalar(d, "views", 0, spath)  # nan fails the range test below
    plane = None
    if d.get("plane") is not None:
        p = d["plane"]
        if not isinstance(p, dict):
            raise InputError("field 'plane' must be an object", file=spath)
        plane = PlaneCalibration(
            homography=_array(p, "homography", (3, 3), spath),
            metres_per_px=float(_array(p, "metres_per_px", (), spath)),
            rvec=_array(p, "rvec", (3,), spath),
            tvec=_array(p, "tvec", (3,), spath),
        )
    return CameraCalibration(
        camera_matrix=K,
        dist_coeffs=D,
        image_size=(int(size[0]), int(size[1])),
        rms_px=_scalar(d, "rms_px", math.nan, spath),
        board=(int(board[0]), int(board[1])),
        square_m=_scalar(d, "square_m", math.nan, spath),
        views=int(views) if 0 <= views <= 1e9 else 0,
        plane=plane,
    )


# ---------------------------------------------------------------- inputs


def iter_images(paths: Iterable[str | Path], video_stride: int = 15) -> Iterator[tuple[str, np.ndarray]]:
    """(name, BGR image) from image files, folders of images and videos (every video_stride-th frame)."""
    import cv2

    from .video import iter_frames

    for p in paths:
        path = Path(p)
        if path.is_dir():
            files = sorted(f for f in path.iterdir() if f.suffix.lower() in IMAGE_SUFFIXES)
            if not files:
                raise InputError("no images in this folder", file=str(path))
            yield from iter_images(files, video_stride)
        elif path.suffix.lower() in IMAGE_SUFFIXES:
            img = cv2.imread(str(path), cv2.IMREAD_COLOR)
            if img is None:
                raise InputError("file not found" if not path.exists() else "not a readable image", file=str(path))
            yield str(path), img
        else:
            for k, _, frame in iter_frames(path):
                if k % video_stride == 0:
                    yield f"{path}#{k}", frame
