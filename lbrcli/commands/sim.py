"""`lbr sim`: the FRI controller simulator on its own, in the foreground."""

from __future__ import annotations

import math
from typing import Annotated, Optional

import typer

from trajectories.errors import OptionError

from ..cup_options import CupSpecOpt
from ..fri_options import parse_host_port, parse_ip
from ..option_groups import with_options
from ..options import (DEFAULT_FLANGE, THESIS_Q_START, FlangeOpt, Floats, JointVector, JsonOpt, LimitsOpt, ToolOpt,
                       choice, floats, joints, number, string_length)  # fmt: skip


def _cartesian_stiffness(text: str | tuple) -> tuple[float, float]:
    """--cartesian-stiffness TRANS,ROT: (0, 1e5] N/m and (0, 1e4] Nm/rad."""
    trans, rot = Floats(2, 0.0, 1e5)(text)
    if not (trans > 0 and 0 < rot <= 1e4):
        raise typer.BadParameter(f"expected TRANS in (0, 1e5] N/m and ROT in (0, 1e4] Nm/rad, got {text!r}")
    return trans, rot


SIM_FLAGS = {
    "BallSpec.length": "--length", "BallSpec.damping": "--damping", "BallSpec.model": "--cup",
    "default_plants.ball_length": "--length", "SimConfig.period_ms": "--period", "SimConfig.receive_multiplier":
    "--receive-multiplier", "SimConfig.version": "--fri-version", "SimConfig.loss": "--loss", "SimConfig.malformed":
    "--malformed", "SimConfig.delay_ms": "--delay", "SimConfig.jitter_ms": "--jitter", "SimConfig.q0": "--q0",
    "SimConfig.port": "--port", "SimConfig.client_port": "--client", "SimConfig.client_host": "--client",
    "SimConfig.operation_mode": "--operation-mode", "SimConfig.command_mode": "--mode",
    "SimConfig.transformations": "--transformation", "SimConfig.joint_stiffness": "--stiffness",
    "SimConfig.cartesian_stiffness": "--cartesian-stiffness", "SimConfig.damping_ratio": "--damping-ratio",
    "SimConfig.external_torque": "--external-torque", "SimConfig.external_force": "--external-force",
    "SimConfig.torque_noise": "--torque-noise", "SimConfig.io": "--io", "IoChannel.name": "--io", "IoChannel.type": "--io",
    "IoChannel.direction": "--io", "IoChannel.value": "--io", "IoChannel.spec": "--io", "SimConfig.quality_good": "--quality-good",
    "SimConfig.quality_window": "--quality-window", "SimConfig.session_duration_s": "--duration",
    "SimConfig.max_runtime_s": "--timeout",
}  # fmt: skip
"""The option of each setting `lbr sim` makes (``Class.field`` → flag)."""


@with_options(flags=SIM_FLAGS)
def sim(
    port: Annotated[
        int,
        number(
            "--port",
            low=0,
            high=65535,
            integer=True,
            help="UDP port the simulator sends from and listens on (0: any free port).",
        ),
    ] = 0,
    host: Annotated[
        str, typer.Option("--host", parser=parse_ip, metavar="IP", help="IP address the simulator binds.")
    ] = "127.0.0.1",
    period: Annotated[
        int, number("--period", low=1, high=100, unit="ms", integer=True, help="Send period \\[ms].")
    ] = 1,
    client: Annotated[
        tuple,
        typer.Option(
            "--client",
            parser=parse_host_port,
            metavar="HOST:PORT",
            help="Where monitoring messages go: HOST:PORT of the FRI client.",
        ),
    ] = "127.0.0.1:30200",
    q0: Annotated[
        JointVector, joints("--q0", help="Start joint positions q1..q7 \\[rad, or with deg suffix].")
    ] = THESIS_Q_START,
    length: Annotated[
        Optional[float],
        string_length("--length", help="Simulate a ball on a string of this length \\[m] hanging from the TCP."),
    ] = None,
    damping: Annotated[
        float, number("--damping", low=0, high=1000, unit="1/s", help="Damping of the simulated ball \\[1/s].")
    ] = 0.0,
    cup: CupSpecOpt = None,
    fri_version: Annotated[
        str,
        choice(
            "--fri-version",
            choices=("1.15", "2.7"),
            help="Wire format: 1.15 (bare protobuf) or 2.7 (length + CRC-32 framing).",
        ),
    ] = "1.15",
    receive_multiplier: Annotated[
        int,
        number("--receive-multiplier", low=1, high=100, integer=True, help="The client answers every k-th message."),
    ] = 1,
    duration: Annotated[
        Optional[float],
        number(
            "--duration",
            low=0,
            high=86400 * 365,
            low_open=True,
            unit="s",
            help="COMMANDING_ACTIVE time \\[s] after which the robot application ends the session (default: until the client stops); with --no-overlay the time from the first MONITORING_READY.",
        ),
    ] = None,
    timeout: Annotated[
        Optional[float],
        number(
            "--timeout",
            low=0,
            high=86400 * 365,
            low_open=True,
            unit="s",
            help="Stop the simulator after this wall time \\[s] (it closes the session: IDLE).",
        ),
    ] = None,
    commanding_after: Annotated[
        float,
        number(
            "--commanding-after",
            low=0,
            high=3600,
            unit="s",
            help="Time \\[s] from the first MONITORING_READY until the overlay starts (at quality GOOD).",
        ),
    ] = 0.2,
    quality_window: Annotated[
        int,
        number(
            "--quality-window",
            low=1,
            high=100_000,
            integer=True,
            help="Cycles in the sliding window of the connection quality.",
        ),
    ] = 50,
    quality_good: Annotated[
        float,
        number(
            "--quality-good",
            low=0,
            high=1,
            low_open=True,
            help="Share of timely cycles in the window for GOOD (commanding allowed); FAIR from 0.5, EXCELLENT from 0.98.",
        ),
    ] = 0.9,
    operation_mode: Annotated[
        str,
        choice(
            "--operation-mode",
            choices=("T1", "T2", "AUT"),
            fold=str.upper,
            help="Reported operation mode: T1, T2 or AUT.",
        ),
    ] = "T1",
    loss: Annotated[
        float, number("--loss", low=0, high=1, help="Fault injection: probability of dropping a monitoring message.")
    ] = 0.0,
    delay: Annotated[
        float,
        number(
            "--delay", low=0, high=1000, unit="ms", help="Fault injection: delay of every monitoring message \\[ms]."
        ),
    ] = 0.0,
    jitter: Annotated[
        float,
        number(
            "--jitter", low=0, high=1000, unit="ms", help="Fault injection: extra random delay, uniform 0..J \\[ms]."
        ),
    ] = 0.0,
    malformed: Annotated[
        float,
        number(
            "--malformed", low=0, high=1, help="Fault injection: probability of sending a corrupted datagram instead."
        ),
    ] = 0.0,
    seed: Annotated[
        int, number("--seed", low=0, high=2**32 - 1, integer=True, help="Seed of the fault injection.")
    ] = 0,
    realtime: Annotated[
        bool,
        typer.Option(
            "--realtime",
            help="Run the loop with real-time scheduling (SCHED_FIFO) if permitted: steadier 1 ms under load.",
        ),
    ] = False,
    pendulum_pty: Annotated[
        bool,
        typer.Option(
            "--pendulum-pty",
            help="Also emulate the thesis's pendulum module: the ball's planar angle θy as AS5600 lines on a pseudo-terminal (its path is printed; read it with --pendulum PATH). Needs --length.",
        ),
    ] = False,
    no_overlay: Annotated[
        bool,
        typer.Option(
            "--no-overlay",
            help="The application only monitors the session (never commands; --duration counts from the first MONITORING_READY), e.g. for KUKA's IOAccess example, which mirrors no positions.",
        ),
    ] = False,
    mode: Annotated[
        str,
        choice(
            "--mode",
            choices=("position", "torque", "wrench", "cartesian"),
            fold=str.lower,
            help="Client command mode of the simulated FRI overlay: position (joint position, position control), torque (joint impedance + commanded torque), wrench (Cartesian impedance + commanded wrench) or cartesian (FRI 2.7 CARTESIAN_POSE: the client commands the TCP pose and E1 = A3, turned into joints by IK; an unreachable or jumping pose ends the overlay).",
        ),
    ] = "position",
    transformation: Annotated[
        Optional[list[str]],
        typer.Option(
            "--transformation",
            metavar="NAME",
            help="FRI 2.7: a frame the robot application asks the client to provide (requestedTransformations; repeatable, at most 5). The values the client sends are reported per frame (received, last value \\[m], timestamp).",
        ),
    ] = None,
    stiffness: Annotated[
        float,
        number(
            "--stiffness",
            low=0,
            high=1e5,
            low_open=True,
            unit="Nm/rad",
            help="Joint impedance stiffness \\[Nm/rad] (--mode torque), every joint.",
        ),
    ] = 1000.0,
    cartesian_stiffness: Annotated[
        tuple,
        typer.Option(
            "--cartesian-stiffness",
            parser=_cartesian_stiffness,
            metavar="TRANS,ROT",
            help="Cartesian impedance stiffness TRANS,ROT \\[N/m, Nm/rad] along the TCP axes (--mode wrench).",
        ),
    ] = "2000,200",
    damping_ratio: Annotated[
        float,
        number(
            "--damping-ratio", low=0, high=10, help="Damping ratio ζ of the impedance controllers (KUKA's default 0.7)."
        ),
    ] = 0.7,
    io: Annotated[
        Optional[list[str]],
        typer.Option(
            "--io",
            metavar="NAME:TYPE:DIR[:VALUE]",
            help="An IO channel of the application's FRI IO configuration: NAME:TYPE:DIRECTION\\[:VALUE], TYPE boolean|digital|analog, DIRECTION in|out (repeatable).",
        ),
    ] = None,
    io_preset: Annotated[
        Optional[str],
        typer.Option(
            "--io-preset", help="A ready IO configuration: kuka-ioaccess (the channels KUKA's IOAccess example uses)."
        ),
    ] = None,
    external_torque: Annotated[
        Optional[tuple],
        floats(
            "--external-torque",
            count=7,
            low=-1000,
            high=1000,
            unit="Nm",
            metavar="T1,...,T7",
            help="A constant push of the environment on the joints τ1..τ7 \\[Nm].",
        ),
    ] = None,
    external_force: Annotated[
        Optional[tuple],
        floats(
            "--external-force",
            count=6,
            low=-1e4,
            high=1e4,
            metavar="FX,FY,FZ,MX,MY,MZ",
            help="A constant external wrench on the TCP Fx,Fy,Fz,Mx,My,Mz \\[N, Nm], base-frame axes.",
        ),
    ] = None,
    torque_noise: Annotated[
        float,
        number(
            "--torque-noise",
            low=0,
            high=1000,
            unit="Nm",
            help="Standard deviation of the noise on the measured torques \\[Nm].",
        ),
    ] = 0.0,
    flange: FlangeOpt = DEFAULT_FLANGE,
    tool: ToolOpt = None,
    limits: LimitsOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Emulate the robot controller's side of an FRI session on real UDP.

    Sends a monitoring message every period to --client and drives the session from the client's replies:
    MONITORING_WAIT → MONITORING_READY (quality GOOD) → COMMANDING_WAIT (client mirrors the ipo position) →
    COMMANDING_ACTIVE (commands executed within the velocity/acceleration limits); late or missing replies fall
    back to monitoring, a command outside the position limits is a safety stop. Runs until the session ends
    (IDLE), --timeout, or Ctrl-C/SIGTERM, each of which closes the session with IDLE messages (a second Ctrl-C
    quits at once); prints the states as they change and the session statistics.

    The robot application holds the robot (PositionHold): the ipo position stays where the robot stood when the
    overlay started, the measured position follows the client's commands (KUKA's LBRJointSineOverlay commands
    ipo + sine). FRI 2.7 messages carry the measured and ipo Cartesian poses, the external force and E1 (A3);
    --mode cartesian runs KUKA's CARTESIAN_POSE overlay, --transformation NAME requests frames from the client.
    """
    from trajectories.robot import parse_flange, parse_tool

    from ..console import Reporter
    from ..cup_options import cup_model
    from ..fri.sim import SimConfig
    from ..options import limits_from, within_limits
    from ..plants import default_plants

    rep = Reporter(json_out)
    within_limits(q0, limits_from(limits), "--q0")
    client_host, client_port = client
    forces = {name: value for name, value in (("external_torque", external_torque), ("external_force", external_force),
                                              ("cartesian_stiffness", cartesian_stiffness)) if value is not None}  # fmt: skip
    config = SimConfig(
        client_host=client_host, client_port=client_port, host=host, port=port, period_ms=period,
        receive_multiplier=receive_multiplier, version=fri_version, q0=tuple(float(x) for x in q0),
        flange=parse_flange(flange).value, tool=parse_tool(tool),
        plants=default_plants(length, damping, pendulum_pty=pendulum_pty, model=cup_model(cup, length)),
        commanding_after_s=commanding_after, session_duration_s=duration, max_runtime_s=timeout,
        loss=loss, delay_ms=delay, jitter_ms=jitter, malformed=malformed, seed=seed,
        quality_window=quality_window, quality_good=quality_good,
        quality_fair=min(0.5, quality_good), quality_excellent=max(0.98, quality_good),
        operation_mode=operation_mode, realtime=realtime, limits_path=str(limits) if limits is not None else None,
        overlay=not no_overlay, command_mode=mode, joint_stiffness=stiffness, damping_ratio=damping_ratio,
        io=_io_channels(io, io_preset), torque_noise=torque_noise, transformations=tuple(transformation or ()), **forces,
    )  # fmt: skip
    config.validate()
    stats, pendulum_path, (h, p) = _run_in_foreground(rep, config)
    if realtime and not stats.realtime:
        rep.warn("real-time scheduling was not granted (needs CAP_SYS_NICE); ran with normal priority")
    _print_stats(rep, stats, config.command_mode)
    rep.emit({"address": f"{h}:{p}", "client": f"{client_host}:{client_port}", "period_ms": period,
              "fri_version": fri_version, **stats.to_dict(), "pendulum_path": pendulum_path})  # fmt: skip


def _io_channels(io: list[str] | None, preset: str | None) -> tuple:
    """The application's IO configuration: --io-preset's channels, then each --io."""
    from ..fri.sim import IO_PRESETS, parse_io

    channels = tuple(parse_io(text) for text in io or ())
    if preset is None:
        return channels
    if preset not in IO_PRESETS:
        raise OptionError(f"--io-preset: one of {', '.join(IO_PRESETS)}, got {preset!r}")
    return IO_PRESETS[preset] + channels


def _run_in_foreground(rep, config) -> tuple:
    """Run the simulator here until the session ends or Ctrl-C/SIGTERM (each closes the session with IDLE messages; a
    second Ctrl-C quits at once), printing the states as they change; (stats, pendulum path, address)."""
    import signal

    from ..fri.constants import ConnectionQuality, SessionState
    from ..fri.sim import Simulator

    interrupted: list[int] = []  # signals received (SIGINT, SIGTERM)

    def on_state(state: SessionState, quality: ConnectionQuality, t: float) -> None:
        rep.print(f"{t:8.3f} s  {SessionState(state).name:<18} quality {ConnectionQuality(quality).name}")

    def on_signal(signum: int, frame: object) -> None:
        if interrupted and signum == signal.SIGINT:
            raise KeyboardInterrupt  # a second Ctrl-C: do not wait for the closing IDLE messages
        interrupted.append(signum)

    sim_ = Simulator(config, stop=lambda: bool(interrupted), on_state=on_state)
    h, p = sim_.address
    rep.print(f"FRI {config.version} simulator on {h}:{p}, sending every {config.period_ms} ms to {config.client_host}:"
              f"{config.client_port}, {config.command_mode} command mode (Ctrl-C stops)")  # fmt: skip
    if sim_.pendulum_path is not None:
        rep.print(f"pendulum module emulated on {sim_.pendulum_path}")
    previous = signal.signal(signal.SIGINT, on_signal), signal.signal(signal.SIGTERM, on_signal)
    try:
        return sim_.run(), sim_.pendulum_path, (h, p)
    finally:
        signal.signal(signal.SIGINT, previous[0])
        signal.signal(signal.SIGTERM, previous[1])


def _print_stats(rep, stats, command_mode: str) -> None:
    """The session statistics: the end, cycles and replies, timing, what was ignored or refused, the ball."""
    rep.print(
        f"end: {stats.end_reason or '-'}; {stats.cycles} cycles, {stats.replies} replies "
        f"({stats.late_replies} late, {stats.missed_replies} missed), {stats.commanded_rows} commands executed"
    )
    if stats.period_ms_p50 is not None:
        rep.print(
            f"send period p50 {stats.period_ms_p50:.3f} ms, p99 {stats.period_ms_p99:.3f} ms, max {stats.period_ms_max:.3f} ms"
        )
    if stats.reply_latency_ms_p50 is not None:
        rep.print(f"reply latency p50 {stats.reply_latency_ms_p50:.3f} ms, p99 {stats.reply_latency_ms_p99:.3f} ms, "
                  f"max {stats.reply_latency_ms_max:.3f} ms")  # fmt: skip
    if stats.foreign_received or stats.malformed_received:
        rep.print(f"ignored: {stats.foreign_received} foreign, {stats.malformed_received} malformed datagrams")
    if stats.io_writes or stats.io_refused:
        rep.print(f"IO: {stats.io_writes} writes applied, {stats.io_refused} refused (input or unknown channel)")
    if stats.incomplete_commands:
        rep.print(f"{stats.incomplete_commands} commands lacked the {command_mode} the mode needs (taken as 0)")
    if stats.command_problem:
        rep.print(f"[red]overlay ended[/red]: {stats.command_problem}")
    for name, fig in stats.transformations.items():
        last = fig["last"]
        where = "" if last is None else " last x, y, z " + ", ".join(f"{v * 1e3:.3f}" for v in last[:3]) + " mm"
        rep.print(f"transformation {name}: {fig['received']} values received{where}")
    if stats.safety_stop:
        rep.print("[red]safety stop[/red]: a command was outside the position limits (or not a number)")
    if stats.max_ball_theta is not None:
        rep.print(f"ball: max tilt {math.degrees(stats.max_ball_theta):.2f} deg")
        catch = stats.plants.get("ball", {}).get("cup")
        if catch is not None:
            rep.print("ball: " + ("caught in the cup" if catch["caught"] else f"not caught — {catch['failure']}"))


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("sim")(sim)
