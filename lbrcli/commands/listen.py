"""`lbr listen`: a remote operator's view of a session's MQTT telemetry."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

from ..options import JsonOpt


def listen(
    url: Annotated[str, typer.Argument(help="mqtt://HOST:PORT/TOPIC published by `lbr execute/monitor --mqtt`.")],
    duration: Annotated[Optional[float], typer.Option("--duration", help="Stop after this many seconds \\[s].")] = None,
    count: Annotated[Optional[int], typer.Option("--count", help="Stop after this many messages.")] = None,
    out: Annotated[Optional[Path], typer.Option("-o", "--out", help="Record every message as one JSON line.")] = None,
    quiet: Annotated[bool, typer.Option("--quiet", help="Do not print each message.")] = False,
    json_out: JsonOpt = False,
) -> None:
    """Print (and record) the JSON state messages a session publishes; Ctrl-C to stop."""
    import json
    import threading
    import time

    from lbrcli.lab.telemetry import TelemetryListener, parse_mqtt_url
    from trajectories.errors import OptionError

    from ..console import Reporter

    rep = Reporter(json_out)
    target = parse_mqtt_url(url, "URL")
    if duration is not None and duration <= 0:
        raise OptionError("--duration must be positive")
    if count is not None and count <= 0:
        raise OptionError("--count must be positive")
    done = threading.Event()
    sink = open(out, "w") if out is not None else None
    n = 0

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
                f" {k}={data[k]:+.3f}" for k in ("ball_theta", "pend_theta") if isinstance(data.get(k), (int, float))
            )
            rep.print(f"t={data.get('t', float('nan')):8.3f} {state:<18} q=[{qtext}]{extra}")
        if count is not None and n >= count:
            done.set()

    listener = TelemetryListener(target, on_message).start()
    t0 = time.monotonic()
    try:
        while not done.wait(0.1):
            if duration is not None and time.monotonic() - t0 >= duration:
                break
    except KeyboardInterrupt:
        pass
    finally:
        listener.stop()
        if sink is not None:
            sink.close()
    rep.print(f"received {listener.received} messages ({listener.malformed} malformed) from {url}")
    rep.emit({"received": listener.received, "malformed": listener.malformed, "connected": listener.connected.is_set()})


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("listen")(listen)
