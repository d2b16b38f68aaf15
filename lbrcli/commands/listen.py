"""`lbr listen`: a remote operator's view of a session's MQTT telemetry."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

from ..options import JsonOpt, number


def listen(
    url: Annotated[str, typer.Argument(help="mqtt://HOST:PORT/TOPIC published by `lbr execute/monitor --mqtt`.")],
    duration: Annotated[
        Optional[float],
        number("--duration", low=0, high=1e7, low_open=True, unit="s", help="Stop after this many seconds \\[s]."),
    ] = None,
    count: Annotated[
        Optional[int], number("--count", low=1, high=10**12, integer=True, help="Stop after this many messages.")
    ] = None,
    out: Annotated[Optional[Path], typer.Option("-o", "--out", help="Record every message as one JSON line.")] = None,
    quiet: Annotated[bool, typer.Option("--quiet", help="Do not print each message.")] = False,
    connect_timeout: Annotated[
        float,
        number(
            "--connect-timeout",
            low=0,
            high=600,
            low_open=True,
            unit="s",
            help="Exit 1 when the broker is not reached within this time \\[s].",
        ),
    ] = 5.0,
    json_out: JsonOpt = False,
) -> None:
    """Print (and record) the JSON state messages a session publishes; Ctrl-C to stop (exit 130, recording kept).

    Exit 1 when the broker cannot be reached, nothing arrives, or fewer than --count messages arrive within
    --duration. The recording appears under its name when the command ends (never half-written).
    """
    import contextlib
    import json
    import threading
    import time

    from lbrcli.lab.telemetry import TelemetryListener, parse_mqtt_url
    from trajectories.errors import CheckFailed

    from ..console import Reporter
    from ..outputs import atomic_open

    rep = Reporter(json_out)
    target = parse_mqtt_url(url, "URL")
    done = threading.Event()
    n = 0
    interrupted = False
    with contextlib.ExitStack() as stack:
        sink = stack.enter_context(atomic_open(out, "w")) if out is not None else None

        def on_message(data: dict) -> None:
            nonlocal n
            n += 1
            if sink is not None:
                sink.write(json.dumps(data) + "\n")
            if not quiet:
                state = data.get("state", "")
                q = data.get("msr_q")
                qtext = " ".join(f"{x:+.3f}" for x in q) if isinstance(q, list) else ""
                extra = "".join(
                    f" {k}={data[k]:+.3f}"
                    for k in ("ball_theta", "pend_theta")
                    if isinstance(data.get(k), (int, float))
                )
                rep.print(f"t={data.get('t', float('nan')):8.3f} {state:<18} q=[{qtext}]{extra}")
            if count is not None and n >= count:
                done.set()

        listener = TelemetryListener(target, on_message).start()
        t0 = time.monotonic()
        try:
            while not done.wait(0.1):
                elapsed = time.monotonic() - t0
                if not listener.connected.is_set() and elapsed >= connect_timeout:
                    break
                if duration is not None and elapsed >= duration:
                    break
        except KeyboardInterrupt:
            interrupted = True
        finally:
            listener.stop()  # no more callbacks: the recording can be closed and renamed
        elapsed = time.monotonic() - t0
        connected = listener.connected.is_set()
        rep.print(
            f"received {listener.received} messages ({listener.malformed} malformed) from {url} in {elapsed:.1f} s"
        )
        failure = None
        if not connected:
            failure = f"could not reach the MQTT broker {target.host}:{target.port} within {connect_timeout:g} s"
        elif interrupted:
            pass
        elif listener.received == 0:
            failure = f"nothing received on '{target.topic}' from {target.host}:{target.port} in {elapsed:.1f} s"
        elif count is not None and listener.received < count:
            failure = f"received {listener.received} of {count} messages in {elapsed:.1f} s"
        rep.emit(
            {
                "received": listener.received,
                "malformed": listener.malformed,
                "connected": connected,
                "seconds": elapsed,
                "ok": failure is None and not interrupted,
                "failure": failure,
            }
        )
        if failure and n == 0:
            raise CheckFailed(failure + ("; nothing recorded" if out is not None else ""))  # no empty recording
    if failure:
        raise CheckFailed(failure)
    if interrupted:
        raise typer.Exit(130)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("listen")(listen)
