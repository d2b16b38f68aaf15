"""`lbr sim`: the FRI controller simulator on its own, in the foreground."""

from __future__ import annotations

from typing import Annotated, Optional

import typer

from ..cup_options import CupSpecOpt
from ..options import DEFAULT_FLANGE, FlangeOpt, JsonOpt, LimitsOpt, ToolOpt, THESIS_Q_START


def _parse_client(text: str) -> tuple[str, int]:
    from trajectories.errors import OptionError

    host, sep, port = text.rpartition(":")
    if not sep or not host:
        raise OptionError(f"--client: expected HOST:PORT, got {text!r}")
    try:
        number = int(port)
    except ValueError:
        raise OptionError(f"--client: port must be an integer, got {port!r}") from None
    if not 1 <= number <= 65535:
        raise OptionError(f"--client: port must be 1..65535, got {number}")
    return host, number


def _floats(text: str, n: int, option: str) -> tuple[float, ...]:
    from trajectories.errors import OptionError

    try:
        values = tuple(float(x) for x in text.split(","))
    except ValueError:
        raise OptionError(f"{option}: expected {n} comma-separated numbers, got {text!r}") from None
    if len(values) != n:
        raise OptionError(f"{option}: expected {n} comma-separated numbers, got {len(values)}")
    return values


def sim(
    port: Annotated[int, typer.Option("--port", help="UDP port the simulator sends from and listens on (0: any free port).")] = 0,
    host: Annotated[str, typer.Option("--host", help="Address the simulator binds.")] = "127.0.0.1",
    period: Annotated[int, typer.Option("--period", help="Send period \\[ms], 1..100.")] = 1,
    client: Annotated[str, typer.Option("--client", help="Where monitoring messages go: HOST:PORT of the FRI client.")] = "127.0.0.1:30200",
    q0: Annotated[str, typer.Option("--q0", help="Start joint positions q1..q7 \\[rad, or with deg suffix].")] = THESIS_Q_START,
    length: Annotated[Optional[float], typer.Option("--length", help="Simulate a ball on a string of this length \\[m] hanging from the TCP.")] = None,
    damping: Annotated[float, typer.Option("--damping", help="Damping of the simulated ball \\[1/s].")] = 0.0,
    cup: CupSpecOpt = None,
    fri_version: Annotated[str, typer.Option("--fri-version", help="Wire format: 1.15 (bare protobuf) or 2.7 (length + CRC-32 framing).")] = "1.15",
    receive_multiplier: Annotated[int, typer.Option("--receive-multiplier", help="The client answers every k-th message.")] = 1,
    duration: Annotated[Optional[float], typer.Option("--duration", help="COMMANDING_ACTIVE time \\[s] after which the robot application ends the session (default: until the client stops); with --no-overlay the time from the first MONITORING_READY.")] = None,
    timeout: Annotated[Optional[float], typer.Option("--timeout", help="Stop the simulator after this wall time \\[s] (it closes the session: IDLE).")] = None,
    commanding_after: Annotated[float, typer.Option("--commanding-after", help="Time \\[s] from the first MONITORING_READY until the overlay starts (at quality GOOD).")] = 0.2,
    quality_window: Annotated[int, typer.Option("--quality-window", help="Cycles in the sliding window of the connection quality.")] = 50,
    quality_good: Annotated[float, typer.Option("--quality-good", help="Share of timely cycles in the window for GOOD (commanding allowed), 0..1; FAIR from 0.5, EXCELLENT from 0.98.")] = 0.9,
    operation_mode: Annotated[str, typer.Option("--operation-mode", help="Reported operation mode: T1, T2 or AUT.")] = "T1",
    loss: Annotated[float, typer.Option("--loss", help="Fault injection: probability of dropping a monitoring message.")] = 0.0,
    delay: Annotated[float, typer.Option("--delay", help="Fault injection: delay of every monitoring message \\[ms].")] = 0.0,
    jitter: Annotated[float, typer.Option("--jitter", help="Fault injection: extra random delay, uniform 0..J \\[ms].")] = 0.0,
    malformed: Annotated[float, typer.Option("--malformed", help="Fault injection: probability of sending a corrupted datagram instead.")] = 0.0,
    seed: Annotated[int, typer.Option("--seed", help="Seed of the fault injection.")] = 0,
    realtime: Annotated[bool, typer.Option("--realtime", help="Run the loop with real-time scheduling (SCHED_FIFO) if permitted: steadier 1 ms under load.")] = False,
    pendulum_pty: Annotated[bool, typer.Option("--pendulum-pty", help="Also emulate the thesis's pendulum module: the ball's planar angle θy as AS5600 lines on a pseudo-terminal (its path is printed; read it with --pendulum PATH). Needs --length.")] = False,
    no_overlay: Annotated[bool, typer.Option("--no-overlay", help="The application only monitors the session (never commands; --duration counts from the first MONITORING_READY), e.g. for KUKA's IOAccess example, which mirrors no positions.")] = False,
    mode: Annotated[str, typer.Option("--mode", help="Client command mode of the simulated FRI overlay: position (joint position, position control), torque (joint impedance + commanded torque) or wrench (Cartesian impedance + commanded wrench).")] = "position",
    stiffness: Annotated[float, typer.Option("--stiffness", help="Joint impedance stiffness \\[Nm/rad] (--mode torque), every joint.")] = 1000.0,
    cartesian_stiffness: Annotated[str, typer.Option("--cartesian-stiffness", help="Cartesian impedance stiffness TRANS,ROT \\[N/m, Nm/rad] along the TCP axes (--mode wrench).")] = "2000,200",
    damping_ratio: Annotated[float, typer.Option("--damping-ratio", help="Damping ratio ζ of the impedance controllers (KUKA's default 0.7).")] = 0.7,
    io: Annotated[Optional[list[str]], typer.Option("--io", help="An IO channel of the application's FRI IO configuration: NAME:TYPE:DIRECTION\\[:VALUE], TYPE boolean|digital|analog, DIRECTION in|out (repeatable).")] = None,
    io_preset: Annotated[Optional[str], typer.Option("--io-preset", help="A ready IO configuration: kuka-ioaccess (the channels KUKA's IOAccess example uses).")] = None,
    external_torque: Annotated[Optional[str], typer.Option("--external-torque", help="A constant push of the environment on the joints τ1..τ7 \\[Nm].")] = None,
    external_force: Annotated[Optional[str], typer.Option("--external-force", help="A constant external wrench on the TCP Fx,Fy,Fz,Mx,My,Mz \\[N, Nm], base-frame axes.")] = None,
    torque_noise: Annotated[float, typer.Option("--torque-noise", help="Standard deviation of the noise on the measured torques \\[Nm].")] = 0.0,
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
    ipo + sine). FRI 2.7 messages carry the measured and ipo Cartesian poses, the external force and E1 (A3).
    """
    from trajectories.robot import parse_flange, parse_tool

    from ..console import Reporter
    from ..fri.constants import ConnectionQuality, SessionState
    from trajectories.errors import OptionError

    from ..fri.sim import IO_PRESETS, SimConfig, Simulator, parse_io
    from ..parsing import parse_joint_vector
    from ..plants import default_plants

    rep = Reporter(json_out)
    client_host, client_port = _parse_client(client)
    channels = tuple(parse_io(text) for text in io or ())
    if io_preset is not None:
        if io_preset not in IO_PRESETS:
            raise OptionError(f"--io-preset: one of {', '.join(IO_PRESETS)}, got {io_preset!r}")
        channels = IO_PRESETS[io_preset] + channels
    if length is not None and not length > 0:
        raise OptionError(f"--length: string length must be > 0 m, got {length:g}")
    cup_model = None
    if cup is not None:
        from ..cup_options import parse_cup_spec

        if length is None:
            raise OptionError("--cup needs the simulated ball (--length)")
        cup_model = parse_cup_spec(cup, length)
    extra = {}
    for name, text, n in (("external_torque", external_torque, 7), ("external_force", external_force, 6),
                          ("cartesian_stiffness", cartesian_stiffness, 2)):
        if text is not None:
            extra[name] = _floats(text, n, "--" + name.replace("_", "-"))
    config = SimConfig(
        client_host=client_host, client_port=client_port, host=host, port=port, period_ms=period,
        receive_multiplier=receive_multiplier, version=fri_version,
        q0=tuple(float(x) for x in parse_joint_vector(q0, "--q0")),
        flange=parse_flange(flange).value, tool=parse_tool(tool),
        plants=default_plants(length, damping, pendulum_pty=pendulum_pty, model=cup_model),
        commanding_after_s=commanding_after, session_duration_s=duration, max_runtime_s=timeout,
        loss=loss, delay_ms=delay, jitter_ms=jitter, malformed=malformed, seed=seed,
        quality_window=quality_window, quality_good=quality_good,
        quality_fair=min(0.5, quality_good), quality_excellent=max(0.98, quality_good),
        operation_mode=operation_mode.upper(), realtime=realtime, limits_path=str(limits) if limits is not None else None,
        overlay=not no_overlay, command_mode=mode.lower(), joint_stiffness=stiffness, damping_ratio=damping_ratio, io=channels,
        torque_noise=torque_noise, **extra,
    )
    config.validate()
    interrupted: list[int] = []  # signals received (SIGINT, SIGTERM)

    def on_state(state: SessionState, quality: ConnectionQuality, t: float) -> None:
        rep.print(f"{t:8.3f} s  {SessionState(state).name:<18} quality {ConnectionQuality(quality).name}")

    sim_ = Simulator(config, stop=lambda: bool(interrupted), on_state=on_state)
    h, p = sim_.address
    rep.print(f"FRI {fri_version} simulator on {h}:{p}, sending every {period} ms to {client_host}:{client_port}, "
              f"{config.command_mode} command mode (Ctrl-C stops)")
    if sim_.pendulum_path is not None:
        rep.print(f"pendulum module emulated on {sim_.pendulum_path}")
    import signal

    def on_signal(signum: int, frame: object) -> None:
        if interrupted and signum == signal.SIGINT:
            raise KeyboardInterrupt  # a second Ctrl-C: do not wait for the closing IDLE messages
        interrupted.append(signum)

    previous = signal.signal(signal.SIGINT, on_signal), signal.signal(signal.SIGTERM, on_signal)
    try:
        stats = sim_.run()
    finally:
        signal.signal(signal.SIGINT, previous[0])
        signal.signal(signal.SIGTERM, previous[1])
    if realtime and not stats.realtime:
        rep.warn("real-time scheduling was not granted (needs CAP_SYS_NICE); ran with normal priority")
    figures = stats.to_dict()
    figures["pendulum_path"] = sim_.pendulum_path
    rep.print(
        f"end: {stats.end_reason or '-'}; {stats.cycles} cycles, {stats.replies} replies "
        f"({stats.late_replies} late, {stats.missed_replies} missed), {stats.commanded_rows} commands executed"
    )
    if stats.period_ms_p50 is not None:
        rep.print(
            f"send period p50 {stats.period_ms_p50:.3f} ms, p99 {stats.period_ms_p99:.3f} ms, "
            f"max {stats.period_ms_max:.3f} ms"
        )
    if stats.reply_latency_ms_p50 is not None:
        rep.print(
            f"reply latency p50 {stats.reply_latency_ms_p50:.3f} ms, p99 {stats.reply_latency_ms_p99:.3f} ms, "
            f"max {stats.reply_latency_ms_max:.3f} ms"
        )
    if stats.foreign_received or stats.malformed_received:
        rep.print(f"ignored: {stats.foreign_received} foreign, {stats.malformed_received} malformed datagrams")
    if stats.io_writes or stats.io_refused:
        rep.print(f"IO: {stats.io_writes} writes applied, {stats.io_refused} refused (input or unknown channel)")
    if stats.incomplete_commands:
        rep.print(f"{stats.incomplete_commands} commands lacked the {config.command_mode} the mode needs (taken as 0)")
    if stats.safety_stop:
        rep.print("[red]safety stop[/red]: a command was outside the position limits (or not a number)")
    if stats.max_ball_theta is not None:
        import math

        rep.print(f"ball: max tilt {math.degrees(stats.max_ball_theta):.2f} deg")
        catch = stats.plants.get("ball", {}).get("cup")
        if catch is not None:
            rep.print("ball: " + ("caught in the cup" if catch["caught"] else f"not caught — {catch['failure']}"))
    rep.emit({"address": f"{h}:{p}", "client": f"{client_host}:{client_port}", "period_ms": period,
              "fri_version": fri_version, **figures})


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("sim")(sim)
