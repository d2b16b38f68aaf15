"""`lbr serve`: the FRI session driven from other processes — joint or pose targets over UDP and MQTT, the state
sent back."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Optional

import typer

from ..fri_options import (
    DEFAULT_BALL_LENGTH,
    BindOpt,
    LengthOpt,
    LogOpt,
    SessionPeriodOpt,
    PortOpt,
    RealtimeOpt,
    BusyWaitOpt,
    RobotOpt,
    SimLenientOpt,
    SimStartOpt,
    VersionOpt,
    WaitOpt,
)
from ..options import DEFAULT_FLANGE, FlangeOpt, JsonOpt, LimitsOpt, ToolOpt, number


def serve(
    listen: Annotated[
        str, typer.Option("--listen", help="HOST:PORT where targets arrive over UDP (the state goes back to the source); 'off': no UDP.")
    ] = "127.0.0.1:30300",
    mqtt: Annotated[
        Optional[str], typer.Option("--mqtt", help="Also take targets from this MQTT topic: mqtt://[USER:PASSWORD@]HOST:PORT/TOPIC (mqtts:// for TLS); the state is published on TOPIC/state.")
    ] = None,
    mqtt_state_hz: Annotated[
        float, number("--mqtt-state-hz", low=0, high=1000, unit="Hz", help="Publish the state on MQTT at most this often \\[Hz] (0: never).")
    ] = 50.0,
    secret: Annotated[
        Optional[Path], typer.Option("--secret", help="File with a shared secret (>= 16 bytes): every target must end with its HMAC-SHA256 tag; others are ignored.")
    ] = None,
    source: Annotated[
        Optional[frozenset], typer.Option("--source", parser=parse_sources, metavar="IP,IP,...", help="Comma-separated IP addresses that may command (default: any; the first owns the session).")
    ] = None,
    timeout: Annotated[
        float, number("--timeout", low=0.005, high=10, unit="s", help="Dead-man: brake when no target arrived for this long \\[s].")
    ] = 0.1,
    first_target: Annotated[
        float, number("--first-target", low=0.1, high=3600, unit="s", help="Stop if no target arrived this long after commanding started \\[s].")
    ] = 30.0,
    delay: Annotated[
        Optional[float], number("--delay", low=0, high=10, unit="s", help="Follow the targets this long behind the newest, on the source's clock \\[s] (default: automatic, from the source's gaps and jitter, 2 ms to --timeout).")
    ] = None,
    speed_scale: Annotated[
        float, number("--speed-scale", low=0, high=1, low_open=True, help="Share of the velocity, acceleration and jerk limits ruckig may use.")
    ] = 0.5,
    state_every: Annotated[
        int, number("--state-every", low=0, high=1000, integer=True, help="Send the state back every N FRI messages (0: never).")
    ] = 1,
    duration: Annotated[
        Optional[float], number("--duration", low=0, high=86400, low_open=True, unit="s", help="End (braking) after this long \\[s] (default: until the source ends).")
    ] = None,
    robot: RobotOpt = None,
    port: PortOpt = 30200,
    bind: BindOpt = None,
    fri_version: VersionOpt = None,
    period: SessionPeriodOpt = None,
    log: LogOpt = None,
    sim_start: SimStartOpt = None,
    length: LengthOpt = None,
    wait: WaitOpt = None,
    realtime: RealtimeOpt = False,
    busy_wait: BusyWaitOpt = None,
    sim_lenient: SimLenientOpt = True,
    flange: FlangeOpt = DEFAULT_FLANGE,
    tool: ToolOpt = None,
    limits: LimitsOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Run an FRI session that follows targets sent by another process (Simulink, MATLAB, ROS 2, a teleoperation
    station, a script).

    Targets arrive over UDP at --listen and/or on the --mqtt topic, binary (136 bytes, magic LBRT, version 1) or
    JSON: joints {"q": \\[7 rad]}, a TCP pose {"pose": \\[x, y, z m, qw, qx, qy, qz]} or {"pose_zyx": \\[x, y, z m,
    alpha, beta, gamma rad]}, with optional feed-forward "v" / "twist" (layout in the docs' file formats and
    lbrcli.bridge.protocol). Poses go through the online IK; the targets are read back on their source's clock
    ("t"), --delay behind the newest and interpolated, and ruckig follows that reference within --speed-scale of
    the limits at every FRI cycle; the guard checks every command. The state (256 bytes, magic LBRS, or JSON
    for JSON sources) goes back over UDP every --state-every messages and on TOPIC/state at --mqtt-state-hz. The
    first source owns the session; others are ignored. A braking stop within the limits ends it when targets stop
    for --timeout (dead-man), the owner sends garbage or a joint target outside the position limits (exit 1), it
    sends {"end": true} or --duration elapses (exit 0), or Ctrl-C.
    """
    from lbrcli.bridge import MqttTransport, MqttUnavailable, TargetFollower, TargetInbox, TimelineOptions, UdpTransport
    from lbrcli.lab.telemetry import parse_mqtt_url
    from trajectories.errors import OptionError

    from ..console import Reporter
    from ..fri_options import busy_wait_seconds, check_simulator_only
    from ..fri_runner import exit_for, print_summary, run_client, simulator_kwargs
    from ..options import THESIS_Q_START, limits_from, make_robot, within_limits

    rep = Reporter(json_out)
    udp = listen.strip().lower() != "off"
    host, _, lport = listen.rpartition(":")
    if udp and (not host or not (lport.isascii() and lport.isdigit()) or not 0 <= int(lport) <= 65535):
        raise OptionError(f"--listen must be HOST:PORT or off, got {listen!r}")
    if not udp and mqtt is None:
        raise OptionError("--listen off needs --mqtt: targets must come from somewhere")
    mqtt_target = parse_mqtt_url(mqtt) if mqtt is not None else None
    key = _read_secret(secret) if secret is not None else None
    if delay is not None and not delay < timeout:
        raise OptionError(f"--delay must be less than --timeout ({timeout:g} s), got {delay:g}")
    check_simulator_only(robot, {"--sim-start": sim_start is not None, "--length": length is not None,
                                 "--sim-strict": not sim_lenient})  # fmt: skip
    lim = limits_from(limits)
    within_limits(sim_start, lim, "--sim-start")
    allowed = set(source) if source else None
    sim_kwargs: dict[str, Any] = {}
    if robot is None:
        sim_kwargs = simulator_kwargs(length=length, default_length=DEFAULT_BALL_LENGTH, period_ms=period or 1,
                                      sim_start=sim_start, default_start=THESIS_Q_START, flange=flange, tool=tool,
                                      max_runtime_s=(duration or 86400.0) + 120.0, limits=limits)  # fmt: skip
    if allowed and not udp:
        raise OptionError("--source restricts UDP senders; with --listen off use the broker's ACL or --secret")
    transports: list = []
    try:
        if udp:
            transports.append(UdpTransport(int(lport), host, allowed))
            rep.print(f"targets on udp://{host}:{transports[-1].port}"
                      + (f" from {', '.join(sorted(allowed))}" if allowed else ""))  # fmt: skip
        if mqtt_target is not None:
            transports.append(MqttTransport(mqtt_target, state_rate_hz=mqtt_state_hz).start())
            rep.print(f"targets on mqtt://{mqtt_target.host}:{mqtt_target.port}/{mqtt_target.topic} "
                      f"(state on {transports[-1].state_topic})")  # fmt: skip
    except OSError as exc:
        for tr in transports:
            tr.close()
        raise OptionError(f"--listen {listen}: cannot bind ({exc.strerror})") from None
    except MqttUnavailable as exc:
        for tr in transports:
            tr.close()
        raise OptionError(f"--mqtt: {exc}") from None
    targets = TargetInbox(transports, key, lim)
    follower = TargetFollower(targets, lim, robot=make_robot(flange, tool), timeout_s=timeout,
                              first_target_s=first_target, speed_scale=speed_scale, state_every=state_every,
                              timeline=TimelineOptions(delay_s=delay, max_delay_s=timeout))  # fmt: skip
    try:
        result, sim_stats, _ = run_client(
            rep, follower, robot=robot, port=port, bind=bind, version=fri_version, limits=lim, log_path=log, wait=wait,
            sim_kwargs=sim_kwargs, sim_lenient=sim_lenient, duration_s=duration, realtime=realtime, busy_wait_s=busy_wait_seconds(busy_wait),
        )  # fmt: skip
    finally:
        targets.close()
    figures = print_summary(rep, result, sim_stats, log)
    f = result.figures
    rep.print(f"targets: {f.get('targets_accepted', 0)} accepted, {f.get('targets_bad', 0)} bad, "
              f"{f.get('targets_foreign', 0)} from other sources, {f.get('targets_stale', 0)} stale"
              + (f", {f.get('targets_unauthenticated', 0)} unauthenticated" if key is not None else ""))  # fmt: skip
    if f.get("pose_targets"):
        rep.print(f"pose targets: {f['pose_targets']}, {f['poses_unreached']} not reached "
                  f"(closest configuration followed; max TCP error {f['max_ik_position_error_m'] * 1e3:.1f} mm), "
                  f"IK at most {f['ik_time_max_ms']:.2f} ms in a cycle")  # fmt: skip
    figures.update(listen=f"{host}:{transports[0].port}" if udp else None, mqtt=mqtt_target.topic if mqtt_target else None,
                   robot=robot or "simulator")  # fmt: skip
    rep.emit(figures)
    exit_for(result)
    if not f.get("targets_accepted"):  # the session ended as asked, but nothing was served
        import sys

        sys.stderr.write("lbr: failed: no target arrived during the session (is the source sending to --listen?)\n")
        raise typer.Exit(1)


def parse_sources(text: str | None) -> frozenset[str] | None:
    """--source: comma-separated IP addresses (the UDP senders allowed to command), checked at parse time."""
    import ipaddress

    if text is None or isinstance(text, frozenset):
        return text
    hosts = [h.strip() for h in str(text).split(",") if h.strip()]
    if not hosts:
        raise typer.BadParameter(f"expected comma-separated IP addresses, got {text!r}")
    try:
        return frozenset(str(ipaddress.ip_address(h)) for h in hosts)
    except ValueError as exc:
        raise typer.BadParameter(f"{exc} (UDP senders are matched by their IP address)") from None


def _read_secret(path: Path) -> bytes:
    from trajectories.errors import InputError, OptionError
    from trajectories.inputs import MAX_SMALL_BYTES, read_input

    try:
        key = read_input(path, MAX_SMALL_BYTES, text=False).rstrip(b"\r\n")
    except InputError as exc:
        raise OptionError(f"--secret {path}: {exc.message}") from None
    if len(key) < 16:
        raise OptionError(f"--secret {path}: the secret has {len(key)} bytes, at least 16 are needed")
    return key


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("serve")(serve)
