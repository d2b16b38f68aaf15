"""`lbr execute`, `lbr monitor`, `lbr ptp`: the FRI client applications (thesis §3.4.3 LBRReadWrite, LBRMonitor,
LBRJointPTP) on the pure-Python FRI session. Without --robot they run against the built-in simulator, started in
its own process on loopback; a real robot is commanded only when named with --robot.
"""

from __future__ import annotations

import contextlib
import math
from pathlib import Path
from typing import Annotated, Any, Callable, Optional

import typer

from ..options import DEFAULT_FLANGE, DtOpt, FlangeOpt, JsonOpt, LimitsOpt, ToolOpt

DEFAULT_BALL_LENGTH = 0.25  # [m] string length of the simulated ball without --length

RobotOpt = Annotated[
    Optional[str],
    typer.Option(
        "--robot",
        help="The robot controller's FRI address (thesis lab: 192.170.10.2). The ONLY way a real robot is "
        "commanded; without it the built-in simulator is started on loopback.",
    ),
]
PortOpt = Annotated[
    int, typer.Option("--port", help="Local UDP port from the robot's FRI configuration (0: any free port, simulator).")
]
BindOpt = Annotated[
    Optional[str],
    typer.Option("--bind", help="Local address to bind (default: all interfaces; 127.0.0.1 with the simulator)."),
]
VersionOpt = Annotated[str, typer.Option("--fri-version", help="FRI wire format of the controller: 1.15 or 2.7.")]
LogOpt = Annotated[
    Optional[Path],
    typer.Option("--log", help="Execution log CSV, one row per monitoring message (valid after any ending)."),
]
WaitOpt = Annotated[
    Optional[float],
    typer.Option("--wait", help="Seconds to wait for the first FRI message \\[s] (default 60 with --robot, 20 simulated)."),
]
PeriodOpt = Annotated[
    Optional[int],
    typer.Option(
        "--period",
        help="Send period \\[ms]: the simulator's (default: the file's step), or with --robot the period the "
        "controller must have.",
    ),
]
LengthOpt = Annotated[
    Optional[float],
    typer.Option("--length", help=f"Simulated ball string length \\[m] (default {DEFAULT_BALL_LENGTH}; 0: no ball)."),
]
SimStartOpt = Annotated[
    Optional[str],
    typer.Option("--sim-start", help="Simulator only: where the simulated robot stands at start (7 angles, deg/rad)."),
]
MultiplierOpt = Annotated[
    int, typer.Option("--receive-multiplier", help="Simulator only: the client answers every k-th message.")
]
RealtimeOpt = Annotated[
    bool,
    typer.Option(
        "--realtime",
        help="Run the FRI loop with real-time scheduling (SCHED_FIFO, needs CAP_SYS_NICE or root); steadier 1 ms under load.",
    ),
]
PlotOpt = Annotated[
    Optional[Path], typer.Option("--plot", help="PNG: commanded vs measured joints, tracking, simulated ball sway.")
]


PendulumOpt = Annotated[
    Optional[str],
    typer.Option("--pendulum", help="Serial port of the pendulum module (thesis ch. 6, e.g. /dev/ttyUSB0); 'sim': the "
                 "simulator's emulated module on a pseudo-terminal. Logs pend_theta \\[rad], pend_omega \\[rad/s]."),
]
BaudOpt = Annotated[int, typer.Option("--baud", help="Baud rate of the pendulum module's serial port.")]
PendZeroOpt = Annotated[int, typer.Option("--pendulum-zero", help="Encoder count (0..4095) of the hanging pendulum.")]
MqttOpt = Annotated[
    Optional[str],
    typer.Option("--mqtt", help="Publish the state as JSON to mqtt://HOST:PORT/TOPIC (off the FRI loop; see `lbr listen`)."),
]
MqttRateOpt = Annotated[float, typer.Option("--mqtt-rate", help="Telemetry messages per second \\[Hz].")]


# -- shared pieces --------------------------------------------------------------------------------------------
def _validate_version(version: str) -> str:
    from trajectories.errors import OptionError

    if version not in ("1.15", "2.7"):
        raise OptionError(f"--fri-version must be 1.15 or 2.7, got {version!r}")
    return version


def _validate_port(port: int) -> None:
    from trajectories.errors import OptionError

    if not 0 <= port <= 65535:
        raise OptionError(f"--port: not a UDP port: {port}")


def _run_session(
    rep,
    *,
    robot: str | None,
    port: int,
    bind: str | None,
    version: str,
    limits,
    log_path: Path | None,
    wait: float | None,
    sim_kwargs: dict[str, Any],
    prepare=None,
    duration_s: float | None = None,
    extra_names: tuple[str, ...] = (),
    extra: Callable | None = None,
    commanding_timeout_s: float | None = None,
    realtime: bool = False,
    lab=None,
):
    """Bind, start the simulator if no robot was named, attach the pendulum module and telemetry, run the session,
    stop everything; (result, sim stats, lab figures)."""
    from lbrcli.fri.client import FriSession, sigint_interrupts
    from lbrcli.fri.log import ExecutionLog

    embedded = robot is None
    session = FriSession(
        "127.0.0.1" if embedded else robot,
        port,
        bind_host=bind if bind is not None else ("127.0.0.1" if embedded else ""),
        version=version,
        limits=limits,
        first_message_timeout_s=wait if wait is not None else (20.0 if embedded else 60.0),
        commanding_timeout_s=commanding_timeout_s if commanding_timeout_s is not None else (20.0 if embedded else None),
    )
    sim = None
    sim_stats = None
    log = None
    attached = None
    lab_figures: dict[str, Any] = {}
    if lab is not None:
        lab.validate(embedded)
    try:
        if log_path is not None:
            log = ExecutionLog(log_path)
        if embedded:
            from lbrcli.fri.simulator import SimConfig, SimulatorProcess

            if realtime and "realtime" in SimConfig.__dataclass_fields__:
                sim_kwargs = {**sim_kwargs, "realtime": True}
            if lab is not None and lab.pendulum == "sim":
                sim_kwargs = {**sim_kwargs, "pendulum_pty": True}
            sim = SimulatorProcess(SimConfig(client_port=session.port, version=version, **sim_kwargs))
            sim.start()
            rep.print(f"simulator on {sim.address[0]}:{sim.address[1]} → client on 127.0.0.1:{session.port}")
        else:
            rep.print(f"waiting for FRI messages from {session.robot_ip} on UDP port {session.port} …")
        tap = None
        if lab is not None and (lab.pendulum or lab.mqtt):
            from lbrcli.lab.attach import LabAttachments

            path = sim.pendulum_path if lab.pendulum == "sim" else lab.pendulum
            attached = LabAttachments(lab, path).start()
            if attached.pendulum is not None:
                rep.print(f"pendulum module on {path}")
                base_names, base_extra = extra_names, extra
                extra_names = tuple(base_names) + attached.extra_names
                extra = (lambda mon: (*base_extra(mon), *attached.extra(mon))) if base_extra else attached.extra
            if attached.publisher is not None:
                rep.print(f"telemetry to {lab.mqtt} at {lab.mqtt_rate_hz:g} Hz")
                tap = attached.tap
        with sigint_interrupts(session), _realtime(rep, realtime):
            result = session.run(
                prepare,
                log,
                duration_s=duration_s,
                extra_names=extra_names,
                extra=extra,
                watchdog=(lambda: None if sim.running else "the simulator process ended") if sim is not None else None,
                tap=tap,
            )
    finally:
        session.close()
        if attached is not None:
            attached.stop()
            lab_figures = attached.summary()
            rep.print("lab: " + ", ".join(f"{k} {v}" for k, v in lab_figures.items()))
        if sim is not None:
            try:
                sim_stats = sim.stop()
            except Exception as exc:  # the session's own outcome matters more
                rep.warn(f"simulator: {exc}")
        if log is not None:
            log.close()
    return result, sim_stats, lab_figures


@contextlib.contextmanager
def _realtime(rep, wanted: bool):
    """SCHED_FIFO for the FRI loop if wanted and permitted (a warning otherwise); normal scheduling afterwards."""
    import os

    if not wanted:
        yield
        return
    try:
        old = os.sched_getscheduler(0), os.sched_getparam(0)
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(20))
    except (AttributeError, PermissionError, OSError):
        rep.warn("real-time scheduling was not granted (needs CAP_SYS_NICE); running with normal priority")
        yield
        return
    try:
        yield
    finally:
        os.sched_setscheduler(0, old[0], old[1])


def _deg(x: float | None) -> float | None:
    return None if x is None else math.degrees(x)


def _print_summary(rep, result, sim_stats, log_path: Path | None) -> dict[str, Any]:
    """Human summary and the figures for --json."""
    from lbrcli.fri.constants import SessionState

    r = result
    states = " → ".join(SessionState(s).name for s in r.states_seen)
    period = f"{r.period_s * 1e3:g} ms" if r.period_s else "?"
    rep.print(f"session: {states}")
    rep.print(f"ended: {r.end_reason} ({r.outcome})")
    rep.print(
        f"cycles {r.cycles} (period {period}), answered {r.answered}, missed {r.missed}, "
        f"stale {r.stale}, foreign {r.foreign}, malformed {r.malformed}"
    )
    if r.prepare_ms is not None:
        skipped = f"; {r.skipped} messages that queued meanwhile were dropped" if r.skipped else ""
        rep.print(f"start checks and planning at the first session message: {r.prepare_ms:.1f} ms{skipped}")
    if r.move_rows or r.trajectory_rows or r.settle_rows:
        rep.print(f"commanded: {r.move_rows} move-to-start rows, {r.trajectory_rows} trajectory rows, {r.settle_rows} settle rows")
    if r.min_tracking is not None:
        rep.print(f"min tracking performance {r.min_tracking:.4f} over {r.active_cycles} COMMANDING_ACTIVE cycles")
    if r.max_tracking_error is not None:
        prev = r.max_tracking_error_prev
        lag = f", {prev:.3e} rad against the previous cycle's command" if prev is not None else ""
        rep.print(f"max |measured − commanded| {r.max_tracking_error:.3e} rad (same cycle){lag}")
    if r.max_ball_theta is not None:
        resid = f", residual {_deg(r.residual_ball_theta):.3f}°" if r.residual_ball_theta is not None else ""
        rep.print(f"ball sway: max {_deg(r.max_ball_theta):.3f}°{resid}")
    if r.latency_p50_ms is not None:
        rep.print(
            f"reply latency p50 {r.latency_p50_ms:.3f} ms, p99 {r.latency_p99_ms:.3f} ms, max {r.latency_max_ms:.3f} ms; "
            f"CPU {r.cpu_us_per_cycle:.1f} µs per cycle"
        )
    if log_path is not None:
        rep.print(f"log: {log_path} ({r.log_rows} rows)")
    figures = r.to_dict()
    figures["max_ball_theta_deg"] = _deg(r.max_ball_theta)
    figures["residual_ball_theta_deg"] = _deg(r.residual_ball_theta)
    figures["log"] = str(log_path) if log_path is not None else None
    if sim_stats is not None:
        figures["simulator"] = sim_stats.to_dict()
    return figures


def _exit_for(result) -> None:
    from lbrcli.fri.client import INTERRUPTED

    if result.ok:
        return
    raise typer.Exit(130 if result.outcome == INTERRUPTED else 1)


def _check_or_fail(rep, traj, lim, margin: float, t1: bool, robot, name: str) -> None:
    from trajectories.errors import CheckFailed

    from .check import print_report, run_check

    report = run_check(traj, lim, margin, False, t1, robot)
    if not report.ok:
        print_report(rep, report, name)
        first = report.failing[0].describe()
        raise CheckFailed(f"{name}: refused, the trajectory fails the limit check ({first}); nothing was sent")
    return report


def _plot(path: Path | None, log_path: Path | None, rep, title: str) -> None:
    if path is None:
        return
    if log_path is None:
        rep.warn("--plot needs --log (the plot is drawn from the log); no plot written")
        return
    from ..plots.execute import plot_execution

    plot_execution(log_path, path, title=title)
    rep.print(f"plot: {path}")


# -- lbr execute ----------------------------------------------------------------------------------------------
def execute(
    joint_csv: Annotated[Path, typer.Argument(help="Joint trajectory t,q1..q7 \\[s, rad]; its step must be the FRI period.")],
    robot: RobotOpt = None,
    port: PortOpt = 30200,
    bind: BindOpt = None,
    log: LogOpt = None,
    fri_version: VersionOpt = "1.15",
    period: PeriodOpt = None,
    resample: Annotated[
        bool, typer.Option("--resample", help="Resample the file (cubic spline) to the controller's period if it differs.")
    ] = False,
    start_tolerance: Annotated[
        float, typer.Option("--start-tolerance", help="Largest |first row − measured position| accepted \\[rad].")
    ] = 1e-3,
    move_to_start: Annotated[
        bool,
        typer.Option("--move-to-start", help="If the robot is farther away, first stream a jerk-limited move there (≤ 20 % of the limits)."),
    ] = False,
    settle: Annotated[float, typer.Option("--settle", help="Hold the last row this long before stopping \\[s].")] = 1.0,
    margin: Annotated[float, typer.Option("--margin", help="Check the file against the limits × (1 − margin).")] = 0.0,
    t1: Annotated[bool, typer.Option("--t1", help="Also refuse files whose flange speed exceeds T1's 250 mm/s.")] = False,
    length: LengthOpt = None,
    sim_start: SimStartOpt = None,
    receive_multiplier: MultiplierOpt = 1,
    wait: WaitOpt = None,
    plot: PlotOpt = None,
    realtime: RealtimeOpt = False,
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

    Before anything is sent the file must pass `lbr check`; at the first FRI message its step must equal the
    controller's period (send period × receive multiplier) and its first row must be within --start-tolerance of the
    measured position. Every command is guarded (position limits, |Δq|/period ≤ velocity limit). The stream ends
    cleanly on a safety stop, drives not active, POOR quality, the session leaving COMMANDING_ACTIVE or Ctrl-C
    (the last command is held a few cycles). Exit 0 completed, 1 refused or stopped, 2 bad input, 130 Ctrl-C.
    """
    from lbrcli.lab.attach import LabOptions

    import numpy as np

    from lbrcli.fri.motion import build_plan, resample as resample_traj
    from trajectories.csvio import read_joint_csv
    from trajectories.errors import InputError, OptionError

    from ..console import Reporter
    from ..options import check_margin, limits_from, make_robot
    from ..parsing import parse_joint_vector

    rep = Reporter(json_out)
    _validate_version(fri_version)
    _validate_port(port)
    check_margin(margin)
    if not (math.isfinite(start_tolerance) and start_tolerance >= 0):
        raise OptionError(f"--start-tolerance must be ≥ 0 rad, got {start_tolerance:g}")
    if not (math.isfinite(settle) and 0 <= settle <= 600):
        raise OptionError(f"--settle must be 0..600 s, got {settle:g}")
    if period is not None and not 1 <= period <= 100:
        raise OptionError(f"--period must be 1..100 ms, got {period}")
    if receive_multiplier < 1:
        raise OptionError(f"--receive-multiplier must be ≥ 1, got {receive_multiplier}")
    if robot is not None and (sim_start is not None or length is not None or receive_multiplier != 1):
        raise OptionError("--sim-start, --length and --receive-multiplier apply to the simulator only, not with --robot")
    lim = limits_from(limits)
    name = str(joint_csv)
    traj = read_joint_csv(joint_csv, dt)
    model = make_robot(flange, tool) if t1 else None
    # 1. the file passes the check before any socket exists
    _check_or_fail(rep, traj, lim, margin, t1, model, name)
    rep.print(f"{name}: {len(traj)} rows, step {traj.dt * 1e3:g} ms, {traj.duration:.3f} s — within the limits")

    # 2. the period: known now for the simulator (and for a robot with --period), else at the first message
    send_ms = traj.dt * 1e3 / receive_multiplier  # the send period the file's step asks for
    if robot is None and period is None:
        whole = round(send_ms) if len(traj) > 1 else 1
        if len(traj) > 1 and (abs(send_ms - whole) > 1e-6 or not 1 <= whole <= 100) and not resample:
            raise InputError(
                f"time step {traj.dt * 1e3:g} ms is not a whole send period of 1..100 ms"
                + (f" × receive multiplier {receive_multiplier}" if receive_multiplier > 1 else "")
                + "; use --resample (with --period)",
                file=name,
            )
        period = int(min(100, max(1, whole)))

    def fit_period(tr, period_s: float):
        """The trajectory at the command period (resampled and re-checked with --resample), else exit 2."""
        if len(tr) < 2 or abs(tr.dt - period_s) <= 1e-6:
            return tr
        if not resample:
            raise InputError(
                f"time step {tr.dt * 1e3:g} ms differs from the controller's command period {period_s * 1e3:g} ms "
                "(send period × receive multiplier); re-plan at that step or use --resample",
                file=name,
            )
        rs = resample_traj(tr, period_s)
        _check_or_fail(rep, rs, lim, margin, t1, model, f"{name} resampled to {period_s * 1e3:g} ms")
        rep.print(f"resampled to {period_s * 1e3:g} ms: {len(rs)} rows")
        return rs

    if period is not None:  # with --robot assume receive multiplier 1 here; the first message tells
        traj = fit_period(traj, period * receive_multiplier * 1e-3)

    def prepare(mon, period_s: float):
        msr = np.array(mon.monitorData.measuredJointPosition.value, dtype=float)
        if msr.shape != (7,):
            raise InputError("the controller sent no measured joint position; cannot check the start")
        if robot is not None and period is not None and mon.connectionInfo.sendPeriod != period:
            raise InputError(f"the controller's send period is {mon.connectionInfo.sendPeriod} ms, --period says {period} ms")
        tr = fit_period(traj, period_s)
        plan = build_plan(
            tr.q, msr, period_s, lim, start_tolerance=start_tolerance, move_to_start=move_to_start, settle_s=settle
        )
        if plan.n_move:
            rep.print(f"moving to the start first: {plan.n_move} rows ({plan.n_move * period_s:.2f} s, ≤ 20 % of the limits)")
        if robot is not None and mon.robotInfo.operationMode == 0 and not t1:
            rep.warn("the robot is in T1: the controller limits the flange speed to 250 mm/s (check with --t1)")
        return plan

    sim_kwargs: dict[str, Any] = {}
    if robot is None:
        from trajectories.robot import parse_tool

        q0 = traj.q[0] if sim_start is None else parse_joint_vector(sim_start, "--sim-start")
        ball = DEFAULT_BALL_LENGTH if length is None else length
        if ball < 0:
            raise OptionError(f"--length must be ≥ 0 m, got {ball:g}")
        sim_kwargs = dict(
            period_ms=int(period),
            receive_multiplier=receive_multiplier,
            q0=tuple(float(v) for v in q0),
            flange=flange,
            tool=parse_tool(tool),
            ball_length=ball if ball > 0 else None,
            limits_path=str(limits) if limits is not None else None,
            max_runtime_s=traj.duration + settle + 120.0,
        )
    result, sim_stats, lab_figures = _run_session(
        rep,
        robot=robot,
        port=port,
        bind=bind,
        version=fri_version,
        limits=lim,
        log_path=log,
        wait=wait,
        sim_kwargs=sim_kwargs,
        prepare=prepare,
        realtime=realtime,
        lab=LabOptions(pendulum, baud, pendulum_zero, mqtt, mqtt_rate),
    )
    figures = _print_summary(rep, result, sim_stats, log)
    figures.update(lab_figures)
    figures.update(file=name, rows=len(traj), duration_s=traj.duration, robot=robot or "simulator")
    _plot(plot, log, rep, joint_csv.name)
    rep.emit(figures)
    _exit_for(result)


# -- lbr monitor ----------------------------------------------------------------------------------------------
def monitor(
    duration: Annotated[float, typer.Option("--duration", help="How long to monitor \\[s].")],
    log: LogOpt = None,
    robot: RobotOpt = None,
    port: PortOpt = 30200,
    bind: BindOpt = None,
    fri_version: VersionOpt = "1.15",
    period: PeriodOpt = None,
    length: LengthOpt = None,
    sim_start: SimStartOpt = None,
    wait: WaitOpt = None,
    plot: PlotOpt = None,
    realtime: RealtimeOpt = False,
    pendulum: PendulumOpt = None,
    baud: BaudOpt = 115200,
    pendulum_zero: PendZeroOpt = 0,
    mqtt: MqttOpt = None,
    mqtt_rate: MqttRateOpt = 50.0,
    flange: FlangeOpt = DEFAULT_FLANGE,
    tool: ToolOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Record everything FRI monitors, plus the flange position by forward kinematics (thesis LBRMonitor).

    Never commands motion: header-only answers in the monitoring states, the ipo position mirrored when the
    robot application starts commanding. Log columns as `lbr execute` plus flange_x, flange_y, flange_z \\[m].
    """
    from lbrcli.lab.attach import LabOptions

    import pinocchio as pin

    from trajectories.errors import OptionError
    from trajectories.robot import FLANGE_FRAME, parse_tool

    from ..console import Reporter
    from ..options import THESIS_Q_START, make_robot
    from ..parsing import parse_joint_vector

    rep = Reporter(json_out)
    _validate_version(fri_version)
    _validate_port(port)
    if not (math.isfinite(duration) and duration > 0):
        raise OptionError(f"--duration must be > 0 s, got {duration:g}")
    if period is not None and not 1 <= period <= 100:
        raise OptionError(f"--period must be 1..100 ms, got {period}")
    if robot is not None and (sim_start is not None or length is not None):
        raise OptionError("--sim-start and --length apply to the simulator only, not with --robot")
    model = make_robot(flange, tool)
    fid = model.model.getFrameId(FLANGE_FRAME)
    mdl, data = model.model, model.data
    import numpy as np

    qbuf = np.zeros(7)

    def flange_xyz(mon) -> tuple[float, float, float]:
        msr = mon.monitorData.measuredJointPosition.value
        if len(msr) != 7:
            return (0.0, 0.0, 0.0)
        qbuf[:] = msr
        pin.framesForwardKinematics(mdl, data, qbuf)
        p = data.oMf[fid].translation
        return (p[0], p[1], p[2])

    sim_kwargs: dict[str, Any] = {}
    if robot is None:
        ball = DEFAULT_BALL_LENGTH if length is None else length
        if ball < 0:
            raise OptionError(f"--length must be ≥ 0 m, got {ball:g}")
        sim_kwargs = dict(
            period_ms=period or 1,
            q0=tuple(float(v) for v in parse_joint_vector(sim_start or THESIS_Q_START, "--sim-start")),
            flange=flange,
            tool=parse_tool(tool),
            ball_length=ball if ball > 0 else None,
            max_runtime_s=duration + 120.0,
        )
    result, sim_stats, lab_figures = _run_session(
        rep,
        robot=robot,
        port=port,
        bind=bind,
        version=fri_version,
        limits=None,
        log_path=log,
        wait=wait,
        sim_kwargs=sim_kwargs,
        duration_s=duration,
        extra_names=("flange_x", "flange_y", "flange_z"),
        extra=flange_xyz,
        realtime=realtime,
        lab=LabOptions(pendulum, baud, pendulum_zero, mqtt, mqtt_rate),
    )
    figures = _print_summary(rep, result, sim_stats, log)
    figures.update(lab_figures)
    figures.update(duration_s=duration, robot=robot or "simulator")
    _plot(plot, log, rep, "monitor")
    rep.emit(figures)
    _exit_for(result)


# -- lbr ptp --------------------------------------------------------------------------------------------------
def ptp(
    q: Annotated[str, typer.Argument(help="Target joint position: 7 comma-separated angles (deg/rad suffixes; default rad).")],
    time_s: Annotated[float, typer.Option("--time", help="Duration of the move \\[s] (jerk-limited, rest to rest).")],
    robot: RobotOpt = None,
    port: PortOpt = 30200,
    bind: BindOpt = None,
    log: LogOpt = None,
    fri_version: VersionOpt = "1.15",
    speed_scale: Annotated[
        float, typer.Option("--speed-scale", help="Fraction of the velocity/acceleration/jerk limits the move may use (≤ 0.5).")
    ] = 0.2,
    settle: Annotated[float, typer.Option("--settle", help="Hold the target this long before stopping \\[s].")] = 0.2,
    period: PeriodOpt = None,
    sim_start: SimStartOpt = None,
    length: LengthOpt = None,
    wait: WaitOpt = None,
    plot: PlotOpt = None,
    realtime: RealtimeOpt = False,
    limits: LimitsOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Jerk-limited joint move to Q reaching it in --time seconds (thesis LBRJointPTP; ruckig).

    Planned from the measured position at the first FRI message with the limits scaled by --speed-scale; refused
    (exit 1) if Q is outside the position limits, or the move cannot be done in --time within the scaled limits.
    """
    import numpy as np

    from lbrcli.fri.motion import Plan, jerk_limited_move
    from trajectories.errors import CheckFailed, InputError, OptionError
    from trajectories.trajectory import JointTrajectory

    from ..console import Reporter
    from ..options import THESIS_Q_START, limits_from
    from ..parsing import parse_joint_vector

    rep = Reporter(json_out)
    _validate_version(fri_version)
    _validate_port(port)
    goal = parse_joint_vector(q, "Q")
    if not (math.isfinite(time_s) and 0 < time_s <= 600):
        raise OptionError(f"--time must be in (0, 600] s, got {time_s:g}")
    if not (math.isfinite(speed_scale) and 0 < speed_scale <= 0.5):
        raise OptionError(f"--speed-scale must be in (0, 0.5], got {speed_scale:g}")
    if not (math.isfinite(settle) and 0 <= settle <= 60):
        raise OptionError(f"--settle must be 0..60 s, got {settle:g}")
    if period is not None and not 1 <= period <= 100:
        raise OptionError(f"--period must be 1..100 ms, got {period}")
    if robot is not None and (sim_start is not None or length is not None):
        raise OptionError("--sim-start and --length apply to the simulator only, not with --robot")
    lim = limits_from(limits)
    over = np.flatnonzero(np.abs(goal) > lim.position)
    if over.size:
        j = int(over[0])
        raise CheckFailed(f"Q: A{j + 1} = {goal[j]:.4f} rad is outside the position limit ±{lim.position[j]:.4f} rad")

    def prepare(mon, period_s: float):
        msr = np.array(mon.monitorData.measuredJointPosition.value, dtype=float)
        if msr.shape != (7,):
            raise InputError("the controller sent no measured joint position; cannot plan the move")
        move = jerk_limited_move(msr, goal, lim, period_s, scale=speed_scale, minimum_duration=time_s)
        needed = len(move) * period_s
        if needed > time_s + period_s * 1.5:
            raise CheckFailed(
                f"the move needs {needed:.3f} s within {speed_scale * 100:g} % of the limits; "
                f"give --time ≥ {math.ceil(needed * 10) / 10:g} or a larger --speed-scale (≤ 0.5)"
            )
        path = JointTrajectory.from_samples(np.vstack([msr, move]), period_s)
        _check_or_fail(rep, path, lim, 0.0, False, None, "ptp move")
        n_settle = int(round(settle / period_s))
        rows = np.vstack([move, np.repeat(move[-1:], n_settle, axis=0)])
        rep.print(f"move: {len(move)} rows, {needed:.3f} s, from the measured position to Q")
        return Plan(rows=rows, n_move=0, n_traj=len(move), n_settle=n_settle, period_s=period_s)

    sim_kwargs: dict[str, Any] = {}
    if robot is None:
        ball = 0.0 if length is None else length
        sim_kwargs = dict(
            period_ms=period or 1,
            q0=tuple(float(v) for v in parse_joint_vector(sim_start or THESIS_Q_START, "--sim-start")),
            ball_length=ball if ball > 0 else None,
            limits_path=str(limits) if limits is not None else None,
            max_runtime_s=time_s + settle + 120.0,
        )
    result, sim_stats, lab_figures = _run_session(
        rep,
        robot=robot,
        port=port,
        bind=bind,
        version=fri_version,
        limits=lim,
        log_path=log,
        wait=wait,
        sim_kwargs=sim_kwargs,
        prepare=prepare,
        realtime=realtime,
    )
    figures = _print_summary(rep, result, sim_stats, log)
    figures.update(lab_figures)
    figures.update(target=goal, time_s=time_s, robot=robot or "simulator")
    if sim_stats is not None and sim_stats.final_q:
        err = float(np.max(np.abs(np.array(sim_stats.final_q) - goal)))
        figures["final_error_rad"] = err
        rep.print(f"simulated robot ended {err:.2e} rad from Q")
    _plot(plot, log, rep, "ptp")
    rep.emit(figures)
    _exit_for(result)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("execute")(execute)
    app.command("monitor")(monitor)
    app.command("ptp")(ptp)
