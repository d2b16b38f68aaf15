"""`lbr ptp`: a jerk-limited joint move (thesis LBRJointPTP) with the TrajectoryPlayer's online ruckig move."""

from __future__ import annotations

import math
from typing import Annotated, Optional

import numpy as np
import typer

from trajectories.errors import CheckFailed

from ..console import Reporter
from ..fri_options import FRI_OPTIONS, FriOptions, PlotOpt, TrackingErrorOpt
from ..fri_runner import exit_for, plot_log, print_summary, run_client
from ..option_groups import with_options
from ..options import JointVector, JsonOpt, LimitsOpt, joints, limits_from, number, string_length, within_limits


def _point_to_point(goal: np.ndarray, time_s: float, speed_scale: float, settle_s: float, lim, rep):
    """The client: a one-row trajectory whose move to the start is the point-to-point move, refused at the first
    message (nothing sent) if it cannot be done in ``time_s`` [s] within ``speed_scale`` of the limits."""
    from lbrcli.fri import OnlineMove, StopSession, TrajectoryPlayer

    class Ptp(TrajectoryPlayer):
        needed_s: float | None = None  # [s] the move's duration within the scaled limits, from the measured position

        def _check_time(self, state) -> None:
            if self.needed_s is not None:
                return
            period_s = self.command_period_s
            need = self.needed_s = OnlineMove(lim, period_s, speed_scale).start(state.measured_joint_position, goal)
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

    return Ptp(goal[None, :], lim, start_tolerance=math.inf, move_to_start=True, move_scale=speed_scale,
               move_minimum_duration=time_s, settle_s=settle_s, finish_text="reached Q and settled")  # fmt: skip


NoBallLengthOpt = Annotated[  # a simulated ball only when asked for
    Optional[float],
    string_length("--length", zero_is_none=True, help="Simulated ball string length \\[m] (default 0: no ball)."),
]


@with_options(fri=FRI_OPTIONS.without("sim_fast").replacing(length=NoBallLengthOpt))
def ptp(
    q: Annotated[
        JointVector,
        joints(
            metavar="Q",
            argument=True,
            help="Target joint position: 7 comma-separated angles (deg/rad suffixes; default rad).",
        ),
    ],
    time_s: Annotated[
        float,
        number(
            "--time",
            low=0,
            high=600,
            low_open=True,
            unit="s",
            help="Duration of the move \\[s] (jerk-limited, rest to rest).",
        ),
    ],
    fri: FriOptions,
    speed_scale: Annotated[
        float,
        number(
            "--speed-scale",
            low=0,
            high=0.5,
            low_open=True,
            help="Fraction of the velocity/acceleration/jerk limits the move may use.",
        ),
    ] = 0.2,
    settle: Annotated[
        float, number("--settle", low=0, high=60, unit="s", help="Hold the target this long before stopping \\[s].")
    ] = 0.2,
    plot: PlotOpt = None,
    max_tracking_error: TrackingErrorOpt = None,
    limits: LimitsOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Jerk-limited joint move to Q reaching it in --time seconds (thesis LBRJointPTP; ruckig).

    Planned from the measured position at the first FRI message with the limits scaled by --speed-scale; refused
    (exit 1, nothing sent) if Q is outside the position limits, or the move cannot be done in --time within the
    scaled limits.
    """
    rep = Reporter(json_out)
    fri.check_simulator_only()
    lim = limits_from(limits)
    within_limits(fri.sim_start, lim, "--sim-start")
    over = np.flatnonzero(np.abs(q) > lim.position)
    if over.size:
        j = int(over[0])
        raise CheckFailed(f"Q: A{j + 1} = {q[j]:.4f} rad is outside the position limit ±{lim.position[j]:.4f} rad")
    client = _point_to_point(q, time_s, speed_scale, settle, lim, rep)
    session = fri.session(lim, max_tracking_error=max_tracking_error)
    simulator = fri.simulator(max_runtime_s=time_s + settle + 120.0, ball=fri.ball() if fri.length else None,
                              limits=limits)  # fmt: skip
    result, sim_stats, lab_figures = run_client(rep, client, session, simulator)
    figures = print_summary(rep, result, sim_stats, session.log)
    figures.update(lab_figures)
    figures.update(target=q, time_s=time_s, robot=fri.robot or "simulator")
    if sim_stats is not None and sim_stats.final_q:
        err = float(np.max(np.abs(np.array(sim_stats.final_q) - q)))
        figures["final_error_rad"] = err
        rep.print(f"simulated robot ended {err:.2e} rad from Q")
    plot_error = plot_log(plot, session.log, rep, "ptp", figures)
    rep.emit(figures)
    exit_for(result, failed=plot_error)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("ptp")(ptp)
