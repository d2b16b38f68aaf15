"""`lbr control ...`: feedback controllers at the FRI rate, on the simulator (default) or a named robot.

``lbr control upright``: swing the pendulum module's rod up from hanging and balance it upright for --hold seconds
(thesis ch. 6's module; :mod:`lbrcli.fri.upright`). Without --robot the simulator models the module as a rigid rod
on the flange whose 12-bit encoder reaches the client over an emulated serial port with --sim-delay and jitter.
Exit 0 when the rod was balanced for --hold and the arm parked; 1 when it was not; 2 on bad options.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any, Optional

import typer

from ..fri_options import (BaudOpt, BindOpt, BusyWaitOpt, LogOpt, PendZeroOpt, PeriodOpt, PlotOpt, PortOpt,
                           RealtimeOpt, RobotOpt, SimLenientOpt, VersionOpt, WaitOpt)  # fmt: skip
from ..options import DEFAULT_FLANGE, THESIS_Q_START, JsonOpt, LimitsOpt


def _pushes(texts: list[str] | None) -> tuple[tuple[float, float], ...]:
    """'10deg@20' → (20.0 s, 0.1745 rad) knocks of the simulated rod."""
    from trajectories.errors import OptionError

    from ..parsing import parse_angle

    out = []
    for text in texts or ():
        angle, sep, when = str(text).partition("@")
        if not sep:
            raise OptionError(f"--push: expected ANGLE@SECONDS (e.g. 10deg@20), got {text!r}")
        try:
            t = float(when)
        except ValueError:
            raise OptionError(f"--push: not a time in seconds: {when!r} in {text!r}") from None
        if not (math.isfinite(t) and t >= 0):
            raise OptionError(f"--push: the time must be >= 0 s, got {when!r}")
        d = parse_angle(angle, "--push")
        if abs(d) > math.pi:
            raise OptionError(f"--push: the angle must be within ±180°, got {angle!r}")
        out.append((t, d))
    return tuple(out)


def upright(
    rod_length: Annotated[float, typer.Option("--rod-length", help="Length of the module's rod \\[m] (uniform rod).")] = 0.5,
    rod_mass: Annotated[float, typer.Option("--rod-mass", help="Mass of the rod \\[kg].")] = 0.1,
    tip_mass: Annotated[float, typer.Option("--tip-mass", help="Mass at the rod's end \\[kg].")] = 0.0,
    hold: Annotated[float, typer.Option("--hold", help="Balance upright this long after the first catch \\[s].")] = 60.0,
    swing_timeout: Annotated[float, typer.Option("--swing-timeout", help="Give up if not caught upright by then \\[s].")] = 30.0,
    travel: Annotated[float, typer.Option("--travel", help="The cart's travel along base y either side of the start \\[m].")] = 0.3,
    q_start: Annotated[str, typer.Option("--q-start", help="The rail's centre pose: 7 joint angles (deg/rad).")] = THESIS_Q_START,
    move_to_start: Annotated[bool, typer.Option("--move-to-start", help="Reach --q-start first by a jerk-limited move.")] = False,
    sensor_rate: Annotated[float, typer.Option("--sensor-rate", help="Encoder readings per second on the serial line \\[Hz].")] = 200.0,
    sensor_delay: Annotated[Optional[float], typer.Option("--sensor-delay", help="Delay the observer assumes from the encoder sample to its line \\[ms] (default: --sim-delay + half --sim-jitter; 6 with --robot).")] = None,
    pendulum: Annotated[Optional[str], typer.Option("--pendulum", help="Serial port of the pendulum module (needed with --robot); default: the simulator's.")] = None,
    baud: BaudOpt = 115200,
    pendulum_zero: PendZeroOpt = 0,
    sim_delay: Annotated[float, typer.Option("--sim-delay", help="Simulator: encoder-to-serial delay \\[ms] (radio + USB).")] = 5.0,
    sim_jitter: Annotated[float, typer.Option("--sim-jitter", help="Simulator: extra delay, uniform in \\[0, jitter] \\[ms].")] = 1.0,
    push: Annotated[Optional[list[str]], typer.Option("--push", help="Simulator: knock the rod by ANGLE at SECONDS after the start, e.g. 10deg@20 (repeatable).")] = None,
    robot: RobotOpt = None,
    port: PortOpt = 30200,
    bind: BindOpt = None,
    log: LogOpt = None,
    fri_version: VersionOpt = None,
    period: PeriodOpt = None,
    wait: WaitOpt = None,
    plot: PlotOpt = None,
    realtime: RealtimeOpt = False,
    busy_wait: BusyWaitOpt = None,
    sim_lenient: SimLenientOpt = False,
    limits: LimitsOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Swing the pendulum module's rod up and balance it upright (energy swing-up, LQR balance, delay observer).

    The arm moves the module's bearing along base y through --q-start (the thesis start pose: flange along base +x,
    so the rod swings in the y–z plane) within the joints' velocity, acceleration and jerk limits. The encoder angle
    is 0 with the rod hanging (--pendulum-zero) and grows toward base +y.
    """
    from lbrcli.fri.upright import LOG_COLUMNS, UprightClient
    from lbrcli.lab.attach import LabOptions
    from lbrcli.plants.rigid_module import RigidModuleSpec
    from planners.rail import build_rail
    from planners.rigid_pendulum import RigidPendulum
    from trajectories.errors import CheckFailed, OptionError
    from trajectories.robot import Flange, Robot, RobotConfig

    from ..console import Reporter
    from ..fri_options import busy_wait_seconds, check_simulator_only, validate_session
    from ..fri_runner import exit_for, print_summary, run_client, simulator_kwargs
    from ..options import check_number, limits_from
    from ..parsing import parse_joint_vector

    rep = Reporter(json_out)
    validate_session(fri_version, port, wait, period, None, busy_wait=busy_wait)
    check_number("--rod-length", rod_length, 0.1, 1.5, unit="m")
    check_number("--rod-mass", rod_mass, 0.0, 5.0, unit="kg")
    check_number("--tip-mass", tip_mass, 0.0, 5.0, unit="kg")
    if rod_mass + tip_mass <= 0:
        raise OptionError("--rod-mass and --tip-mass cannot both be 0")
    check_number("--hold", hold, 0.0, 3600.0, unit="s")
    check_number("--swing-timeout", swing_timeout, 1.0, 600.0, unit="s")
    check_number("--travel", travel, 0.05, 0.5, unit="m")
    check_number("--sensor-rate", sensor_rate, 10.0, 10000.0, unit="Hz")
    check_number("--sim-delay", sim_delay, 0.0, 100.0, unit="ms")
    check_number("--sim-jitter", sim_jitter, 0.0, 50.0, unit="ms")
    if sensor_delay is not None:
        check_number("--sensor-delay", sensor_delay, 0.0, 100.0, unit="ms")
    pushes = _pushes(push)
    check_simulator_only(robot, {"--push": bool(pushes), "--sim-delay": sim_delay != 5.0, "--sim-jitter": sim_jitter != 1.0,
                                 "--sim-lenient": sim_lenient})  # fmt: skip
    if robot is not None and not pendulum:
        raise OptionError("--pendulum PORT is needed with --robot (the module's serial port)")
    if robot is None and pendulum not in (None, "sim"):
        raise OptionError("--pendulum: without --robot the simulator's module is used; give --robot to use a real one")
    q0 = parse_joint_vector(q_start, "--q-start")
    lim = limits_from(limits)
    model = RigidPendulum(rod_length=rod_length, rod_mass=rod_mass, tip_mass=tip_mass)
    robot_model = Robot(RobotConfig(flange=Flange(DEFAULT_FLANGE)))
    try:
        rail = build_rail(robot_model, q0, lim, travel)
    except ValueError as exc:
        raise CheckFailed(f"--q-start/--travel: no rail along base y fits the joint limits: {exc}") from None
    assumed_ms = sensor_delay if sensor_delay is not None else (sim_delay + 0.5 * sim_jitter if robot is None else 6.0)
    client = UprightClient(rail, model.equivalent_length, lim, hold_s=hold, swing_timeout_s=swing_timeout,
                           sensor_delay_s=assumed_ms * 1e-3, sensor_rate_hz=sensor_rate, move_to_start=move_to_start)
    rep.print(f"rod {rod_length:g} m (equivalent length {model.equivalent_length:.3f} m, period {model.natural_period:.3f} s); "
              f"rail ±{travel:g} m, up to {rail.limits.velocity:.2f} m/s, {rail.limits.acceleration:.2f} m/s² anywhere "
              "(more where the joints allow)")  # fmt: skip
    sim_kwargs: dict[str, Any] = {}
    plants = None
    if robot is None:
        sim_kwargs = simulator_kwargs(length=0.0, default_length=0.0, period_ms=period or 1, sim_start=None,
                                      default_start=tuple(float(v) for v in q0), flange=DEFAULT_FLANGE, tool=None,
                                      max_runtime_s=hold + swing_timeout + 120.0, limits=limits)  # fmt: skip
        plants = (RigidModuleSpec(model, sensor_rate, sim_delay, sim_jitter, pushes=pushes, zero_count=pendulum_zero),)
    lab = LabOptions(pendulum or "sim", baud, pendulum_zero)
    result, sim_stats, lab_figures = run_client(
        rep, client, robot=robot, port=port, bind=bind, version=fri_version, limits=lim, log_path=log, wait=wait,
        sim_kwargs=sim_kwargs, realtime=realtime, busy_wait_s=busy_wait_seconds(busy_wait), sim_lenient=sim_lenient,
        lab=lab, plants=plants, extra_names=LOG_COLUMNS, extra=client.log_values,
    )  # fmt: skip
    figures = print_summary(rep, result, sim_stats, log)
    figures.update(lab_figures)
    f = client.figures()
    if f["swing_up_s"] is not None:
        rep.print(f"swing-up {f['swing_up_s']:.2f} s; balanced {f['balanced_s']:.1f} s (longest {f['longest_balance_s']:.1f} s), "
                  f"falls {f['falls']}, max |angle from upright| {f['max_theta_balanced_deg']:.2f}° (estimate)")  # fmt: skip
    if f["controller_us_p50"] is not None:
        rep.print(f"controller per cycle: p50 {f['controller_us_p50']:.1f} µs, p99 {f['controller_us_p99']:.1f} µs")
    if sim_stats is not None:
        mod = sim_stats.plants.get("pendulum_module", {})
        if mod:
            rep.print(f"simulated rod: final angle {mod.get('final_phi_deg', math.nan):.2f}° from hanging, "
                      f"{mod.get('lines_sent', 0)} encoder lines sent")
    figures.update(rod_length_m=rod_length, equivalent_length_m=model.equivalent_length, hold_s=hold,
                   robot=robot or "simulator", rail_velocity_m_s=rail.limits.velocity,
                   rail_acceleration_m_s2=rail.limits.acceleration)  # fmt: skip
    if plot is not None:
        if log is None:
            rep.warn("--plot needs --log (the plot is drawn from the log); no plot written")
        else:
            from ..plots.control import plot_upright

            plot_upright(Path(log), Path(plot))
            rep.print(f"plot: {plot}")
    rep.emit(figures)
    exit_for(result, lab_figures)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    groups["control"].command("upright")(upright)
