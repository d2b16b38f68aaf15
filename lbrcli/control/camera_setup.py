"""The camera as the damper's sensor: the camera's options (checked together at the CLI edge) turned into the
simulator's camera, the geometry the tracker assumes, and the check that this camera can see the sway the move
makes."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from trajectories.errors import CheckFailed, OptionError

SIM_FPS = 120.0  # [1/s] the simulated camera's defaults
SIM_LATENCY_MS = 15.0
SIM_EXPOSURE_MS = 4.0
SIM_SIZE = (320, 240)  # [px] (with frame stamps the tilt is within 0.05° RMS; 640x480 halves that at twice the CPU)
FOV_DEG = 50.0  # horizontal field of view of a camera given by position and look-at [deg]
REAL_CAMERA_DELAY_MS = 20.0  # assumed exposure-to-arrival delay of a real camera whose delay is not stated
TRACKING_ALLOWANCE_MS = 6.0  # the default sensor delay adds this to the camera's delay (capture → result)
MIN_PX_PER_DEG = 0.25  # [px] a 1° tilt must move the ball at least this far in the image
TRANSFER_MS = 1.0  # the simulated camera's frame: sent → decoded here, about


def observer_bandwidth(fps: float) -> float:
    """The damper's observer bandwidth [rad/s] for camera readings at ``fps`` [1/s]: fps/40 within 2..6. A camera's
    readings are noisier (0.05–0.3° per frame) and later (25–70 ms) than the controller's inputs, and each reading
    corrects the estimate by gains proportional to bandwidth × reading interval: the default 20 rad/s lets 0.15° of
    noise shake the ball by 0.1° and at 30 fps (gain 0.9 per reading) runs away. Offline scans of the crane move
    (string ±20 %, 30–120 fps, 25–60 ms, 0.07–0.3° noise, 10 ms jitter) found 2–4 rad/s best."""
    return min(6.0, max(2.0, fps / 40.0))


@dataclass(frozen=True)
class CameraOptions:
    """The command's camera options as given (None: not given)."""

    source: str | None = None  # the camera's source (None: the embedded simulator's camera)
    geometry: Path | None = None  # the camera geometry JSON (as `lbr track live` reads)
    position: tuple[float, float, float] | None = None  # where the simulated camera stands [m]
    look_at: tuple[float, float, float] | None = None  # the point it looks at [m]
    fov: float | None = None  # its field of view [deg]
    delay_ms: float | None = None  # [ms] the camera's own delay, if the user states it
    sim_position: tuple[float, float, float] | None = None
    sim_look_at: tuple[float, float, float] | None = None
    sim_fov: float | None = None
    sim_size: tuple[int, int] | None = None
    sim_fps: float | None = None
    sim_exposure_ms: float | None = None
    sim_latency_ms: float | None = None
    sim_stop_s: float | None = None
    sim_stamp: bool | None = None  # the simulated camera writes each frame's index into it (default: yes)

    def sim_given(self) -> bool:
        return any(getattr(self, f.name) is not None for f in fields(self) if f.name.startswith("sim_"))


def sim_camera_config(opts: CameraOptions, pivots_m: np.ndarray, string_m: float, sway_rad: np.ndarray):
    """The simulated camera of ``opts`` (lbrcli.lab.camera_stream.CameraConfig); its pose by default sees the ball's
    whole path from 30° above, 45° around from the base's line to it (:func:`tracking.camera_geometry.camera_pose_for`)."""
    from lbrcli.lab.camera_stream import CameraConfig
    from tracking.camera_geometry import camera_pose_for

    size = opts.sim_size or SIM_SIZE
    fov = opts.sim_fov or FOV_DEG
    position, look_at = opts.sim_position, opts.sim_look_at
    if position is None or look_at is None:
        auto_pos, auto_look = camera_pose_for(pivots_m, string_m, sway_rad, fov, size)
        look_at = look_at if look_at is not None else tuple(float(v) for v in auto_look)
        position = position if position is not None else tuple(float(v) for v in auto_pos)
    fps = opts.sim_fps or SIM_FPS
    return CameraConfig(position_m=tuple(position), look_at_m=tuple(look_at), fov_deg=fov, size=tuple(size), fps=fps,
                        stamp=opts.sim_stamp is not False,
                        exposure_s=(opts.sim_exposure_ms if opts.sim_exposure_ms is not None else min(SIM_EXPOSURE_MS, 500.0 / fps)) * 1e-3,
                        latency_s=(opts.sim_latency_ms if opts.sim_latency_ms is not None else SIM_LATENCY_MS) * 1e-3)  # fmt: skip


def camera_delay_ms(opts: CameraOptions, sim_config) -> float:
    """The camera's own delay [ms] from the moment a frame shows to its arrival: the one stated, else the simulated
    camera's half exposure + latency + transfer, else REAL_CAMERA_DELAY_MS."""
    if opts.delay_ms is not None:
        return opts.delay_ms
    if sim_config is not None:
        return (sim_config.exposure_s / 2 + sim_config.latency_s) * 1e3 + TRANSFER_MS
    return REAL_CAMERA_DELAY_MS


def assumed_geometry(opts: CameraOptions, size: tuple[int, int] | None, sim_config):
    """(the geometry the tracker assumes, the setting it comes from): the geometry file, the camera's pose, or the
    simulated camera's own (a perfect calibration). ``size``: the source's image size [px] (for a pose)."""
    from tracking.camera_geometry import CameraGeometry, load_geometry

    if opts.geometry is not None:
        geometry, _ = load_geometry(opts.geometry)
        return geometry, "CameraOptions.geometry"
    if opts.position is not None:
        look = opts.look_at if opts.look_at is not None else sim_config.look_at_m
        return CameraGeometry.from_pose(opts.position, look, opts.fov or FOV_DEG, size), "CameraOptions.position"
    where = "CameraOptions.sim_position" if opts.sim_position is not None else "the simulated camera"
    return sim_config.geometry(), where


def check_view(geometry, where: str, pivots_m: np.ndarray, t_s: np.ndarray, string_m: float, sway_rad: np.ndarray,
               needed: dict[int, float]):  # fmt: skip
    """The camera must see the ball along the whole path and see a tilt along every axis in ``needed`` (axis → the
    move's largest sway along it [rad]); CheckFailed (exit 1, as the module on an axis it cannot see) naming ``where``
    otherwise. The SwayView."""
    from tracking.camera_geometry import sway_view

    w = geometry.image_size[0]
    view = sway_view(geometry, pivots_m, string_m, sway_rad, margin_px=0.02 * w)
    if view.outside is not None:
        k = view.outside
        raise CheckFailed(f"{where}: the camera does not see the ball at t = {t_s[k]:.2f} s of the move (it leaves "
                          f"the {geometry.image_size[0]}x{geometry.image_size[1]} image or is behind the camera)")  # fmt: skip
    for axis, sway in needed.items():
        if view.px_per_deg[axis] < MIN_PX_PER_DEG:
            k = view.worst[axis]
            name = "xy"[axis]
            raise CheckFailed(f"{where}: the camera cannot see the sway along base {name}: a 1° tilt toward {name} "
                              f"moves the ball {view.px_per_deg[axis]:.3f} px in its image at t = {t_s[k]:.2f} s (at "
                              f"least {MIN_PX_PER_DEG:g} px needed), and the move sways the ball up to "
                              f"{math.degrees(sway):.1f}° along {name}; look at the ball from higher up or from "
                              "across that axis")  # fmt: skip
    return view


def camera_sensor_for(opts: CameraOptions, rep, stack, *, robot_factory, rows: np.ndarray, t: np.ndarray,
                      period_s: float, accel: np.ndarray, model_len: float, true_len: float, target_rad: float,
                      color: str, sensor_delay_ms: float | None, q_rest) -> tuple:  # fmt: skip
    """(the damper's CameraSensor, the simulator's camera plant spec or None, the sensor delay the observer assumes
    [ms]) for the joint path ``rows`` (n, 7) [rad] at times ``t`` [s] with the planned TCP accelerations ``accel``
    (n, 2) [m/s²]. The camera — the user's source, or the simulator's, rendering a scene the simulator will write
    (:mod:`lbrcli.plants.camera`; until then the ball of ``true_len`` [m] hangs still at ``q_rest``) — is started
    here and must show the ball; everything started is stopped by ``stack`` (a contextlib.ExitStack). The geometry is
    checked against the move first (CheckFailed: a camera that cannot see the ball or the sway)."""
    from planners.feedback.damping import sway_reference
    from tracking.color import color_spec

    from lbrcli.lab.camera_stream import CameraProcess
    from lbrcli.plants.camera import SceneRing, SimCameraSpec, hanging_scene

    from .camera import CAMERA_NICENESS, CameraTilt
    from .sensors import CameraSensor

    ball = color_spec(color, "CameraSensor.color")
    robot = robot_factory()
    idx = np.unique(np.append(np.arange(0, len(rows), 10), len(rows) - 1))
    pivots, _ = robot.fk_path(np.asarray(rows)[idx])
    ref, _ = sway_reference(np.asarray(accel), model_len, period_s)
    sway = ref[idx]
    peak = np.max(np.abs(ref), axis=0)
    needed = {axis: float(peak[axis]) for axis in (0, 1) if peak[axis] >= target_rad}
    sim_config = sim_camera_config(opts, pivots, model_len, sway) if opts.source is None else None
    delay_ms = camera_delay_ms(opts, sim_config)
    tilt = CameraTilt(opts.source or "", None, robot, ball, model_len, delay_ms * 1e-3, q_rest=q_rest,
                      fps=sim_config.fps if sim_config is not None else None)  # fmt: skip
    spec = None
    if sim_config is not None:  # the geometry is known before anything starts
        geometry, where = assumed_geometry(opts, tuple(sim_config.size), sim_config)
        view = check_view(geometry, where, pivots, np.asarray(t)[idx], model_len, sway, needed)
        ring = SceneRing.create()
        stack.callback(ring.remove)
        hanging_scene(ring, robot.fk(np.asarray(q_rest, float)).translation, true_len)
        camera = CameraProcess(ring, sim_config, opts.sim_stop_s, niceness=CAMERA_NICENESS).start()
        stack.callback(camera.stop)
        tilt.source = camera.url
        tilt.geometry = geometry
        tilt.stamp = (camera.t_start, sim_config.fps) if sim_config.stamp else None
        spec = SimCameraSpec(ring.path)
    stack.callback(tilt.stop)
    tilt.start()
    size = tilt.size
    if sim_config is None:  # a real camera: its image size is known now
        geometry, where = assumed_geometry(opts, size, None)
        view = check_view(geometry, where, pivots, np.asarray(t)[idx], model_len, sway, needed)
        tilt.geometry = geometry
    if tuple(geometry.image_size) != tuple(size):
        raise OptionError(f"{where}: its image is {geometry.image_size[0]}x{geometry.image_size[1]} px, the "
                          f"camera's {size[0]}x{size[1]}")  # fmt: skip
    tilt.view_px_per_deg = view.px_per_deg
    assumed_ms = sensor_delay_ms if sensor_delay_ms is not None else delay_ms + TRACKING_ALLOWANCE_MS
    sensor = CameraSensor(tilt, (0, 1), tilt.fps)
    c = geometry.centre
    rep.print(f"camera: {'the simulator’s, ' if opts.source is None else ''}{tilt.source}, {size[0]}x{size[1]} px at "
              f"{tilt.fps:g} fps, at ({c[0]:.2f}, {c[1]:.2f}, {c[2]:.2f}) m, {geometry.elevation_deg:.0f}° down; a 1° "
              f"tilt moves the ball ≥ {view.px_per_deg[0]:.2f} px (x), ≥ {view.px_per_deg[1]:.2f} px (y); its delay "
              f"{delay_ms:.1f} ms; each reading used with its own age (about {assumed_ms:.0f} ms)")  # fmt: skip
    return sensor, spec, assumed_ms


def print_camera(rep, f: dict) -> None:
    """The camera's figures of a run, for people."""
    if f.get("camera_frames_read") is not None:
        rep.print(f"camera: {f['camera_frames_read']} frames read, {f['camera_frames_tracked']} tracked, "
                  f"{f['camera_frames_dropped']} dropped; ball found in {f['camera_found_percent']:.1f} %; capture → "
                  f"result p50 {f['camera_latency_ms_p50'] or math.nan:.1f} ms, p95 {f['camera_latency_ms_p95'] or math.nan:.1f} ms")  # fmt: skip
    if f.get("camera_string_m") is not None:
        how = ("measured from the hanging ball" if f["camera_string_source"] == "camera"
               else "assumed (no still view of the hanging ball before the first row)")  # fmt: skip
        rep.print(f"camera: string {f['camera_string_m']:.4f} m {how}")
    if f.get("camera_age_ms_p50") is not None:
        rep.print(f"camera: readings used at age p50 {f['camera_age_ms_p50']:.1f} ms, p95 {f['camera_age_ms_p95']:.1f} ms; "
                  f"{f['camera_late_readings']} too old to use (over 0.25 s)")  # fmt: skip
