"""`lbr sim`: the FRI controller simulator on its own, in the foreground."""

from __future__ import annotations

from typing import Annotated, Optional

import typer

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


def sim(
    port: Annotated[int, typer.Option("--port", help="UDP port the simulator sends from and listens on (0: any free port).")] = 0,
    host: Annotated[str, typer.Option("--host", help="Address the simulator binds.")] = "127.0.0.1",
    period: Annotated[int, typer.Option("--period", help="Send period \\[ms], 1..100.")] = 1,
    client: Annotated[str, typer.Option("--client", help="Where monitoring messages go: HOST:PORT of the FRI client.")] = "127.0.0.1:30200",
    q0: Annotated[str, typer.Option("--q0", help="Start joint positions q1..q7 \\[rad, or with deg suffix].")] = THESIS_Q_START,
    length: Annotated[Optional[float], typer.Option("--length", help="Simulate a ball on a string of this length \\[m] hanging from the TCP.")] = None,
    damping: Annotated[float, typer.Option("--damping", help="Damping of the simulated ball \\[1/s].")] = 0.0,
    fri_version: Annotated[str, typer.Option("--fri-version", help="Wire format: 1.15 (bare protobuf) or 2.7 (length + CRC-32 framing).")] = "1.15",
    receive_multiplier: Annotated[int, typer.Option("--receive-multiplier", help="The client answers every k-th message.")] = 1,
    duration: Annotated[Optional[float], typer.Option("--duration", help="COMMANDING_ACTIVE time \\[s] after which the robot application ends the session (default: until the client stops).")] = None,
    timeout: Annotated[Optional[float], typer.Option("--timeout", help="Stop the simulator after this wall time \\[s].")] = None,
    commanding_after: Annotated[float, typer.Option("--commanding-after", help="Time \\[s] in MONITORING_READY before the overlay starts.")] = 0.2,
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
    (IDLE), --timeout, or Ctrl-C; prints the states as they change and the session statistics.
    """
    from trajectories.robot import parse_flange, parse_tool

    from ..console import Reporter
    from ..fri.constants import ConnectionQuality, SessionState
    from ..fri.simulator import SimConfig, Simulator
    from ..parsing import parse_joint_vector

    rep = Reporter(json_out)
    client_host, client_port = _parse_client(client)
    config = SimConfig(
        client_host=client_host, client_port=client_port, host=host, port=port, period_ms=period,
        receive_multiplier=receive_multiplier, version=fri_version,
        q0=tuple(float(x) for x in parse_joint_vector(q0, "--q0")),
        flange=parse_flange(flange).value, tool=parse_tool(tool), ball_length=length, ball_damping=damping,
        commanding_after_s=commanding_after, session_duration_s=duration, max_runtime_s=timeout,
        loss=loss, delay_ms=delay, jitter_ms=jitter, malformed=malformed, seed=seed,
        quality_window=quality_window, quality_good=quality_good,
        quality_fair=min(0.5, quality_good), quality_excellent=max(0.98, quality_good),
        operation_mode=operation_mode.upper(), realtime=realtime, limits_path=str(limits) if limits is not None else None,
        pendulum_pty=pendulum_pty,
    )
    config.validate()
    interrupted = []

    def on_state(state: SessionState, quality: ConnectionQuality, t: float) -> None:
        rep.print(f"{t:8.3f} s  {SessionState(state).name:<18} quality {ConnectionQuality(quality).name}")

    sim_ = Simulator(config, stop=lambda: bool(interrupted), on_state=on_state)
    h, p = sim_.address
    rep.print(f"FRI {fri_version} simulator on {h}:{p}, sending every {period} ms to {client_host}:{client_port} (Ctrl-C stops)")
    if sim_.pendulum_path is not None:
        rep.print(f"pendulum module emulated on {sim_.pendulum_path}")
    import signal

    previous = signal.signal(signal.SIGINT, lambda *_: interrupted.append(True))
    try:
        stats = sim_.run()
    finally:
        signal.signal(signal.SIGINT, previous)
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
    if stats.safety_stop:
        rep.print("[red]safety stop[/red]: a command was outside the position limits")
    if stats.max_ball_theta is not None:
        import math

        rep.print(f"ball: max tilt {math.degrees(stats.max_ball_theta):.2f} deg")
    rep.emit({"address": f"{h}:{p}", "client": f"{client_host}:{client_port}", "period_ms": period,
              "fri_version": fri_version, **figures})


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("sim")(sim)
