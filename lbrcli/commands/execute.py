"""`lbr execute`: stream a joint CSV over FRI (thesis §3.4.3 LBRReadWrite) with the TrajectoryPlayer client.

Without --robot the built-in simulator is started in its own process on loopback; a real robot is commanded only
when named with --robot.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Optional

import typer

from trajectories.csvio import read_joint_csv
from trajectories.errors import InputError

from ..console import Reporter
from ..cup_options import CupSpecOpt, cup_model
from ..fri_options import (DEFAULT_BALL_LENGTH, FRI_OPTIONS, LAB_OPTIONS, FriOptions, MultiplierOpt, PeriodOpt, PlotOpt,
                           StartToleranceOpt, TrackingErrorOpt)  # fmt: skip
from ..fri_runner import exit_for, plot_log, print_summary, run_client
from ..lab.attach import LabOptions
from ..option_groups import with_options
from ..options import (DEFAULT_FLANGE, DtOpt, FlangeOpt, JsonOpt, LimitsOpt, MarginOpt, ToolOpt, limits_from, make_robot,
                       number, string_length, within_limits)  # fmt: skip
from ..session_end import FILE_ROWS_COLUMN
from ..session_settings import LogColumns

ExecuteLengthOpt = Annotated[  # also shapes the move to the start, with --robot too
    Optional[float],
    string_length(
        "--length",
        zero_is_none=True,
        help="String length of the ball on the flange \\[m]: the move to the start is input-shaped (ZVD) for its "
        f"swing period; without --robot also the simulated ball's (default {DEFAULT_BALL_LENGTH}; 0: no ball).",
    ),
]


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


@with_options(fri=FRI_OPTIONS.replacing(period=PeriodOpt, length=ExecuteLengthOpt), lab=LAB_OPTIONS)
def execute(
    joint_csv: Annotated[
        Path, typer.Argument(help="Joint trajectory t,q1..q7 \\[s, rad]; its step must be the FRI period.")
    ],
    fri: FriOptions,
    lab: LabOptions,
    resample: Annotated[
        bool,
        typer.Option("--resample", help="Resample the file (cubic spline) to the controller's period if it differs."),
    ] = False,
    start_tolerance: StartToleranceOpt = 1e-3,
    move_to_start: Annotated[
        bool,
        typer.Option(
            "--move-to-start",
            help="If the robot is farther away, first move there (jerk-limited, ≤ 20 % of the limits; input-shaped for "
            "the ball's swing with --length or the simulator's ball).",
        ),
    ] = False,
    settle: Annotated[
        float, number("--settle", low=0, high=600, unit="s", help="Hold the last row this long before stopping \\[s].")
    ] = 1.0,
    margin: MarginOpt = 0.0,
    t1: Annotated[
        bool, typer.Option("--t1", help="Also refuse files whose flange speed exceeds T1's 250 mm/s.")
    ] = False,
    damping: Annotated[
        float,
        number(
            "--damping",
            low=0,
            high=1000,
            unit="1/s",
            help="Simulator only: damping of the simulated ball \\[1/s] (0: it swings on).",
        ),
    ] = 0.0,
    cup: CupSpecOpt = None,
    start_sway: Annotated[
        float,
        number(
            "--start-sway",
            low=0,
            high=45,
            low_open=True,
            unit="deg",
            help="With --move-to-start, hold the first row until the measured sway (the simulated ball, or --pendulum) "
            "has stayed below this for 0.6 of a swing period \\[deg].",
        ),
    ] = 0.2,
    sway_wait: Annotated[
        float,
        number(
            "--sway-wait",
            low=0,
            high=3600,
            unit="s",
            help="Hold it at most this long, then start and report the sway \\[s] (0: only report).",
        ),
    ] = 30.0,
    receive_multiplier: MultiplierOpt = 1,
    plot: PlotOpt = None,
    max_tracking_error: TrackingErrorOpt = None,
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
    rep = Reporter(json_out)
    fri.check_simulator_only({"--damping": damping != 0.0, "--cup": cup is not None,
                              "--receive-multiplier": receive_multiplier != 1}, length=False)  # fmt: skip
    fri.refuse_log_over(joint_csv)
    lim = limits_from(limits)
    within_limits(fri.sim_start, lim, "--sim-start")
    name, traj = str(joint_csv), read_joint_csv(joint_csv, dt)
    check = FileCheck(rep, lim, margin, t1, make_robot(flange, tool) if t1 else None, name)
    check(traj, name)  # the file passes the check before any socket exists
    rep.print(f"{name}: {len(traj)} rows, step {traj.dt * 1e3:g} ms, {traj.duration:.3f} s — within the limits")
    traj, period_ms = _at_command_period(traj, fri, receive_multiplier, resample, check)
    ball_length = fri.ball_length() if fri.embedded else fri.length  # [m] the swing the move to the start is shaped for
    player = _player(traj, lim, period_ms * receive_multiplier * 1e-3, check if resample else None, ball_length,
                     make_robot(flange, tool), start_tolerance=start_tolerance, move_to_start=move_to_start, settle_s=settle,
                     start_sway_rad=math.radians(start_sway), sway_wait_s=sway_wait)  # fmt: skip
    if move_to_start:
        rep.print("a move to the start (≤ 20 % of the limits) precedes the file if the robot stands elsewhere")
    simulator = fri.simulator(max_runtime_s=traj.duration + settle + sway_wait + 120.0, start=traj.q[0], lab=lab,
                              ball=fri.ball(damping, cup_model(cup, ball_length)) if fri.embedded else None,
                              period_ms=period_ms, receive_multiplier=receive_multiplier, flange=flange, tool=tool,
                              limits=limits)  # fmt: skip
    session = fri.session(lim, max_tracking_error=max_tracking_error, check_period=False)  # the player checks it
    result, sim_stats, lab_figures = run_client(rep, player, session, simulator, lab=lab, extra=LogColumns(
        (FILE_ROWS_COLUMN,), lambda state: (len(player.rows),)))  # the log tells when it completed  # fmt: skip
    figures = print_summary(rep, result, sim_stats, fri.log)
    figures.update(lab_figures)
    figures.update(file=name, rows=len(traj), duration_s=traj.duration, robot=fri.robot or "simulator")
    _report_cup(rep, figures, cup, fri.log)
    if fri.robot is not None and result.figures.get("operation_mode") == "TEST_MODE_1" and not t1:
        rep.warn("the robot is in T1: the controller limits the flange speed to 250 mm/s (check with --t1)")
    plot_error = plot_log(plot, fri.log, rep, joint_csv.name, figures)
    rep.emit(figures)
    exit_for(result, lab_figures, lab.mqtt, failed=plot_error)


class FileCheck:
    """`lbr check` of a joint file (and of the file resampled): CheckFailed (exit 1, nothing sent) if it fails."""

    def __init__(self, rep, lim, margin: float, t1: bool, model, name: str) -> None:
        self.rep, self.lim, self.margin, self.t1, self.model, self.name = rep, lim, margin, t1, model, name

    def __call__(self, traj, name: str):
        return check_or_fail(self.rep, traj, self.lim, self.margin, self.t1, self.model, name)

    def resampled(self, traj, period_s: float):
        """``traj`` resampled (cubic spline) to ``period_s`` [s], checked again."""
        from trajectories.resample import resample

        rs = resample(traj, period_s)
        self(rs, f"{self.name} resampled to {period_s * 1e3:g} ms")
        self.rep.print(f"resampled to {period_s * 1e3:g} ms: {len(rs)} rows")
        return rs


def _at_command_period(traj, fri: FriOptions, k: int, resample: bool, check: FileCheck):
    """(the rows at the command period, the send period [ms]). The simulator's period is ours to choose; with --robot,
    --period (else the file's step) is assumed and the first message must agree. InputError when the step is not a
    whole send period × ``k`` (the receive multiplier) and --resample was not given."""
    from lbrcli.fri.players import whole_send_period_ms

    period = fri.period
    if period is None:
        whole = whole_send_period_ms(traj.dt, k) if len(traj) > 1 else 1
        if whole is None and not (resample and fri.embedded):
            raise InputError(f"time step {traj.dt * 1e3:g} ms is not a whole send period of 1..100 ms"
                             + (f" × receive multiplier {k}" if k > 1 else "") + "; use --resample with --period",
                             file=check.name)  # fmt: skip
        period = whole if whole is not None else int(min(100, max(1, round(traj.dt * 1e3 / k))))
    period_s = period * k * 1e-3
    if len(traj) > 1 and abs(traj.dt - period_s) > 1e-6:
        if not resample:
            raise InputError(f"time step {traj.dt * 1e3:g} ms differs from the command period {period_s * 1e3:g} ms "
                             "(send period × receive multiplier); re-plan at that step or use --resample", file=check.name)  # fmt: skip
        traj = check.resampled(traj, period_s)
    return traj, period


def _player(traj, lim, period_s: float, check: FileCheck | None, ball_length: float | None, robot, *,
            start_tolerance: float, move_to_start: bool, settle_s: float, start_sway_rad: float, sway_wait_s: float):  # fmt: skip
    """The TrajectoryPlayer of the rows: the move to the start shaped for the ball's swing (if its length is known),
    the first row held while the sway settles; ``check``: resample at the controller's period if it differs."""
    from lbrcli.fri import StopSession, TrajectoryPlayer
    from lbrcli.fri.sway import IoSway, SwayWatch, window_for_length
    from planners.pendulum import natural_period
    from planners.shapers import make_shaper
    from trajectories.errors import CheckFailed

    def at_controller_period(period_s: float):
        """--resample with a robot whose period was not given: resample at the first message (and re-check)."""
        try:
            return check.resampled(traj, period_s).q  # type: ignore[union-attr]
        except CheckFailed as exc:
            raise StopSession(str(exc), completed=False) from None

    return TrajectoryPlayer(
        traj.q, lim, period_s=period_s, start_tolerance=start_tolerance, move_to_start=move_to_start, settle_s=settle_s,
        resample=at_controller_period if check is not None else None,
        move_shaper=make_shaper("zvd", natural_period(ball_length)) if ball_length else None,
        move_robot=robot if ball_length else None,
        sway=SwayWatch(IoSway("ball_theta"), start_sway_rad, window_for_length(ball_length), sway_wait_s),
    )  # fmt: skip


def _report_cup(rep, figures: dict, cup: str | None, log: Path | None) -> None:
    """The simulated cup-and-ball: caught or not (simulator time), and what the log says (with --cup and --log)."""
    plant = (figures.get("simulator") or {}).get("plants", {}).get("ball", {}).get("cup")
    if plant is not None:
        rep.print(
            "simulated ball: "
            + ("caught in the cup" if plant["caught"] else f"not caught — {plant['failure']}")
            + " (simulator time)"
        )
    if cup is not None and log is not None:
        from ..cup_log import cup_summary, describe

        summary = cup_summary(log)
        if summary is not None:
            rep.print(describe(summary))
            figures["cup"] = summary


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("execute")(execute)
