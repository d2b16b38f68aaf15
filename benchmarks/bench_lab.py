"""FRI reply latency at 1 ms with the pendulum module (serial) and MQTT telemetry on, against the same run without.

The client is `lbr execute --robot 127.0.0.1` paced by a controller in this process (see bench_fri.py); the
pendulum module is emulated on a pseudo-terminal fed at 200 lines/s by a thread here, telemetry goes at 50 Hz to a
Mosquitto broker started on loopback. Goal (issue 8): p50/p99 within 10 % of the run without them.
"""

from __future__ import annotations

import importlib.util
import math
import shutil
import socket
import subprocess
import tempfile
import threading
import time
from pathlib import Path


def _bench_fri():
    spec = importlib.util.spec_from_file_location("bench_fri", Path(__file__).with_name("bench_fri.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    return module


def _broker(tmp: Path):
    exe = shutil.which("mosquitto") or ("/usr/sbin/mosquitto" if Path("/usr/sbin/mosquitto").exists() else None)
    if exe is None:
        return None, None
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    conf = tmp / "mosquitto.conf"
    conf.write_text(f"listener {port} 127.0.0.1\nallow_anonymous true\npersistence false\n")
    proc = subprocess.Popen([exe, "-c", str(conf)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(0.5)
    return proc, port


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    from lbrcli.lab.pendulum_serial import PendulumEmulator

    fri = _bench_fri()
    duration = 5.0 if quick else 30.0
    rows: list[tuple[str, float, str]] = []
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        broker, port = _broker(tmp)
        emu = PendulumEmulator(rate_hz=200)
        stop = threading.Event()

        def feed() -> None:
            t0 = time.monotonic()
            while not stop.is_set():
                t = time.monotonic() - t0
                emu.feed(t, 0.3 * math.sin(2 * math.pi * t), 0.6 * math.pi * math.cos(2 * math.pi * t))
                time.sleep(0.001)

        feeder = threading.Thread(target=feed, daemon=True)
        feeder.start()
        lab = ("--pendulum", emu.path) + (("--mqtt", f"mqtt://127.0.0.1:{port}/lbr/bench") if broker else ())
        label = "serial + MQTT" if broker else "serial (no mosquitto: MQTT not measured)"
        try:
            off = fri._measure(1, duration, tmp, tag="1 ms, plain")
            on = fri._measure(1, duration, tmp, extra_args=lab, tag=f"1 ms, {label}")
        finally:
            stop.set()
            feeder.join(1)
            emu.close()
            if broker:
                broker.terminate()
                broker.wait(5)
    rows += off + on
    get = {name: value for name, value, _ in off + on}
    for q in ("p50", "p99"):
        a = get[f"1 ms, plain: reply latency {q} (controller side)"]
        b = get[f"1 ms, {label}: reply latency {q} (controller side)"]
        rows.append((f"reply latency {q} with {label} / without", b / a, "ratio"))
    return rows
