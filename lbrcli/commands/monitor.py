"""`lbr monitor`: record everything FRI monitors (thesis LBRMonitor) with a client that never commands motion."""

from __future__ import annotations

from typing import Annotated

import typer

from ..console import Reporter
from ..fri_options import FRI_OPTIONS, LAB_OPTIONS, FriOptions, PlotOpt
from ..fri_runner import exit_for, plot_log, print_summary, run_client
from ..lab.attach import LabOptions
from ..option_groups import with_options
from ..options import DEFAULT_FLANGE, FlangeOpt, JsonOpt, ToolOpt, make_robot, number
from ..session_settings import LogColumns


@with_options(fri=FRI_OPTIONS.without("sim_fast"), lab=LAB_OPTIONS)
def monitor(
    duration: Annotated[
        float, number("--duration", low=0, high=86400, low_open=True, unit="s", help="How long to monitor \\[s].")
    ],
    fri: FriOptions,
    lab: LabOptions,
    plot: PlotOpt = None,
    flange: FlangeOpt = DEFAULT_FLANGE,
    tool: ToolOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Record everything FRI monitors, plus the flange position by forward kinematics (thesis LBRMonitor).

    Never commands motion: header-only answers in the monitoring states, the robot held at the ipo position when
    the robot application starts commanding. Log columns as `lbr execute` plus flange_x, flange_y, flange_z \\[m].
    """
    from lbrcli.fri.watcher import FLANGE_COLUMNS, Watcher, flange_position

    rep = Reporter(json_out)
    fri.check_simulator_only()
    session = fri.session(duration_s=duration)
    simulator = fri.simulator(max_runtime_s=duration + 120.0, ball=fri.ball(), lab=lab, flange=flange, tool=tool)
    columns = LogColumns(FLANGE_COLUMNS, flange_position(make_robot(flange, tool)))
    result, sim_stats, lab_figures = run_client(rep, Watcher(), session, simulator, lab=lab, extra=columns)
    figures = print_summary(rep, result, sim_stats, session.log)
    figures.update(lab_figures)
    figures.update(duration_s=duration, robot=fri.robot or "simulator")
    plot_error = plot_log(plot, session.log, rep, "monitor", figures)
    rep.emit(figures)
    exit_for(result, lab_figures, lab.mqtt, failed=plot_error)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("monitor")(monitor)
