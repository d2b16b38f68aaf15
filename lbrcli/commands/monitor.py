"""`lbr monitor`: record everything FRI monitors (thesis LBRMonitor) with a client that never commands motion."""

from __future__ import annotations

from typing import Annotated, Any

import typer

from ..fri_options import (
    DEFAULT_BALL_LENGTH,
    BaudOpt,
    BindOpt,
    LengthOpt,
    LogOpt,
    MqttOpt,
    MqttRateOpt,
    PendulumOpt,
    PendZeroOpt,
    SessionPeriodOpt,
    PlotOpt,
    PortOpt,
    RealtimeOpt,
    BusyWaitOpt,
    SimLenientOpt,
    RobotOpt,
    SimStartOpt,
    VersionOpt,
    WaitOpt,
)
from ..options import DEFAULT_FLANGE, FlangeOpt, JsonOpt, ToolOpt, number


def monitor(
    duration: Annotated[float, number("--duration", low=0, high=86400, low_open=True, unit="s", help="How long to monitor \\[s].")],
    log: LogOpt = None,
    robot: RobotOpt = None,
    port: PortOpt = 30200,
    bind: BindOpt = None,
    fri_version: VersionOpt = None,
    period: SessionPeriodOpt = None,
    length: LengthOpt = None,
    sim_start: SimStartOpt = None,
    wait: WaitOpt = None,
    plot: PlotOpt = None,
    realtime: RealtimeOpt = False,
    busy_wait: BusyWaitOpt = None,
    sim_lenient: SimLenientOpt = True,
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

    Never commands motion: header-only answers in the monitoring states, the robot held at the ipo position when
    the robot application starts commanding. Log columns as `lbr execute` plus flange_x, flange_y, flange_z \\[m].
    """
    import numpy as np
    import pinocchio as pin

    from lbrcli.fri import LBRClient, Phase
    from lbrcli.lab.attach import LabOptions
    from trajectories.robot import FLANGE_FRAME

    from ..console import Reporter
    from ..fri_options import busy_wait_seconds, check_simulator_only
    from ..fri_runner import exit_for, plot_log, print_summary, run_client, simulator_kwargs
    from ..options import THESIS_Q_START, make_robot

    rep = Reporter(json_out)
    check_simulator_only(robot, {"--sim-start": sim_start is not None, "--length": length is not None,
                                 "--sim-strict": not sim_lenient})  # fmt: skip
    model = make_robot(flange, tool)
    fid = model.model.getFrameId(FLANGE_FRAME)
    mdl, data = model.model, model.data
    qbuf = np.zeros(7)

    def flange_xyz(state) -> tuple[float, float, float]:
        qbuf[:] = state.message.monitorData.measuredJointPosition.value
        pin.framesForwardKinematics(mdl, data, qbuf)
        p = data.oMf[fid].translation
        return (p[0], p[1], p[2])

    class Watcher(LBRClient):
        """KUKA's default client: watches, and holds the ipo position if the application starts commanding."""

        def command(self, state):
            self.phase = Phase.MIRROR
            return super().command(state)

    sim_kwargs: dict[str, Any] = {}
    if robot is None:
        sim_kwargs = simulator_kwargs(length=length, default_length=DEFAULT_BALL_LENGTH, period_ms=period or 1,
                                      sim_start=sim_start, default_start=THESIS_Q_START, flange=flange, tool=tool,
                                      max_runtime_s=duration + 120.0)  # fmt: skip
    result, sim_stats, lab_figures = run_client(
        rep, Watcher(), robot=robot, port=port, bind=bind, version=fri_version, limits=None, log_path=log, wait=wait,
        sim_kwargs=sim_kwargs, sim_lenient=sim_lenient, duration_s=duration, extra_names=("flange_x", "flange_y", "flange_z"), extra=flange_xyz,
        realtime=realtime, busy_wait_s=busy_wait_seconds(busy_wait), lab=LabOptions(pendulum, baud, pendulum_zero, mqtt, mqtt_rate),
    )  # fmt: skip
    figures = print_summary(rep, result, sim_stats, log)
    figures.update(lab_figures)
    figures.update(duration_s=duration, robot=robot or "simulator")
    plot_error = plot_log(plot, log, rep, "monitor", figures)
    rep.emit(figures)
    exit_for(result, lab_figures, mqtt, failed=plot_error)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("monitor")(monitor)
