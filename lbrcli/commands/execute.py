"""`lbr execute`: stream a joint CSV over FRI (thesis §3.4.3 LBRReadWrite) with the TrajectoryPlayer client.

Without --robot the built-in simulator is started in its own process on loopback; a real robot is commanded only
when named with --robot.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any, Optional

import typer

from ..fri_options import (
    DEFAULT_BALL_LENGTH,
    BaudOpt,
    BindOpt,
    LogOpt,
    MqttOpt,
    MqttRateOpt,
    MultiplierOpt,
    PendulumOpt,
    PendZeroOpt,
    PeriodOpt,
    PlotOpt,
    PortOpt,
    RealtimeOpt,
    BusyWaitOpt,
    SimLenientOpt,
    SimFastOpt, SimLockstepOpt,
    TrackingErrorOpt,
    RobotOpt,
    SimStartOpt,
    VersionOpt,
    WaitOpt,
)
from ..cup_options import CupSpecOpt
from ..options import DEFAULT_FLANGE, DtOpt, FlangeOpt, JsonOpt, LimitsOpt, MarginOpt, ToolOpt, number


def check_or_fail(rep, traj, lim, margin: float, t1: bool, robot, name: str):
    """Run `lbr check` on the trajectory; CheckFailed (exit 1, nothing sent) if it fails."""
    from trajectories.errors import CheckFailed

    from .check import print_report, run_check

    report = run_check(traj, lim, margin, False, t1, robot)
    if not report.ok:
        print_report(rep, report, name)
        first = report.failing[0].describe()
        raise CheckFailed(f"{name}: refused, the trajectory fails the limit check ({first}); nothing was sent")
    return report


def _resampled(rep, traj, period_s: float, lim, margin: float, t1: bool, model, name: str):
    from trajectories.resample import resample

    rs = resample(traj, period_s)
    check_or_fail(rep, rs, lim, margin, t1, model, f"{name} resampled to {period_s * 1e3:g} ms")
    rep.print(f"resampled to {period_s * 1e3:g} ms: {len(rs)} rows")
    return rs


def execute(
    joint_csv: Annotated[Path, typer.Argument(help="Joint trajectory t,q1..q7 \\[s, rad]; its step must be the FRI period.")],
    robot: RobotOpt = None,
    port: PortOpt = 30200,
    bind: BindOpt = None,
    log: LogOpt = None,
    fri_version: VersionOpt = None,
    period: PeriodOpt = None,
    resample: Annotated[
        bool, typer.Option("--resample", help="Resample the file (cubic spline) to the controller's period if it differs.")
    ] = False,
    start_tolerance: Annotated[
        float, number("--start-tolerance", low=0, high=0.1, unit="rad",
                      help="Largest |first row − measured position| accepted \\[rad].")
    ] = 1e-3,
    move_to_start: Annotated[
        bool,
        typer.Option(
            "--move-to-start",
            help="If the robot is farther away, first move there (jerk-limited, ≤ 20 % of the limits; input-shaped for "
            "the ball's swing with --length or the simulator's ball).",
        ),
    ] = False,
    settle: Annotated[float, number("--settle", low=0, high=600, unit="s", help="Hold the last row this long before stopping \\[s].")] = 1.0,
    margin: MarginOpt = 0.0,
    t1: Annotated[bool, typer.Option("--t1", help="Also refuse files whose flange speed exceeds T1's 250 mm/s.")] = False,
    length: Annotated[
        Optional[float],
        number(
            "--length", low=0, high=5, unit="m",
            help="String length of the ball on the flange \\[m]: the move to the start is input-shaped (ZVD) for its "
            f"swing period; without --robot also the simulated ball's (default {DEFAULT_BALL_LENGTH}; 0: no ball).",
        ),
    ] = None,
    damping: Annotated[
        float, number("--damping", low=0, high=1000, unit="1/s",
                      help="Simulator only: damping of the simulated ball \\[1/s] (0: it swings on).")
    ] = 0.0,
    cup: CupSpecOpt = None,
    start_sway: Annotated[
        float,
        number(
            "--start-sway", low=0, high=45, low_open=True, unit="deg",
            help="With --move-to-start, hold the first row until the measured sway (the simulated ball, or --pendulum) "
            "has stayed below this for 0.6 of a swing period \\[deg].",
        ),
    ] = 0.2,
    sway_wait: Annotated[
        float,
        number("--sway-wait", low=0, high=3600, unit="s", help="Hold it at most this long, then start and report the sway \\[s] (0: only report)."),
    ] = 30.0,
    sim_start: SimStartOpt = None,
    receive_multiplier: MultiplierOpt = 1,
    wait: WaitOpt = None,
    plot: PlotOpt = None,
    realtime: RealtimeOpt = False,
    busy_wait: BusyWaitOpt = None,
    sim_lenient: SimLenientOpt = True,
    sim_lockstep: SimLockstepOpt = False,
    sim_fast: SimFastOpt = False,
    max_tracking_error: TrackingErrorOpt = None,
    pendulum: PendulumOpt = None,
    baud: BaudOpt = 115200,
    pendulum_zero: PendZeroOpt = 0,
    mqtt: MqttOpt = None,
    mqtt_rate: MqttRateOpt = 50.0,
    flange: FlangeOpt = DEFAULT_FLANGE,
    tool: ToolOpt = None,
    limits: LimitsOpt = None,
    dt: DtOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Stream a joint trajectory over FRI, one row per answered cycle (thesis LBRReadWrite), logging every cycle.

    Before anything is sent the file must pass `lbr check` and its step must equal the controller's period (send
    period × receive multiplier). At the first FRI message and again at activation its first row must be within
    --start-tolerance of the measured position; the stream starts with a short jerk-limited move from where the
    controller holds the robot (input-shaped for the string's swing period when the ball's length is known, so that
    it leaves the ball at rest); then, while the simulated ball (or the --pendulum module) sways more than
    --start-sway, the first row is held, at most --sway-wait. The sway the rows start with is reported. Every command passes the guard. Ctrl-C, SIGTERM, a guard refusal and the end of the
    file are jerk-limited braking stops; a safety stop, drives off, POOR quality or the session leaving
    COMMANDING_ACTIVE end the stream at once. The log's file_rows column (the rows streamed) lets `lbr track film` and
    `lbr compare` tell a completed session from one that stopped early. Exit 0 completed, 1 refused or stopped, 2 bad
    input, 130 Ctrl-C.
    """
    from lbrcli.fri import TrajectoryPlayer
    from lbrcli.lab.attach import LabOptions
    from trajectories.csvio import read_joint_csv
    from trajectories.errors import InputError, OptionError

    from ..console import Reporter
    from ..fri_options import busy_wait_seconds, check_simulator_only
    from ..fri_runner import exit_for, plot_log, print_summary, run_client, simulator_kwargs
    from ..options import limits_from, make_robot, within_limits
    from ..session_end import FILE_ROWS_COLUMN

    rep = Reporter(json_out)
    check_simulator_only(robot, {"--sim-start": sim_start is not None, "--damping": damping != 0.0, "--cup": cup is not None,
                                 "--receive-multiplier": receive_multiplier != 1, "--sim-strict": not sim_lenient, "--sim-lockstep": sim_lockstep, "--sim-fast": sim_fast})  # fmt: skip
    ball = DEFAULT_BALL_LENGTH if length is None and robot is None else length
    if log is not None and log.resolve() == joint_csv.resolve():
        raise OptionError(f"--log {log} is the trajectory file itself; choose another name")
    lim = limits_from(limits)
    within_limits(sim_start, lim, "--sim-start")
    name = str(joint_csv)
    traj = read_joint_csv(joint_csv, dt)
    model = make_robot(flange, tool) if t1 else None
    # 1. the file passes the check before any socket exists
    check_or_fail(rep, traj, lim, margin, t1, model, name)
    rep.print(f"{name}: {len(traj)} rows, step {traj.dt * 1e3:g} ms, {traj.duration:.3f} s — within the limits")

    # 2. the period: the simulator's is ours to choose; with --robot, --period (else the file's step) is assumed and
    #    the first message must agree
    send_ms = traj.dt * 1e3 / receive_multiplier
    if period is None:
        whole = round(send_ms) if len(traj) > 1 else 1
        if len(traj) > 1 and (abs(send_ms - whole) > 1e-6 or not 1 <= whole <= 100) and not (resample and robot is None):
            raise InputError(
                f"time step {traj.dt * 1e3:g} ms is not a whole send period of 1..100 ms"
                + (f" × receive multiplier {receive_multiplier}" if receive_multiplier > 1 else "")
                + "; use --resample with --period",
                file=name,
            )
        period = int(min(100, max(1, whole)))
    period_s = period * receive_multiplier * 1e-3
    if len(traj) > 1 and abs(traj.dt - period_s) > 1e-6:
        if not resample:
            raise InputError(
                f"time step {traj.dt * 1e3:g} ms differs from the command period {period_s * 1e3:g} ms "
                "(send period × receive multiplier); re-plan at that step or use --resample",
                file=name,
            )
        traj = _resampled(rep, traj, period_s, lim, margin, t1, model, name)

    def at_controller_period(period_s: float):
        """--resample with a robot whose period was not given: resample at the first message (and re-check)."""
        from lbrcli.fri import StopSession
        from trajectories.errors import CheckFailed

        try:
            return _resampled(rep, traj, period_s, lim, margin, t1, model, name).q
        except CheckFailed as exc:
            raise StopSession(str(exc), completed=False) from None

    from lbrcli.fri.sway import IoSway, SwayWatch, window_for_length
    from planners.pendulum import natural_period
    from planners.shapers import make_shaper

    player = TrajectoryPlayer(
        traj.q, lim, period_s=period_s, start_tolerance=start_tolerance,
        move_to_start=move_to_start, settle_s=settle, resample=at_controller_period if resample else None,
        move_shaper=make_shaper("zvd", natural_period(ball)) if ball else None,
        move_robot=(model or make_robot(flange, tool)) if ball else None,
        sway=SwayWatch(IoSway("ball_theta"), math.radians(start_sway), window_for_length(ball), sway_wait),
    )  # fmt: skip
    if move_to_start:
        rep.print("a move to the start (≤ 20 % of the limits) precedes the file if the robot stands elsewhere")

    sim_kwargs: dict[str, Any] = {}
    if robot is None:
        sim_kwargs = simulator_kwargs(length=ball, default_length=DEFAULT_BALL_LENGTH, period_ms=int(period),
                                      sim_start=sim_start, default_start=traj.q[0], flange=flange, tool=tool,
                                      max_runtime_s=traj.duration + settle + sway_wait + 120.0, limits=limits)  # fmt: skip
        sim_kwargs.update(receive_multiplier=receive_multiplier, ball_damping=damping)
        if cup is not None:
            from ..cup_options import parse_cup_spec

            if not ball:
                raise OptionError("--cup needs the simulated ball (--length > 0)")
            sim_kwargs["ball_model"] = parse_cup_spec(cup, ball)
    result, sim_stats, lab_figures = run_client(
        rep, player, robot=robot, port=port, bind=bind, version=fri_version, limits=lim, log_path=log, wait=wait,
        sim_kwargs=sim_kwargs, sim_lenient=sim_lenient, sim_lockstep=sim_lockstep, sim_fast=sim_fast, realtime=realtime, busy_wait_s=busy_wait_seconds(busy_wait), max_tracking_error=max_tracking_error, lab=LabOptions(pendulum, baud, pendulum_zero, mqtt, mqtt_rate),
        extra_names=(FILE_ROWS_COLUMN,), extra=lambda state: (len(player.rows),),  # the log tells when it completed
    )  # fmt: skip
    figures = print_summary(rep, result, sim_stats, log)
    figures.update(lab_figures)
    figures.update(file=name, rows=len(traj), duration_s=traj.duration, robot=robot or "simulator")
    plant = (figures.get("simulator") or {}).get("plants", {}).get("ball", {}).get("cup")
    if plant is not None:
        rep.print("simulated ball: " + ("caught in the cup" if plant["caught"] else f"not caught — {plant['failure']}")
                  + " (simulator time)")
    if cup is not None and log is not None:
        from ..cup_log import cup_summary, describe

        summary = cup_summary(log)
        if summary is not None:
            rep.print(describe(summary))
            figures["cup"] = summary
    if robot is not None and result.figures.get("operation_mode") == "TEST_MODE_1" and not t1:
        rep.warn("the robot is in T1: the controller limits the flange speed to 250 mm/s (check with --t1)")
    plot_error = plot_log(plot, log, rep, joint_csv.name, figures)
    rep.emit(figures)
    exit_for(result, lab_figures, mqtt, failed=plot_error)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("execute")(execute)
