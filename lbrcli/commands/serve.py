"""`lbr serve`: the FRI session driven from other processes — joint or pose targets over UDP and MQTT, the state
sent back."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated, Optional

import typer

from trajectories.errors import OptionError

from ..console import Reporter
from ..fri_options import FRI_OPTIONS, FriOptions
from ..fri_runner import exit_for, print_summary, run_client
from ..option_groups import with_options
from ..options import (
    DEFAULT_FLANGE,
    FlangeOpt,
    JsonOpt,
    LimitsOpt,
    ToolOpt,
    limits_from,
    make_robot,
    number,
    within_limits,
)


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


@with_options(fri=FRI_OPTIONS.without("sim_fast"))
def serve(
    fri: FriOptions,
    listen: Annotated[
        str,
        typer.Option(
            "--listen",
            help="HOST:PORT where targets arrive over UDP (the state goes back to the source); 'off': no UDP.",
        ),
    ] = "127.0.0.1:30300",
    mqtt: Annotated[
        Optional[str],
        typer.Option(
            "--mqtt",
            help="Also take targets from this MQTT topic: mqtt://[USER:PASSWORD@]HOST:PORT/TOPIC (mqtts:// for TLS); the state is published on TOPIC/state.",
        ),
    ] = None,
    mqtt_state_hz: Annotated[
        float,
        number(
            "--mqtt-state-hz",
            low=0,
            high=1000,
            unit="Hz",
            help="Publish the state on MQTT at most this often \\[Hz] (0: never).",
        ),
    ] = 50.0,
    secret: Annotated[
        Optional[Path],
        typer.Option(
            "--secret",
            help="File with a shared secret (>= 16 bytes): every target must end with its HMAC-SHA256 tag; others are ignored.",
        ),
    ] = None,
    source: Annotated[
        Optional[frozenset],
        typer.Option(
            "--source",
            parser=parse_sources,
            metavar="IP,IP,...",
            help="Comma-separated IP addresses that may command (default: any; the first owns the session).",
        ),
    ] = None,
    timeout: Annotated[
        float,
        number(
            "--timeout",
            low=0.005,
            high=10,
            unit="s",
            help="Dead-man: brake when no target arrived for this long \\[s].",
        ),
    ] = 0.1,
    first_target: Annotated[
        float,
        number(
            "--first-target",
            low=0.1,
            high=3600,
            unit="s",
            help="Stop if no target arrived this long after commanding started \\[s].",
        ),
    ] = 30.0,
    delay: Annotated[
        Optional[float],
        number(
            "--delay",
            low=0,
            high=10,
            unit="s",
            help="Follow the targets this long behind the newest, on the source's clock \\[s] (default: automatic, from the source's gaps and jitter, 2 ms to --timeout).",
        ),
    ] = None,
    speed_scale: Annotated[
        float,
        number(
            "--speed-scale",
            low=0,
            high=1,
            low_open=True,
            help="Share of the velocity, acceleration and jerk limits ruckig may use.",
        ),
    ] = 0.5,
    state_every: Annotated[
        int,
        number(
            "--state-every", low=0, high=1000, integer=True, help="Send the state back every N FRI messages (0: never)."
        ),
    ] = 1,
    duration: Annotated[
        Optional[float],
        number(
            "--duration",
            low=0,
            high=86400,
            low_open=True,
            unit="s",
            help="End (braking) after this long \\[s] (default: until the source ends).",
        ),
    ] = None,
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
    from lbrcli.bridge import TargetFollower, TimelineOptions

    rep = Reporter(json_out)
    endpoint = _listen_address(listen, mqtt, source)
    key = _read_secret(secret) if secret is not None else None
    if delay is not None and not delay < timeout:
        raise OptionError(f"--delay must be less than --timeout ({timeout:g} s), got {delay:g}")
    fri.check_simulator_only()
    lim = limits_from(limits)
    within_limits(fri.sim_start, lim, "--sim-start")
    session = fri.session(lim, duration_s=duration)
    simulator = fri.simulator(max_runtime_s=(duration or 86400.0) + 120.0, ball=fri.ball(), flange=flange, tool=tool,
                              limits=limits)  # fmt: skip
    targets, (listening, topic) = _open_targets(rep, endpoint, mqtt, mqtt_state_hz, source, key, lim)
    follower = TargetFollower(targets, lim, robot=make_robot(flange, tool), timeout_s=timeout,
                              first_target_s=first_target, speed_scale=speed_scale, state_every=state_every,
                              timeline=TimelineOptions(delay_s=delay, max_delay_s=timeout))  # fmt: skip
    try:
        result, sim_stats, _ = run_client(rep, follower, session, simulator)
    finally:
        targets.close()
    figures = print_summary(rep, result, sim_stats, session.log)
    _print_targets(rep, result.figures, key is not None)
    figures.update(listen=listening, mqtt=topic, robot=fri.robot or "simulator")
    rep.emit(figures)
    exit_for(result)
    if not result.figures.get("targets_accepted"):  # the session ended as asked, but nothing was served
        sys.stderr.write("lbr: failed: no target arrived during the session (is the source sending to --listen?)\n")
        raise typer.Exit(1)


def _listen_address(listen: str, mqtt: str | None, source: frozenset | None) -> tuple[str, int] | None:
    """--listen as (host, port), None for 'off'; OptionError when it does not go with --mqtt and --source."""
    if listen.strip().lower() == "off":
        if mqtt is None:
            raise OptionError("--listen off needs --mqtt: targets must come from somewhere")
        if source:
            raise OptionError("--source restricts UDP senders; with --listen off use the broker's ACL or --secret")
        return None
    host, _, port = listen.rpartition(":")
    if not host or not (port.isascii() and port.isdigit()) or not 0 <= int(port) <= 65535:
        raise OptionError(f"--listen must be HOST:PORT or off, got {listen!r}")
    return host, int(port)


def _open_targets(rep, endpoint: tuple[str, int] | None, mqtt: str | None, state_hz: float, source: frozenset | None,
                  key: bytes | None, lim):  # fmt: skip
    """The target inbox over UDP at ``endpoint`` and/or the --mqtt topic, and where they are ("HOST:PORT" and the
    topic, for the figures); OptionError when one cannot be opened."""
    from lbrcli.bridge import MqttTransport, MqttUnavailable, TargetInbox, UdpTransport
    from lbrcli.lab.telemetry import parse_mqtt_url

    mqtt_target = parse_mqtt_url(mqtt, "--mqtt") if mqtt is not None else None
    transports: list = []
    try:
        if endpoint is not None:
            host, port = endpoint
            transports.append(UdpTransport(port, host, set(source) if source else None))
            rep.print(f"targets on udp://{host}:{transports[-1].port}"
                      + (f" from {', '.join(sorted(source))}" if source else ""))  # fmt: skip
        if mqtt_target is not None:
            transports.append(MqttTransport(mqtt_target, state_rate_hz=state_hz).start())
            rep.print(f"targets on mqtt://{mqtt_target.host}:{mqtt_target.port}/{mqtt_target.topic} "
                      f"(state on {transports[-1].state_topic})")  # fmt: skip
    except (OSError, MqttUnavailable) as exc:
        for tr in transports:
            tr.close()
        if isinstance(exc, MqttUnavailable):
            raise OptionError(f"--mqtt: {exc}") from None
        raise OptionError(f"--listen {endpoint[0]}:{endpoint[1]}: cannot bind ({exc.strerror})") from None  # type: ignore[index]
    where = (f"{endpoint[0]}:{transports[0].port}" if endpoint is not None else None,
             mqtt_target.topic if mqtt_target is not None else None)  # fmt: skip
    return TargetInbox(transports, key, lim), where


def _print_targets(rep, f: dict, authenticated: bool) -> None:
    """What the targets did (accepted, bad, foreign, stale, unauthenticated; poses and their IK)."""
    rep.print(f"targets: {f.get('targets_accepted', 0)} accepted, {f.get('targets_bad', 0)} bad, "
              f"{f.get('targets_foreign', 0)} from other sources, {f.get('targets_stale', 0)} stale"
              + (f", {f.get('targets_unauthenticated', 0)} unauthenticated" if authenticated else ""))  # fmt: skip
    if f.get("pose_targets"):
        rep.print(f"pose targets: {f['pose_targets']}, {f['poses_unreached']} not reached "
                  f"(closest configuration followed; max TCP error {f['max_ik_position_error_m'] * 1e3:.1f} mm), "
                  f"IK at most {f['ik_time_max_ms']:.2f} ms in a cycle")  # fmt: skip


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
