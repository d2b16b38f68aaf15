"""`lbr serve`: the FRI session driven from other processes — joint targets over UDP, the state sent back."""

from __future__ import annotations

import math
from typing import Annotated, Any, Optional

import typer

from ..fri_options import (
    DEFAULT_BALL_LENGTH,
    BindOpt,
    LengthOpt,
    LogOpt,
    PeriodOpt,
    PortOpt,
    RealtimeOpt,
    RobotOpt,
    SimLenientOpt,
    SimStartOpt,
    VersionOpt,
    WaitOpt,
)
from ..options import DEFAULT_FLANGE, FlangeOpt, JsonOpt, LimitsOpt, ToolOpt


def serve(
    listen: Annotated[
        str, typer.Option("--listen", help="HOST:PORT where targets arrive (UDP; the state goes back to the source).")
    ] = "127.0.0.1:30300",
    source: Annotated[
        Optional[str], typer.Option("--source", help="Comma-separated hosts that may command (default: any; the first owns the session).")
    ] = None,
    timeout: Annotated[
        float, typer.Option("--timeout", help="Dead-man: brake when no target arrived for this long \\[s].")
    ] = 0.1,
    first_target: Annotated[
        float, typer.Option("--first-target", help="Stop if no target arrived this long after commanding started \\[s].")
    ] = 30.0,
    speed_scale: Annotated[
        float, typer.Option("--speed-scale", help="Share of the velocity, acceleration and jerk limits ruckig may use (0..1].")
    ] = 0.5,
    state_every: Annotated[
        int, typer.Option("--state-every", help="Send the state back every N FRI messages (0: never).")
    ] = 1,
    duration: Annotated[
        Optional[float], typer.Option("--duration", help="End (braking) after this long \\[s] (default: until the source ends).")
    ] = None,
    robot: RobotOpt = None,
    port: PortOpt = 30200,
    bind: BindOpt = None,
    fri_version: VersionOpt = None,
    period: PeriodOpt = None,
    log: LogOpt = None,
    sim_start: SimStartOpt = None,
    length: LengthOpt = None,
    wait: WaitOpt = None,
    realtime: RealtimeOpt = False,
    sim_lenient: SimLenientOpt = False,
    flange: FlangeOpt = DEFAULT_FLANGE,
    tool: ToolOpt = None,
    limits: LimitsOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Run an FRI session that follows joint targets sent by another process (Simulink, MATLAB, ROS 2, a script).

    Targets arrive over UDP at --listen, binary (136 bytes, magic LBRT, version 1) or JSON {"q": [...], "v": [...]}
    (layout in the README and lbrcli.bridge.protocol); ruckig follows the newest one within --speed-scale of the
    limits at every FRI cycle and the guard checks every command. The state (200 bytes, magic LBRS) goes back to the
    source every --state-every messages. The first source owns the session; others are ignored. A braking stop
    within the limits ends it when targets stop for --timeout (dead-man), the source sends garbage or a target
    outside the position limits (exit 1), the source sends {"end": true} or --duration elapses (exit 0), or Ctrl-C.
    """
    from lbrcli.bridge import TargetFollower, UdpTargets
    from trajectories.errors import OptionError

    from ..console import Reporter
    from ..fri_options import validate_period, validate_port, validate_version, validate_wait
    from ..fri_runner import exit_for, print_summary, run_client, simulator_kwargs
    from ..options import THESIS_Q_START, limits_from

    rep = Reporter(json_out)
    validate_version(fri_version)
    validate_port(port)
    validate_wait(wait)
    validate_period(period)
    host, _, lport = listen.rpartition(":")
    if not host or not lport.isdigit() or not 0 <= int(lport) <= 65535:
        raise OptionError(f"--listen must be HOST:PORT, got {listen!r}")
    for name, value, lo, hi in (("--timeout", timeout, 0.005, 10.0), ("--first-target", first_target, 0.1, 3600.0)):
        if not (math.isfinite(value) and lo <= value <= hi):
            raise OptionError(f"{name} must be {lo:g}..{hi:g} s, got {value:g}")
    if not (math.isfinite(speed_scale) and 0 < speed_scale <= 1):
        raise OptionError(f"--speed-scale must be in (0, 1], got {speed_scale:g}")
    if not 0 <= state_every <= 1000:
        raise OptionError(f"--state-every must be 0..1000, got {state_every}")
    if duration is not None and not (math.isfinite(duration) and 0 < duration <= 86400):
        raise OptionError(f"--duration must be in (0, 86400] s, got {duration:g}")
    if robot is not None and (sim_start is not None or length is not None or sim_lenient):
        raise OptionError("--sim-start, --length and --sim-lenient apply to the simulator only, not with --robot")
    lim = limits_from(limits)
    allowed = {h.strip() for h in source.split(",") if h.strip()} if source else None
    sim_kwargs: dict[str, Any] = {}
    if robot is None:
        sim_kwargs = simulator_kwargs(length=length, default_length=DEFAULT_BALL_LENGTH, period_ms=period or 1,
                                      sim_start=sim_start, default_start=THESIS_Q_START, flange=flange, tool=tool,
                                      max_runtime_s=(duration or 86400.0) + 120.0, limits=limits)  # fmt: skip
    try:
        targets = UdpTargets(int(lport), host, allowed)
    except OSError as exc:
        raise OptionError(f"--listen {listen}: cannot bind ({exc.strerror})") from None
    rep.print(f"targets on udp://{host}:{targets.port}" + (f" from {', '.join(sorted(allowed))}" if allowed else ""))
    follower = TargetFollower(targets, lim, timeout_s=timeout, first_target_s=first_target, speed_scale=speed_scale,
                              state_every=state_every)  # fmt: skip
    try:
        result, sim_stats, _ = run_client(
            rep, follower, robot=robot, port=port, bind=bind, version=fri_version, limits=lim, log_path=log, wait=wait,
            sim_kwargs=sim_kwargs, sim_lenient=sim_lenient, duration_s=duration, realtime=realtime,
        )  # fmt: skip
    finally:
        targets.close()
    figures = print_summary(rep, result, sim_stats, log)
    f = result.figures
    rep.print(f"targets: {f.get('targets_accepted', 0)} accepted, {f.get('targets_bad', 0)} bad, "
              f"{f.get('targets_foreign', 0)} from other sources, {f.get('targets_stale', 0)} stale")  # fmt: skip
    figures.update(listen=f"{host}:{targets.port}", robot=robot or "simulator")
    rep.emit(figures)
    exit_for(result)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("serve")(serve)
