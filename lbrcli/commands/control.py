"""`lbr control ...`: feedback controllers at the FRI rate, on the simulator (default) or a named robot.

``lbr control upright``: swing the pendulum module's rod up from hanging and balance it upright for --hold seconds
(thesis ch. 6's module; :mod:`lbrcli.control.upright`). Without --robot the simulator models the module as a rigid rod
on the flange whose 12-bit encoder reaches the client over an emulated serial port with --sim-delay and jitter.
Exit 0 when the rod was balanced for --hold and the arm parked; 1 when it was not; 2 on bad options.

``lbr control damp FILE``: stream a joint CSV (an anti-sway move, or any) while the measured sway of the ball
corrects the TCP's horizontal path (:mod:`lbrcli.control.damping`): the sway a wrong string length leaves decays within
a period or two. Exit 0 when the file was streamed, damped and the arm returned to its last row.
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Optional

import typer

from trajectories.errors import CheckFailed, InputError, OptionError

from ..console import Reporter
from ..fri_options import DEFAULT_BALL_LENGTH, FRI_OPTIONS, LAB_OPTIONS, FriOptions, PlotOpt, StartToleranceOpt
from ..fri_runner import exit_for, plot_log, print_summary, run_client
from ..lab.attach import LabOptions
from ..option_groups import OptionGroup, with_options
from ..options import (DEFAULT_FLANGE, THESIS_Q_START, DtOpt, FlangeOpt, JointVector, JsonOpt, LimitsOpt, ToolOpt,
                       choice, floats, grid, joints, limits_from, make_robot, number, string_length,
                       within_limits)  # fmt: skip
from ..session_settings import LogColumns

if TYPE_CHECKING:  # imported where used: lbrcli.control loads the planners (not for `lbr --help`)
    from ..control.camera_setup import CameraOptions
    from ..control.damp_setup import CameraSetup, DampSetup

UPRIGHT_LAB = LAB_OPTIONS.without("mqtt", "mqtt_rate").replacing(
    pendulum=Annotated[
        Optional[str],
        typer.Option(
            "--pendulum", help="Serial port of the pendulum module (needed with --robot); default: the simulator's."
        ),
    ]
)
DAMP_LAB = LAB_OPTIONS.without("mqtt", "mqtt_rate").replacing(
    pendulum=Annotated[
        Optional[str],
        typer.Option(
            "--pendulum",
            help="Serial port of the pendulum module (--sensor module with --robot); default: the simulator's.",
        ),
    ]
)
DampSimStartOpt = Annotated[
    Optional[JointVector],
    joints("--sim-start", help="Simulator: where the robot stands at start (7 angles); default the first row."),
]


def _pushes(texts: list[str] | None) -> tuple[tuple[float, float], ...]:
    """'10deg@20' → (20.0 s, 0.1745 rad) knocks of the simulated rod."""
    from trajectories.errors import OptionError
    from trajectories.numbers import NotANumber, plain_float

    from ..parsing import parse_angle

    out = []
    for text in texts or ():
        angle, sep, when = str(text).partition("@")
        if not sep:
            raise OptionError(f"--push: expected ANGLE@SECONDS (e.g. 10deg@20), got {text!r}")
        try:
            t = plain_float(when)
        except NotANumber:
            raise OptionError(f"--push: not a time in seconds: {when!r} in {text!r}") from None
        if not t >= 0:
            raise OptionError(f"--push: the time must be >= 0 s, got {when!r}")
        d = parse_angle(angle, "--push")
        if abs(d) > math.pi:
            raise OptionError(f"--push: the angle must be within ±180°, got {angle!r}")
        out.append((t, d))
    return tuple(out)


FIT_WAIT_S = 4.0  # [s] in a lock-step simulation the rod's fit is taken this long after the free swing (simulated
# time): the session then does not depend on how fast this computer fits
UPRIGHT_FLAGS = {
    "RigidModuleSpec.rate_hz": "--sensor-rate", "RigidModuleSpec.delay_ms": "--sim-delay", "RigidModuleSpec.jitter_ms":
    "--sim-jitter", "RigidModuleSpec.pushes": "--push", "RigidModuleSpec.noise_counts": "--sim-noise",
    "RigidModuleSpec.sign": "--sim-encoder-sign", "RigidModuleSpec.zero_count": "--pendulum-zero",
    "UprightClient.move_to_start": "--move-to-start", "SessionOptions.encoder_sign": "--encoder-sign",
    "identify.nominal_length": "--rod-length",
}  # fmt: skip
"""`lbr control upright`'s own flags of the settings its libraries name (``Class.field`` → option)."""


@with_options(fri=FRI_OPTIONS.without("sim_start", "length"), lab=UPRIGHT_LAB, flags=UPRIGHT_FLAGS)
def upright(
    fri: FriOptions,
    lab: LabOptions,
    rod_length: Annotated[
        float,
        number("--rod-length", low=0.1, high=1.5, unit="m", help="Length of the module's rod \\[m] (uniform rod)."),
    ] = 0.5,
    rod_mass: Annotated[float, number("--rod-mass", low=0, high=5, unit="kg", help="Mass of the rod \\[kg].")] = 0.1,
    tip_mass: Annotated[
        float, number("--tip-mass", low=0, high=5, unit="kg", help="Mass at the rod's end \\[kg].")
    ] = 0.0,
    hold: Annotated[
        float,
        number(
            "--hold",
            low=0,
            high=3600,
            unit="s",
            help="Balance upright this long in one run without a fall: the goal \\[s].",
        ),
    ] = 60.0,
    swing_timeout: Annotated[
        float,
        number(
            "--swing-timeout",
            low=1,
            high=600,
            unit="s",
            help="Give up if not caught upright within this long of swinging \\[s].",
        ),
    ] = 30.0,
    recatch: Annotated[
        float,
        number(
            "--recatch",
            low=1,
            high=600,
            unit="s",
            help="After a fall, give up if not caught again within this long \\[s].",
        ),
    ] = 20.0,
    identify: Annotated[
        bool,
        typer.Option(
            "--identify/--no-identify",
            help="Identify the rod (length, friction, the encoder's offset and sign, the delay) from a short push before the swing-up (default), or trust --rod-length and --sensor-delay.",
        ),
    ] = True,
    encoder_sign: Annotated[
        int,
        number(
            "--encoder-sign",
            low=-1,
            high=1,
            integer=True,
            help="The sign the module's encoder counts with: 1, or -1 for one mounted reversed (the identification refuses to go on when they disagree).",
        ),
    ] = 1,
    travel: Annotated[
        float,
        number(
            "--travel",
            low=0.05,
            high=0.5,
            unit="m",
            help="The cart's travel along base y either side of the start \\[m].",
        ),
    ] = 0.4,
    q_start: Annotated[
        JointVector, joints("--q-start", help="The rail's centre pose: 7 joint angles (deg/rad).")
    ] = THESIS_Q_START,
    move_to_start: Annotated[
        bool, typer.Option("--move-to-start", help="Reach --q-start first by a jerk-limited move.")
    ] = False,
    sensor_rate: Annotated[
        float,
        number(
            "--sensor-rate",
            low=10,
            high=10000,
            unit="Hz",
            help="Encoder readings per second on the serial line \\[Hz].",
        ),
    ] = 200.0,
    sensor_delay: Annotated[
        Optional[float],
        number(
            "--sensor-delay",
            low=0,
            high=100,
            unit="ms",
            help="Delay the observer assumes from the encoder sample to its line \\[ms] (default: --sim-delay + half --sim-jitter; 6 with --robot).",
        ),
    ] = None,
    sim_delay: Annotated[
        float,
        number(
            "--sim-delay", low=0, high=100, unit="ms", help="Simulator: encoder-to-serial delay \\[ms] (radio + USB)."
        ),
    ] = 5.0,
    sim_jitter: Annotated[
        float,
        number(
            "--sim-jitter", low=0, high=50, unit="ms", help="Simulator: extra delay, uniform in \\[0, jitter] \\[ms]."
        ),
    ] = 1.0,
    push: Annotated[
        Optional[list[str]],
        typer.Option(
            "--push",
            metavar="ANGLE@SECONDS",
            help="Simulator: knock the rod by ANGLE at SECONDS after the start, e.g. 10deg@20 (repeatable).",
        ),
    ] = None,
    sim_rod_length: Annotated[
        Optional[float],
        number(
            "--sim-rod-length",
            low=0.1,
            high=1.5,
            unit="m",
            help="Simulator: the simulated rod's length \\[m] (default: --rod-length) — a rod the controller does not know.",
        ),
    ] = None,
    sim_friction: Annotated[
        float,
        number(
            "--sim-friction",
            low=0,
            high=0.5,
            help="Simulator: the bearing's dry friction as a share of the rod's peak gravity torque.",
        ),
    ] = 0.0,
    sim_noise: Annotated[
        int,
        number(
            "--sim-noise",
            low=0,
            high=100,
            integer=True,
            help="Simulator: encoder noise, up to ± this many counts per reading.",
        ),
    ] = 0,
    sim_encoder_sign: Annotated[
        int,
        number(
            "--sim-encoder-sign",
            low=-1,
            high=1,
            integer=True,
            help="Simulator: -1 mounts the simulated encoder reversed.",
        ),
    ] = 1,
    plot: PlotOpt = None,
    limits: LimitsOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Swing the pendulum module's rod up and balance it upright (energy swing-up, LQR balance, delay observer).

    The arm moves the module's bearing along base y through --q-start (the thesis start pose: flange along base +x,
    so the rod swings in the y–z plane) within the joints' velocity, acceleration and jerk limits. The encoder angle
    is 0 with the rod hanging (--pendulum-zero) and grows toward base +y. First the rod must hang still; then a short
    push identifies it (its length, friction, the encoder's offset and sign, the delay), the swing-up brings it up,
    the balance holds it for --hold in one run (a fall is caught again within --recatch), and it is lowered gently in
    ever smaller swings before the arm parks. Exit 0 only when the hold was met; 1 otherwise (the reason on stderr).
    """
    from lbrcli.control.upright import LOG_COLUMNS, UprightClient
    from lbrcli.plants.rigid_module import RigidModuleSpec
    from planners.feedback.session import SessionOptions
    from planners.rigid_pendulum import RigidPendulum

    from ..plots.control import plot_upright

    rep = Reporter(json_out)
    pushes = _pushes(push)
    _check_upright(fri, lab, rod_mass + tip_mass, (encoder_sign, sim_encoder_sign), {
        "--push": bool(pushes), "--sim-delay": sim_delay != 5.0, "--sim-jitter": sim_jitter != 1.0,
        "--sim-rod-length": sim_rod_length is not None, "--sim-friction": sim_friction != 0.0, "--sim-noise": sim_noise != 0,
        "--sim-encoder-sign": sim_encoder_sign != 1})  # fmt: skip
    lim = limits_from(limits)
    q0 = within_limits(q_start, lim, "--q-start")
    model = RigidPendulum(rod_length=rod_length, rod_mass=rod_mass, tip_mass=tip_mass)
    rail = _rail(q0, lim, travel)
    assumed_ms = sensor_delay if sensor_delay is not None else (
        sim_delay + 0.5 * sim_jitter if fri.robot is None else 6.0)  # fmt: skip
    fit_wait, fitting = _fitting(fri, identify)
    plan = SessionOptions(hold_s=hold, swing_timeout_s=swing_timeout, recatch_s=recatch, identify=identify,
                          encoder_sign=encoder_sign, sensor_delay_s=assumed_ms * 1e-3, fit_wait_s=fit_wait)  # fmt: skip
    client = UprightClient(rail, model.equivalent_length, lim, session=plan, sensor_rate_hz=sensor_rate,
                           move_to_start=move_to_start)  # fmt: skip
    _print_rail(rep, model, rail, rod_length, travel)
    rod = RigidModuleSpec(simulated_rod(model, sim_rod_length, sim_friction), sensor_rate, sim_delay, sim_jitter, pushes=pushes,
                          zero_count=lab.pendulum_zero, noise_counts=sim_noise, sign=sim_encoder_sign)  # fmt: skip
    simulator = fri.simulator(max_runtime_s=hold + swing_timeout + 3 * recatch + 180.0, start=q0, plants=(rod,),
                              limits=limits)  # fmt: skip
    with fitting() as client.fitter:
        result, sim_stats, lab_figures = run_client(rep, client, fri.session(lim), simulator, lab=replace(lab, pendulum=lab.pendulum or "sim"),
                                                    extra=LogColumns(LOG_COLUMNS, client.log_values))  # fmt: skip
    figures = print_summary(rep, result, sim_stats, fri.log) | lab_figures  # the client's figures join the session's
    _print_upright(rep, figures, model, sim_stats)
    figures.update(rod_length_m=rod_length, equivalent_length_m=model.equivalent_length, hold_s=hold,
                   robot=fri.robot or "simulator", rail_velocity_m_s=rail.limits.velocity,
                   rail_acceleration_m_s2=rail.limits.acceleration)  # fmt: skip
    plot_error = plot_log(plot, fri.log, rep, "upright", figures, draw=plot_upright)
    rep.emit(figures)
    exit_for(result, lab_figures, failed=plot_error)


def _fitting(fri: FriOptions, identify: bool):
    """(the fit's wait [s], a factory of the fitter's context): in a lock-step simulation the rod's fit is taken
    ``FIT_WAIT_S`` of simulated time after the free swing, by a worker that is not niced (the same session on any
    computer); else as soon as a niced worker has it (the FRI loop first)."""
    from lbrcli.control.fitter import ProcessFitter

    paced = fri.robot is None and (fri.sim_lockstep or fri.sim_fast)
    if not identify:
        return 0.0, contextlib.nullcontext
    return FIT_WAIT_S * paced, lambda: contextlib.closing(ProcessFitter(0 if paced else 15))


def _check_upright(
    fri: FriOptions, lab: LabOptions, mass: float, signs: tuple[int, int], sim_only: dict[str, bool]
) -> None:
    """The upright options that do not go together: OptionError (exit 2) naming them."""
    if mass <= 0:
        raise OptionError("--rod-mass and --tip-mass cannot both be 0")
    fri.check_simulator_only(sim_only)
    if fri.robot is not None and not lab.pendulum:
        raise OptionError("--pendulum PORT is needed with --robot (the module's serial port)")
    if fri.robot is None and lab.pendulum not in (None, "sim"):
        raise OptionError("--pendulum: without --robot the simulator's module is used; give --robot to use a real one")
    if 0 in signs:
        raise OptionError("--encoder-sign and --sim-encoder-sign must be 1 or -1")


def _rail(q0, lim, travel: float):
    """The rail along base y through ``q0`` (±``travel`` [m]); CheckFailed (exit 1) when the joints allow none."""
    from planners.rail import build_rail
    from trajectories.robot import Flange, Robot, RobotConfig

    try:
        return build_rail(Robot(RobotConfig(flange=Flange(DEFAULT_FLANGE))), q0, lim, travel)
    except ValueError as exc:
        raise CheckFailed(f"--q-start/--travel: no rail along base y fits the joint limits: {exc}") from None


def simulated_rod(model, length: float | None, friction_share: float):
    """The simulated rod: ``model`` (planners.rigid_pendulum.RigidPendulum), or the same rod ``length`` [m] long
    (one the controller does not know), with dry friction of at least ``friction_share`` of its peak gravity torque."""
    from planners.rigid_pendulum import RigidPendulum

    rod = (
        model if length is None else RigidPendulum(rod_length=length, rod_mass=model.rod_mass, tip_mass=model.tip_mass)
    )
    return replace(rod, coulomb=max(rod.coulomb, friction_share * rod.mass * rod.com * 9.81))


def _print_rail(rep, model, rail, rod_length: float, travel: float) -> None:
    rep.print(f"rod {rod_length:g} m (equivalent length {model.equivalent_length:.3f} m, period {model.natural_period:.3f} s); "
              f"rail ±{travel:g} m, up to {rail.limits.velocity:.2f} m/s, {rail.limits.acceleration:.2f} m/s² anywhere "
              "(more where the joints allow)")  # fmt: skip


def _print_upright(rep, f: dict, model, sim_stats) -> None:
    """What the upright session found: the identified rod, the swing-up and balance, the controller's time. The
    session's verdict (in ``f``) names this command's flags where it names settings, as its end line does."""
    from ..option_groups import name_text

    if f.get("verdict"):
        f["verdict"] = name_text(f["verdict"])
    if f.get("identified_length_m") is not None:
        rep.print(f"identified: equivalent length {f['identified_length_m']:.3f} m (model {model.equivalent_length:.3f} m), "
                  f"dry friction {100 * f['identified_coulomb_share']:.1f} % of its gravity torque, encoder offset "
                  f"{f['encoder_offset_deg']:.2f}°, delay {f['identified_delay_ms']:.1f} ms")  # fmt: skip
    if f.get("swing_up_s") is not None:
        rep.print(f"swing-up {f['swing_up_s']:.2f} s; balanced {f['balanced_s']:.1f} s (longest run {f['longest_balance_s']:.1f} s), "
                  f"catches {f['catches']}, falls {f['falls']}, max |angle from upright| {f['max_theta_balanced_deg']:.2f}° (estimate)")  # fmt: skip
    if f["controller_us_p50"] is not None:
        rep.print(f"controller per cycle: p50 {f['controller_us_p50']:.1f} µs, p99 {f['controller_us_p99']:.1f} µs")
    mod = sim_stats.plants.get("pendulum_module", {}) if sim_stats is not None else {}
    if mod:
        rep.print(
            f"simulated rod: final angle {mod.get('final_phi_deg', math.nan):.2f}° from hanging, "
            f"{mod.get('lines_sent', 0)} encoder lines sent"
        )


CameraOpt = Annotated[
    Optional[str],
    typer.Option(
        "--camera",
        metavar="SOURCE",
        help="With --sensor camera: a V4L2 device index (0) or path (/dev/video0), a stream URL (http://…/stream.mjpg, rtsp://…) or a video file played at its frame rate; default with the simulator: its own camera (--sim-camera-*).",
    ),
]
GeometryOpt = Annotated[
    Optional[Path],
    typer.Option(
        "--geometry",
        help="The camera's pose JSON, as `lbr track live --geometry` reads (camera_matrix, dist_coeffs, rotation, centre_m, image_size — or position_m, look_at_m, fov_deg, image_size); its pivot_m and string_m are not used: the pivot is the robot's TCP, the string is measured.",
    ),
]
CameraPositionOpt = Annotated[
    Optional[tuple],
    floats(
        "--camera-position",
        count=3,
        low=-20,
        high=20,
        unit="m",
        metavar="X,Y,Z",
        help="Instead of --geometry: the camera's centre in the base frame \\[m] (with --camera-look-at, --camera-fov; image size from the source).",
    ),
]
CameraLookAtOpt = Annotated[
    Optional[tuple],
    floats(
        "--camera-look-at",
        count=3,
        low=-20,
        high=20,
        unit="m",
        metavar="X,Y,Z",
        help="The point at the image centre \\[m], base frame.",
    ),
]
CameraFovOpt = Annotated[
    Optional[float],
    number("--camera-fov", low=1, high=170, unit="deg", help="Horizontal field of view \\[deg] (default 50)."),
]
CameraDelayOpt = Annotated[
    Optional[float],
    number(
        "--camera-delay",
        low=0,
        high=1000,
        unit="ms",
        help="The camera's own delay from the middle of a frame's exposure to its arrival here \\[ms], which the tracker cannot see (default: the simulated camera's exposure/2 + latency + 1 ms; 20 with --camera — measure yours).",
    ),
]
SimCameraPositionOpt = Annotated[
    Optional[tuple],
    floats(
        "--sim-camera-position",
        count=3,
        low=-20,
        high=20,
        unit="m",
        metavar="X,Y,Z",
        help="Simulator: its camera's centre \\[m], base frame (default: 30° above the ball's path, 45° around from the base's line to it, as close as sees it whole).",
    ),
]
SimCameraLookAtOpt = Annotated[
    Optional[tuple],
    floats(
        "--sim-camera-look-at",
        count=3,
        low=-20,
        high=20,
        unit="m",
        metavar="X,Y,Z",
        help="Simulator: the point at its camera's image centre \\[m] (default: the middle of the ball's path).",
    ),
]
SimCameraFovOpt = Annotated[
    Optional[float],
    number(
        "--sim-camera-fov",
        low=5,
        high=120,
        unit="deg",
        help="Simulator: its camera's horizontal field of view \\[deg] (default 50).",
    ),
]
SimCameraSizeOpt = Annotated[
    Optional[tuple],
    grid(
        "--sim-camera-size",
        low=64,
        high=4096,
        metavar="WxH",
        help="Simulator: its camera's image size \\[px] (default 320x240).",
    ),
]
SimCameraFpsOpt = Annotated[
    Optional[float],
    number(
        "--sim-camera-fps",
        low=10,
        high=500,
        unit="1/s",
        help="Simulator: its camera's frame rate \\[1/s] (default 120; 30–240 tested).",
    ),
]
SimCameraExposureOpt = Annotated[
    Optional[float],
    number(
        "--sim-camera-exposure",
        low=0,
        high=100,
        unit="ms",
        help="Simulator: its camera's exposure \\[ms] (motion blur; default 4, at most one frame).",
    ),
]
SimCameraLatencyOpt = Annotated[
    Optional[float],
    number(
        "--sim-camera-latency",
        low=0,
        high=500,
        unit="ms",
        help="Simulator: from the end of an exposure to the frame leaving its camera \\[ms] (default 15).",
    ),
]
SimCameraStampOpt = Annotated[
    Optional[bool],
    typer.Option(
        "--sim-camera-stamp/--no-sim-camera-stamp",
        help="Simulator: its camera writes each frame's index into the frame's corner (a camera's embedded frame counter), so a frame's moment is known exactly (default); without it, as with --camera, a frame shows its arrival − --camera-delay.",
    ),
]
SimCameraStopOpt = Annotated[
    Optional[float],
    number(
        "--sim-camera-stop",
        low=0,
        high=3600,
        low_open=True,
        unit="s",
        help="Simulator: its camera stops streaming this long after the simulator started \\[s] (a failure drill).",
    ),
]


def _camera_options(
    camera: CameraOpt = None,
    geometry: GeometryOpt = None,
    camera_position: CameraPositionOpt = None,
    camera_look_at: CameraLookAtOpt = None,
    camera_fov: CameraFovOpt = None,
    camera_delay: CameraDelayOpt = None,
    sim_camera_position: SimCameraPositionOpt = None,
    sim_camera_look_at: SimCameraLookAtOpt = None,
    sim_camera_fov: SimCameraFovOpt = None,
    sim_camera_size: SimCameraSizeOpt = None,
    sim_camera_fps: SimCameraFpsOpt = None,
    sim_camera_exposure: SimCameraExposureOpt = None,
    sim_camera_latency: SimCameraLatencyOpt = None,
    sim_camera_stamp: SimCameraStampOpt = None,
    sim_camera_stop: SimCameraStopOpt = None,
) -> CameraOptions:
    """The camera options of `lbr control damp --sensor camera` (the simulator's camera too), as one value."""
    from ..control.camera_setup import CameraOptions

    return CameraOptions(camera, geometry, camera_position, camera_look_at, camera_fov, camera_delay, sim_camera_position,
                         sim_camera_look_at, sim_camera_fov, sim_camera_size, sim_camera_fps, sim_camera_exposure,
                         sim_camera_latency, sim_camera_stop, sim_camera_stamp)  # fmt: skip


CAMERA_OPTIONS = OptionGroup(_camera_options, flags={
    "CameraOptions.geometry": "--geometry", "CameraOptions.position": "--camera-position",
    "CameraOptions.sim_position": "--sim-camera-position", "CameraSensor.color": "--color"})  # fmt: skip
"""`lbr control damp --sensor camera`: the camera (or the simulator's) and its geometry (:class:`CameraOptions`)."""


@with_options(
    fri=FRI_OPTIONS.without("period", "length").replacing(sim_start=DampSimStartOpt),
    lab=DAMP_LAB,
    cam=CAMERA_OPTIONS,
    flags={"BallSpec.length": "--sim-length"},
)
def damp(
    joint_csv: Annotated[
        Path, typer.Argument(help="Joint trajectory t,q1..q7 \\[s, rad]; its step must be the FRI period.")
    ],
    fri: FriOptions,
    lab: LabOptions,
    cam: CameraOptions,
    length: Annotated[
        Optional[float],
        string_length(
            "--length",
            help="String length the damper assumes (pivot to ball centre) \\[m]; default the simulated ball's.",
        ),
    ] = None,
    damp_time: Annotated[
        Optional[float],
        number(
            "--damp-time",
            low=0,
            high=600,
            unit="s",
            help="Keep damping this long after the last row \\[s] (default 3 swing periods).",
        ),
    ] = None,
    sensor: Annotated[
        str,
        choice(
            "--sensor",
            choices=("io", "module", "camera"),
            help="Where the sway comes from: io (the controller's analog inputs --io-names), module (the pendulum module on --pendulum; one axis) or camera (the ball tracked live in --camera, or the simulator's camera).",
        ),
    ] = "io",
    color: Annotated[
        str,
        typer.Option(
            "--color",
            help="With --sensor camera: the ball's colour (red, orange, yellow, green, cyan, blue, magenta, or a hue range H1-H2).",
        ),
    ] = "red",
    io_names: Annotated[
        str,
        typer.Option(
            "--io-names",
            help="Analog inputs with θx, θy \\[rad] (atan2(s_x, −s_z), atan2(s_y, −s_z) of the string direction s).",
        ),
    ] = "ball_theta_x,ball_theta_y",
    module_axis: Annotated[
        str,
        choice(
            "--module-axis",
            choices=("x", "y"),
            help="With --sensor module: the base axis the module swings along (x or y).",
        ),
    ] = "y",
    sensor_delay: Annotated[
        Optional[float],
        number(
            "--sensor-delay",
            low=0,
            high=500,
            unit="ms",
            help="Age of a reading when it arrives \\[ms] (default: --sim-delay + one period; one period with --robot; with --sensor camera each reading's own age is used, this only where it is unknown; default --camera-delay + 6).",
        ),
    ] = None,
    sensor_rate: Annotated[
        float,
        number(
            "--sensor-rate", low=10, high=10000, unit="Hz", help="With --sensor module: readings per second \\[Hz]."
        ),
    ] = 200.0,
    open_loop: Annotated[
        bool,
        typer.Option(
            "--open-loop", help="Estimate and log the sway but do not correct (the plan alone, for comparison)."
        ),
    ] = False,
    target: Annotated[
        float,
        number(
            "--target",
            low=0.001,
            high=45,
            unit="deg",
            help="The goal: residual sway at most this, fitted over the last swing period of --damp-time \\[deg]; exit 1 above it.",
        ),
    ] = 0.3,
    move_to_start: Annotated[
        bool,
        typer.Option(
            "--move-to-start",
            help="If the robot stands elsewhere, first move there (jerk-limited, input-shaped for the swing).",
        ),
    ] = False,
    start_tolerance: StartToleranceOpt = 1e-3,
    start_sway: Annotated[
        float,
        number(
            "--start-sway",
            low=1e-3,
            high=45,
            unit="deg",
            help="With --move-to-start, hold the first row until the sway stayed below this \\[deg].",
        ),
    ] = 0.2,
    sway_wait: Annotated[
        float, number("--sway-wait", low=0, high=3600, unit="s", help="Hold it at most this long \\[s].")
    ] = 30.0,
    sim_length: Annotated[
        Optional[float],
        string_length(
            "--sim-length", help="Simulator: the ball's true string length \\[m] (default --length, else 0.25)."
        ),
    ] = None,
    sim_delay: Annotated[
        float,
        number(
            "--sim-delay",
            low=0,
            high=200,
            unit="ms",
            help="Simulator: the ball IO shows the ball this much later \\[ms] (camera/encoder link).",
        ),
    ] = 0.0,
    plot: PlotOpt = None,
    flange: FlangeOpt = DEFAULT_FLANGE,
    tool: ToolOpt = None,
    limits: LimitsOpt = None,
    dt: DtOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Stream a joint CSV with active sway damping: the measured ball angle corrects the TCP's path every cycle.

    The file must pass `lbr check` and its step must be the FRI period. From the first row on, an LQR on the
    deviation of the measured sway from the sway the plan itself intends (model with --length) moves the TCP
    horizontally by a few millimetres, inside the joints' velocity and acceleration headroom the file leaves; a
    delay-compensating observer bridges --sensor-delay. After the last row it damps for --damp-time, then a
    jerk-limited move returns the arm to the last row. Log columns as `lbr execute` plus damp_x, damp_y [m] (the
    offset), est_theta_x/y and ref_theta_x/y [rad].

    --sensor camera tracks the ball live in --camera (or, on the simulator, in its own rendered camera) and takes
    the tilt from the camera's geometry, the robot's pivot at each frame's moment and the string length the camera
    measures from the hanging ball. A camera that cannot see the ball along the move, or the sway along an axis the
    move swings it in, is refused before anything is sent (exit 1, as the module on such an axis); a camera that
    fails during the run (stream ended, no frames, ball lost) stops the correction, the rows finish as planned,
    exit 1.
    """
    from lbrcli.control.damp_setup import DampSetup
    from lbrcli.control.damping import LOG_COLUMNS

    rep = Reporter(json_out)
    names = _check_damp(fri, lab, cam, sensor, io_names, length,
                        {"--sim-length": sim_length is not None, "--sim-delay": sim_delay != 0.0})  # fmt: skip
    fri.refuse_log_over(joint_csv)
    lim = limits_from(limits)
    within_limits(fri.sim_start, lim, "--sim-start")
    traj, period_ms = _damp_file(rep, joint_csv, dt, lim)
    model_len = length if length is not None else (sim_length if sim_length is not None else DEFAULT_BALL_LENGTH)
    true_len = sim_length if sim_length is not None else model_len
    setup = DampSetup(make_robot(flange, tool), traj, lim, period_ms * 1e-3, model_len, true_len, damp_time, sensor,
                      names, module_axis, sensor_rate, math.radians(target), open_loop)  # fmt: skip
    if sensor == "module":
        _check_module_axis(setup)
    assumed_ms = sensor_delay if sensor_delay is not None else (
        sim_delay + period_ms if fri.robot is None or sensor == "io" else 6.0 + period_ms)  # fmt: skip
    with contextlib.ExitStack() as camera_stack:  # a camera (and the simulator's) is stopped however this ends
        camera = (_open_camera(setup, cam, rep, camera_stack, lambda: make_robot(flange, tool), fri, color, sensor_delay,
                               move_to_start) if sensor == "camera" else None)  # fmt: skip
        client = setup.client(camera, assumed_ms, start_tolerance=start_tolerance, move_to_start=move_to_start,
                              start_sway_rad=math.radians(start_sway), sway_wait_s=sway_wait)  # fmt: skip
        _print_damp_plan(rep, str(joint_csv), setup, period_ms)
        simulator = fri.simulator(max_runtime_s=traj.duration + setup.damp_s + sway_wait + 120.0, start=traj.q[0], period_ms=period_ms,
                                  ball=setup.ball(sim_delay), plants=setup.plants(camera, sim_delay), flange=flange, tool=tool,
                                  limits=limits)  # fmt: skip
        result, sim_stats, lab_figures = run_client(rep, client, fri.session(lim), simulator, extra=LogColumns(LOG_COLUMNS, client.log_values),
                                                    lab=replace(lab, pendulum=lab.pendulum or "sim") if sensor == "module" else None)  # fmt: skip
        if camera is not None:
            camera.sensor.tracker.stop()
            lab_figures.update(camera.sensor.tracker.summary())
    figures = print_summary(rep, result, sim_stats, fri.log)
    figures.update(lab_figures)  # the client's figures are merged into the session's
    _print_damping(rep, figures, camera is not None, target)
    figures.update(file=str(joint_csv), rows=len(traj), duration_s=traj.duration, string_length_m=model_len,
                   damp_s=setup.damp_s, robot=fri.robot or "simulator", sim_length_m=true_len if fri.robot is None else None)  # fmt: skip
    plot_error = plot_log(plot, fri.log, rep, joint_csv.name, figures)
    rep.emit(figures)
    exit_for(result, lab_figures, failed=plot_error)


def _check_damp(fri: FriOptions, lab: LabOptions, cam: CameraOptions, sensor: str, io_names: str, length: float | None,
                sim_only: dict[str, bool]) -> tuple[str, str]:  # fmt: skip
    """The damper's options that do not go together: OptionError (exit 2) naming them; the two --io-names."""
    _check_camera(cam, sensor, fri.robot)
    if sensor == "camera" and (fri.sim_fast or fri.sim_lockstep):
        flag = "--sim-fast" if fri.sim_fast else "--sim-lockstep"
        raise OptionError(f"{flag}: the simulator's camera films in real time; run --sensor camera without it")
    if sensor == "camera" and sim_only["--sim-delay"]:
        raise OptionError(
            "--sim-delay delays the simulator's ball IO and module; its camera's delay is --sim-camera-latency"
        )
    names = tuple(n.strip() for n in io_names.split(","))
    if len(names) != 2 or not all(names):
        raise OptionError(f"--io-names: expected two analog input names 'theta_x,theta_y', got {io_names!r}")
    if fri.robot is not None and length is None:
        raise OptionError("--length is needed with --robot (the string length the damper assumes)")
    fri.check_simulator_only(sim_only)
    if sensor == "module" and fri.robot is not None and not lab.pendulum:
        raise OptionError("--pendulum PORT is needed with --sensor module and --robot")
    if fri.robot is None and lab.pendulum not in (None, "sim"):
        raise OptionError("--pendulum: without --robot the simulator's module is used; give --robot to use a real one")
    return names  # type: ignore[return-value]


def _check_camera(cam: CameraOptions, sensor: str, robot: str | None) -> None:
    """OptionError (exit 2) on camera options that do not go together (or with --sensor and --robot)."""
    from ..control.camera_setup import SIM_FPS

    if sensor != "camera":
        if any(getattr(cam, f.name) is not None for f in fields(cam)):
            raise OptionError("--camera, --geometry, --camera-* and --sim-camera-* apply to --sensor camera only")
        return
    if robot is not None and cam.source is None:
        raise OptionError("--camera SOURCE is needed with --sensor camera and --robot (a device, URL or file)")
    if cam.sim_given() and (robot is not None or cam.source is not None):
        raise OptionError("--sim-camera-* set the simulator's camera; not with --camera or --robot")
    if cam.geometry is not None and (cam.position is not None or cam.look_at is not None or cam.fov is not None):
        raise OptionError("give the camera's geometry either as --geometry FILE or as --camera-position/"
                          "--camera-look-at/--camera-fov, not both")  # fmt: skip
    if cam.position is None and (cam.look_at is not None or cam.fov is not None):
        raise OptionError("--camera-look-at and --camera-fov need --camera-position")
    if cam.source is not None and cam.geometry is None and cam.position is None:
        raise OptionError("--camera needs the camera's geometry: --geometry CAMERA.json (as `lbr track live`) or "
                          "--camera-position X,Y,Z with --camera-look-at X,Y,Z")  # fmt: skip
    if cam.position is not None and cam.look_at is None and cam.source is not None:
        raise OptionError("--camera-position needs --camera-look-at (where the camera looks) with --camera")
    for name, pos, look in (
        ("--camera", cam.position, cam.look_at),
        ("--sim-camera", cam.sim_position, cam.sim_look_at),
    ):
        if pos is not None and look is not None and math.dist(pos, look) < 0.05:
            raise OptionError(f"{name}-look-at must be at least 5 cm from {name}-position")
    fps = cam.sim_fps if cam.sim_fps is not None else SIM_FPS
    if cam.sim_exposure_ms is not None and cam.sim_exposure_ms > 1e3 / fps:
        raise OptionError(f"--sim-camera-exposure {cam.sim_exposure_ms:g} ms is longer than a frame at {fps:g} fps")


def _damp_file(rep, path: Path, dt: float | None, lim):
    """The joint file, checked (`lbr check`, at least 2 rows, a step of a whole send period 1..100 ms); (trajectory,
    send period [ms])."""
    from lbrcli.fri.players import whole_send_period_ms
    from trajectories.csvio import read_joint_csv

    from .execute import check_or_fail

    traj = read_joint_csv(path, dt)
    check_or_fail(rep, traj, lim, 0.0, False, None, str(path))
    if len(traj) < 2:
        raise InputError("needs at least 2 rows", file=str(path))
    period_ms = whole_send_period_ms(traj.dt)
    if period_ms is None:
        raise InputError(f"time step {traj.dt * 1e3:g} ms is not a whole FRI send period of 1..100 ms; resample it "
                         "(lbr retime) first", file=str(path))  # fmt: skip
    return traj, period_ms


def _check_module_axis(setup: DampSetup) -> None:
    """CheckFailed (exit 1) when the module's rod cannot swing with the ball's sway somewhere along the file: its
    bearing (the flange's z) must lie along the base axis across the sway it is to measure."""
    row, err = setup.module_axis_error()
    if err > math.radians(20.0):
        axis = setup.module_axis
        raise CheckFailed(f"--sensor module: the module's bearing axis is {math.degrees(err):.0f}° off base "
                          f"{'xy'[1 - 'xy'.index(axis)]} at row {row + 1} (t = {setup.traj.t[row]:.3f} s): its rod "
                          f"cannot swing with the ball's sway along {axis} there (a flange pointing down "
                          "keeps it vertical); use --sensor io or a camera, or a move with the flange horizontal "
                          "(e.g. the thesis start pose)")  # fmt: skip


def _open_camera(setup: DampSetup, cam: CameraOptions, rep, stack, robot_factory, fri: FriOptions, color: str,
                 sensor_delay: float | None, move_to_start: bool) -> CameraSetup:  # fmt: skip
    """The camera of --sensor camera, opened (its frame rate and image size are needed, and it must see the ball)."""
    from lbrcli.control.camera_setup import camera_sensor_for
    from lbrcli.control.damp_setup import CameraSetup

    q = setup.traj.q
    q_rest = (
        (fri.sim_start if fri.sim_start is not None else q[0])
        if fri.robot is None
        else (None if move_to_start else q[0])
    )
    return CameraSetup(*camera_sensor_for(
        cam, rep, stack, robot_factory=robot_factory, rows=q, t=setup.traj.t, period_s=setup.period_s,
        accel=setup.plan.planned_accel, model_len=setup.model_length, true_len=setup.true_length,
        target_rad=setup.target_rad, color=color, sensor_delay_ms=sensor_delay, q_rest=q_rest))  # fmt: skip


def _print_damp_plan(rep, name: str, setup: DampSetup, period_ms: int) -> None:
    travel, low, high = setup.offset_room()
    rep.print(f"{name}: {len(setup.traj)} rows, step {period_ms} ms, {setup.traj.duration:.3f} s — within the limits; "
              f"string {setup.model_length:g} m (period {setup.swing_period_s:.3f} s), damping {setup.damp_s:.2f} s after "
              "the last row" + (" (open loop: no correction)" if setup.open_loop else ""))  # fmt: skip
    rep.print(
        f"offset room: up to {travel * 1e3:.0f} mm, {low:.2f}–{high:.2f} m/s² along the file (the joints' headroom)"
    )


def _print_damping(rep, f: dict, camera: bool, target: float) -> None:
    """What the damper did: the offsets, the camera, a sensor fault, the residual sway, its time per cycle."""
    rep.print(f"offset: largest {f['max_offset_m'] * 1e3:.1f} mm, trimmed to the headroom in {f['offset_trimmed_cycles']} "
              f"cycles; return to the last row {f['return_rows']} commands")  # fmt: skip
    if camera:
        from lbrcli.control.camera_setup import print_camera

        print_camera(rep, f)
    if f.get("sensor_fault"):
        rep.warn(f"the sway sensor failed a check: {f['sensor_fault']}")
    if f["measured_residual_deg"] is not None:
        rep.print(f"residual sway (fitted over the last swing period of the damping time): {f['measured_residual_deg']:.3f}° "
                  f"(target {target:g}°; largest single reading {f['peak_residual_reading_deg']:.3f}°)")  # fmt: skip
    if f["controller_us_p50"] is not None:
        rep.print(f"damper per cycle: p50 {f['controller_us_p50']:.1f} µs, p99 {f['controller_us_p99']:.1f} µs")


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    groups["control"].command("upright")(upright)
    groups["control"].command("damp")(damp)
