"""`lbr ptp`: a jerk-limited joint move (thesis LBRJointPTP) with the TrajectoryPlayer's online ruckig move."""

from __future__ import annotations

import math
from typing import Annotated, Any

import numpy as np
import typer

from ..fri_options import BindOpt, LengthOpt, LogOpt, SessionPeriodOpt, PlotOpt, PortOpt, RealtimeOpt, RobotOpt, BusyWaitOpt, SimLenientOpt, SimStartOpt, TrackingErrorOpt, VersionOpt, WaitOpt
from ..options import JointVector, JsonOpt, LimitsOpt, joints, number


def ptp(
    q: Annotated[JointVector, joints(metavar="Q", argument=True, help="Target joint position: 7 comma-separated angles (deg/rad suffixes; default rad).")],
    time_s: Annotated[float, number("--time", low=0, high=600, low_open=True, unit="s", help="Duration of the move \\[s] (jerk-limited, rest to rest).")],
    robot: RobotOpt = None,
    port: PortOpt = 30200,
    bind: BindOpt = None,
    log: LogOpt = None,
    fri_version: VersionOpt = None,
    speed_scale: Annotated[
        float, number("--speed-scale", low=0, high=0.5, low_open=True, help="Fraction of the velocity/acceleration/jerk limits the move may use.")
    ] = 0.2,
    settle: Annotated[float, number("--settle", low=0, high=60, unit="s", help="Hold the target this long before stopping \\[s].")] = 0.2,
    period: SessionPeriodOpt = None,
    sim_start: SimStartOpt = None,
    length: LengthOpt = None,
    wait: WaitOpt = None,
    plot: PlotOpt = None,
    realtime: RealtimeOpt = False,
    busy_wait: BusyWaitOpt = None,
    sim_lenient: SimLenientOpt = True,
    max_tracking_error: TrackingErrorOpt = None,
    limits: LimitsOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Jerk-limited joint move to Q reaching it in --time seconds (thesis LBRJointPTP; ruckig).

    Planned from the measured position at the first FRI message with the limits scaled by --speed-scale; refused
    (exit 1, nothing sent) if Q is outside the position limits, or the move cannot be done in --time within the
    scaled limits.
    """
    from lbrcli.fri import OnlineMove, StopSession, TrajectoryPlayer
    from trajectories.errors import CheckFailed

    from ..console import Reporter
    from ..fri_options import busy_wait_seconds, check_simulator_only
    from ..fri_runner import exit_for, plot_log, print_summary, run_client, simulator_kwargs
    from ..options import DEFAULT_FLANGE, THESIS_Q_START, limits_from, within_limits

    rep = Reporter(json_out)
    goal = q
    check_simulator_only(robot, {"--sim-start": sim_start is not None, "--length": length is not None,
                                 "--sim-strict": not sim_lenient})  # fmt: skip
    lim = limits_from(limits)
    within_limits(sim_start, lim, "--sim-start")
    over = np.flatnonzero(np.abs(goal) > lim.position)
    if over.size:
        j = int(over[0])
        raise CheckFailed(f"Q: A{j + 1} = {goal[j]:.4f} rad is outside the position limit ±{lim.position[j]:.4f} rad")

    class Ptp(TrajectoryPlayer):
        """The move to the start of a one-row trajectory is the point-to-point move; refused before it starts
        if it cannot be done in --time within the scaled limits."""

        def _check_time(self, state) -> None:
            if getattr(self, "_timed", False):
                return
            self._timed = True
            period_s = state.sample_time * state.receive_multiplier
            need = OnlineMove(lim, period_s, speed_scale).start(state.measured_joint_position, goal)
            self.needed_s = need
            if need > time_s + 1.5 * period_s:
                raise StopSession(
                    f"the move needs {need:.3f} s within {speed_scale * 100:g} % of the limits; give --time ≥ "
                    f"{math.ceil(need * 10) / 10:g} or a larger --speed-scale (≤ 0.5)", completed=False,
                )  # fmt: skip
            rep.print(f"move: {need if need > time_s else time_s:.3f} s from the measured position to Q")

        def monitor(self, state) -> None:
            self._check_time(state)
            super().monitor(state)

        def wait_for_command(self, state) -> None:
            self._check_time(state)
            super().wait_for_command(state)

    client = Ptp(
        goal[None, :], lim, start_tolerance=math.inf, move_to_start=True, move_scale=speed_scale,
        move_minimum_duration=time_s, settle_s=settle, finish_text="reached Q and settled",
    )  # fmt: skip
    sim_kwargs: dict[str, Any] = {}
    if robot is None:
        sim_kwargs = simulator_kwargs(length=length, default_length=0.0, period_ms=period or 1, sim_start=sim_start,
                                      default_start=THESIS_Q_START, flange=DEFAULT_FLANGE, tool=None,
                                      max_runtime_s=time_s + settle + 120.0, limits=limits)  # fmt: skip
    result, sim_stats, lab_figures = run_client(
        rep, client, robot=robot, port=port, bind=bind, version=fri_version, limits=lim, log_path=log, wait=wait,
        sim_kwargs=sim_kwargs, sim_lenient=sim_lenient, realtime=realtime, busy_wait_s=busy_wait_seconds(busy_wait), max_tracking_error=max_tracking_error,
    )  # fmt: skip
    figures = print_summary(rep, result, sim_stats, log)
    figures.update(lab_figures)
    figures.update(target=goal, time_s=time_s, robot=robot or "simulator")
    if sim_stats is not None and sim_stats.final_q:
        err = float(np.max(np.abs(np.array(sim_stats.final_q) - goal)))
        figures["final_error_rad"] = err
        rep.print(f"simulated robot ended {err:.2e} rad from Q")
    plot_error = plot_log(plot, log, rep, "ptp", figures)
    rep.emit(figures)
    exit_for(result, failed=plot_error)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("ptp")(ptp)
