"""Film and track the ball: the tracker (offline over a video, live from a camera), colours, the camera's geometry
and calibration, the track file, the comparison of a track with the model, and synthetic footage with exact
ground truth.

The names below are the entry points (imported on first use: ``import tracking`` does not load OpenCV).
"""

from trajectories.lazy import lazy_exports

TYPE_CHECKING = False  # typing.TYPE_CHECKING without importing typing (type checkers and griffe read it so)
if TYPE_CHECKING:
    from .calibration import CameraCalibration, calibrate_camera, load_calibration, save_calibration
    from .camera_geometry import CameraGeometry, load_geometry, save_geometry, tilt_from_pixel
    from .color import ColorSpec, color_spec
    from .compare import Comparison, compare_angles, estimate_lag
    from .live import LiveResult, LiveTracker, TiltSetup
    from .pipeline import track_video
    from .synthetic import render_pendulum_video
    from .tracker import BallTracker, TrackerOptions
    from .trackfile import read_track_csv, write_track_csv
    from .video import iter_frames, probe_video

__all__ = [
    "BallTracker", "CameraCalibration", "CameraGeometry", "ColorSpec", "Comparison", "LiveResult", "LiveTracker",
    "TiltSetup", "TrackerOptions", "calibrate_camera", "color_spec", "compare_angles", "estimate_lag",
    "iter_frames", "load_calibration", "load_geometry", "probe_video", "read_track_csv", "render_pendulum_video",
    "save_calibration", "save_geometry", "tilt_from_pixel", "track_video", "write_track_csv",
]  # fmt: skip
__getattr__, __dir__ = lazy_exports(__name__)
