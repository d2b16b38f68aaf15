"""Pendulum module over a real pseudo-terminal, telemetry through a real Mosquitto broker on loopback."""

import json
import math
import subprocess
import sys
import time

import pytest

from lbrcli.lab.pendulum_serial import PendulumEmulator, PendulumReader, format_line, parse_line
from lbrcli.lab.telemetry import MqttTarget, TelemetryListener, TelemetryPublisher, parse_mqtt_url
from trajectories.errors import OptionError
from lbrcli.fri.realtime import permitted

REALTIME = ["--realtime"] if permitted() else []  # refused with exit 2 where the system does not grant it


def test_parse_line_thesis_eq_6_1():
    theta, omega = parse_line(b"1024,0.5\n")
    assert theta == pytest.approx(math.pi / 2) and omega == 0.5
    assert parse_line("3072;-1.25")[0] == pytest.approx(-math.pi / 2)  # wrapped to (−π, π]
    assert parse_line("2048 0", zero_count=2048)[0] == 0.0
    for bad in ("", "12", "4096,0", "-1,0", "abc,1", "1,2,3", "5,nan"):
        with pytest.raises(ValueError):
            parse_line(bad)


def test_format_parse_round_trip():
    for theta in (-3.0, -0.7, 0.0, 0.01, 1.2, 3.1):
        t2, w2 = parse_line(format_line(theta, -2.5, zero_count=1000), zero_count=1000)
        assert t2 == pytest.approx(theta, abs=2 * math.pi / 4096) and w2 == -2.5


def test_reader_on_a_pty_counts_malformed_lines_and_keeps_going():
    emu = PendulumEmulator(rate_hz=1000)
    try:
        with PendulumReader(emu.path) as reader:
            emu.write_raw(b"garbage\n12\n")
            for k in range(20):
                emu.feed(k * 0.01, 0.3, -1.5)
                time.sleep(0.002)
            assert wait_for(lambda: reader.latest is not None and reader.lines >= 22)
            assert reader.malformed == 2
            assert reader.latest.theta == pytest.approx(0.3, abs=2e-3)
            assert reader.latest.omega == -1.5
    finally:
        emu.close()


def test_reader_bad_port_is_an_option_error():
    with pytest.raises(OptionError, match="cannot open serial port"):
        PendulumReader("/dev/does-not-exist").start()


def test_parse_mqtt_url():
    assert parse_mqtt_url("mqtt://localhost:1884/lbr/state") == MqttTarget("localhost", 1884, "lbr/state")
    assert parse_mqtt_url("mqtt://h/t").port == 1883
    for bad in ("http://h/t", "mqtt://h:1/", "mqtt://h:1/a/#"):
        with pytest.raises(OptionError):
            parse_mqtt_url(bad)


@pytest.mark.heavy
def test_publisher_decimates_and_listener_receives(broker):
    got = []
    listener = TelemetryListener(broker, got.append).start()
    assert listener.connected.wait(5)
    time.sleep(0.2)  # subscription acknowledged
    pub = TelemetryPublisher(broker, rate_hz=50).start()
    assert wait_for(pub._client.is_connected)
    t0 = time.monotonic()
    cycles = 0
    while time.monotonic() - t0 < 1.0:  # a 1 kHz loop offering every cycle
        t = time.monotonic() - t0
        pub.offer(t, {"state": "COMMANDING_ACTIVE", "msr_q": [0.1] * 7, "k": cycles})
        cycles += 1
        time.sleep(0.001)
    pub.stop()
    assert wait_for(lambda: len(got) >= pub.published, 3)
    listener.stop()
    assert cycles > 300
    # decimated to ≈ 50 Hz, not one message per cycle
    assert 35 <= len(got) <= 55
    assert got[0]["state"] == "COMMANDING_ACTIVE" and got[0]["msr_q"] == [0.1] * 7
    ts = [m["t"] for m in got]
    assert all(b - a >= 0.019 for a, b in zip(ts, ts[1:]))


@pytest.mark.heavy
def test_publisher_reconnects_after_broker_restart(broker_process, broker):
    pub = TelemetryPublisher(broker, rate_hz=100).start()
    assert wait_for(pub._client.is_connected)
    t0 = time.monotonic()

    def offer_for(seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            pub.offer(time.monotonic() - t0, {"x": 1})  # never blocks, connected or not
            time.sleep(0.002)

    offer_for(0.2)
    broker_process.restart()  # the connection is gone; a fresh broker comes up on the same port
    t_restart = time.monotonic() - t0
    got = []
    listener = TelemetryListener(broker, got.append).start()
    assert listener.connected.wait(5)
    time.sleep(0.2)
    offer_for(0.2)
    # paho reconnects by itself (1–5 s back-off); the same publisher object delivers again
    deadline = time.monotonic() + 10
    while not got and time.monotonic() < deadline:
        offer_for(0.1)
    pub.stop()
    listener.stop()
    assert got, "the publisher did not reconnect after the broker restarted"
    assert all(m["t"] > t_restart for m in got)
    assert pub.dropped > 0  # what was offered while disconnected was dropped, not queued into the FRI loop


@pytest.mark.heavy
def test_listen_cli_records(broker, tmp_path, lbr):
    url = f"mqtt://{broker.host}:{broker.port}/{broker.topic}"
    out = tmp_path / "rec.jsonl"
    proc = subprocess.Popen(
        [sys.executable, "-m", "lbrcli", "listen", url, "--count", "5", "-o", str(out), "--json"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    time.sleep(1.5)  # let it subscribe
    pub = TelemetryPublisher(broker, rate_hz=100).start()
    assert wait_for(pub._client.is_connected)
    t0 = time.monotonic()
    while proc.poll() is None and time.monotonic() - t0 < 10:
        pub.offer(time.monotonic() - t0, {"state": "MONITORING_READY", "msr_q": [0.0] * 7})
        time.sleep(0.005)
    pub.stop()
    stdout, stderr = proc.communicate(timeout=10)
    assert proc.returncode == 0, stderr
    assert json.loads(stdout)["received"] >= 5
    lines = out.read_text().splitlines()
    assert len(lines) >= 5 and json.loads(lines[0])["state"] == "MONITORING_READY"


def test_listen_bad_url_exit_2(lbr):
    res = lbr("listen", "http://nowhere/x")
    assert res.returncode == 2 and "expected mqtt://" in res.stderr and "Traceback" not in res.stderr


# -- attached to a real FRI session on the simulator -----------------------------------------------------------
import numpy as np

from tests.helpers.cli import Q_START
from tests.helpers.broker import wait_for


def _move_csv(path, h=0.005, seconds=1.5):
    from trajectories.csvio import write_joint_csv
    from trajectories.trajectory import JointTrajectory

    t = np.arange(0, seconds + h / 2, h)
    s = 0.5 - 0.5 * np.cos(np.pi * t / seconds)
    write_joint_csv(path, JointTrajectory(t=t, q=Q_START + np.outer(s, [0.3, 0, 0, 0, 0, 0, 0])))
    return path


def _log(path):
    from lbrcli.fri.log import LOG_COLUMNS, NAN_COLUMNS
    from trajectories.csvio import read_table

    return read_table(path, LOG_COLUMNS, time="increasing", nan_columns=NAN_COLUMNS)


@pytest.mark.heavy
def test_execute_reads_the_emulated_pendulum_module_over_a_pty(tmp_path, lbr):
    csv = _move_csv(tmp_path / "move.csv")
    log = tmp_path / "log.csv"
    # a process of its own: --realtime changes the scheduling of the process it runs in (as a user's `lbr` would)
    res = lbr("execute", csv, "--port", "0", *REALTIME, "--pendulum", "sim", "--log", log, "--json", process=True)
    assert res.returncode == 0, res.stderr
    figures = json.loads(res.stdout)
    assert figures["pendulum_lines"] > 100 and figures["pendulum_malformed"] == 0
    table = _log(log)
    pend, ball = table.column("pend_theta"), table.column("ball_theta_y")
    ok = np.isfinite(pend)
    assert ok.mean() > 0.9
    assert np.abs(ball).max() > np.radians(1.0)  # the ball really swung
    # the reading is the ball's angle when it was read (pend_age before the row; the module's radio latency is part of
    # it): within one encoder count (0.088°) and the swing of the few ms between the encoder's sample and its line —
    # judged at the reading's own time, since a loaded PC reads the pty late now and then
    t, age = table.column("t"), table.column("pend_age")
    read = ok & (age >= 0)  # (age −1: no reading yet)
    at_reading = np.interp(t[read] - age[read], t, ball)
    assert np.degrees(np.abs(pend[read] - at_reading).max()) < 0.5
    assert read.mean() > 0.9 and np.median(age[read]) < 0.05  # fresh readings (the module sends at 200 Hz)
    assert figures["start_sway_deg"] is not None and figures["start_sway_deg"] < 0.2  # judged from the module


def test_the_pendulum_module_is_the_sway_source_while_its_reading_is_fresh():
    import time
    from types import SimpleNamespace

    from lbrcli.lab.attach import LabAttachments, LabOptions

    attached = LabAttachments(LabOptions(), None)
    assert attached.pendulum_sway(None) is None  # no module
    attached.pendulum = SimpleNamespace(latest=None)
    assert attached.pendulum_sway(None) is None  # no reading yet
    attached.pendulum.latest = SimpleNamespace(theta=-0.12, host_time=time.monotonic())
    assert attached.pendulum_sway(None) == -0.12
    attached.pendulum.latest = SimpleNamespace(theta=-0.12, host_time=time.monotonic() - 0.5)
    assert attached.pendulum_sway(None) is None  # half a second old: not the swing now


@pytest.mark.heavy
def test_execute_publishes_telemetry_to_a_real_broker(broker, tmp_path):
    csv = _move_csv(tmp_path / "move.csv")
    got = []
    listener = TelemetryListener(broker, got.append).start()
    assert listener.connected.wait(5)
    time.sleep(0.2)
    url = f"mqtt://{broker.host}:{broker.port}/{broker.topic}"
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "lbrcli",
            "execute",
            str(csv),
            "--port",
            "0",
            *REALTIME,
            "--mqtt",
            url,
            "--mqtt-rate",
            "20",
            "--pendulum",
            "sim",
            "--json",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert res.returncode == 0, res.stderr
    figures = json.loads(res.stdout)
    assert wait_for(lambda: len(got) >= figures["mqtt_published"], 3)
    listener.stop()
    assert figures["mqtt_published"] >= 20
    states = {m["state"] for m in got}
    assert "COMMANDING_ACTIVE" in states
    active = [m for m in got if m["state"] == "COMMANDING_ACTIVE"]
    assert len(active[0]["msr_q"]) == 7 and "ball_theta" in active[0] and "pend_theta" in got[-1]
    ts = [m["t"] for m in got]
    assert all(b - a >= 0.049 for a, b in zip(ts, ts[1:]))  # decimated to 20 Hz
    # the robot moved: A1 went from the start toward +0.3 rad
    assert max(m["msr_q"][0] for m in got) > 0.2


@pytest.mark.heavy
def test_lab_options_refused_with_one_line(tmp_path, lbr):
    csv = _move_csv(tmp_path / "move.csv")
    res = lbr("execute", csv, "--port", "0", "--pendulum", "/dev/does-not-exist")
    assert res.returncode == 2 and "cannot open serial port" in res.stderr and "Traceback" not in res.stderr
    res = lbr("execute", csv, "--robot", "127.0.0.1", "--port", "0", "--pendulum", "sim")
    assert res.returncode == 2 and "--pendulum: 'sim'" in res.stderr and "not with a robot" in res.stderr
    res = lbr("monitor", "--duration", "0.5", "--mqtt", "http://x/y")
    assert res.returncode == 2 and "expected mqtt://" in res.stderr


@pytest.mark.heavy
def test_monitor_logs_the_pendulum(tmp_path, lbr):
    log = tmp_path / "mon.csv"
    res = lbr(
        "monitor",
        "--duration",
        "1",
        "--port",
        "0",
        *REALTIME,
        "--sim-lenient",
        "--pendulum",
        "sim",
        "--length",
        "0.25",
        "--log",
        log,
        "--json",
        process=True,
    )
    assert res.returncode == 0, res.stderr
    table = _log(log)
    assert table.has("pend_theta") and table.has("flange_x")
    pend = table.column("pend_theta")
    # the robot stands still: the module reads the hanging pendulum (0 within one count)
    assert np.isfinite(pend).sum() > 50 and np.nanmax(np.abs(pend)) < 2e-3


@pytest.mark.heavy
def test_telemetry_that_reaches_no_broker_is_a_failure(lbr):
    """The session ran, but what was asked (telemetry) did not happen: exit 1, one line."""
    res = lbr("monitor", "--duration", "0.5", "--port", "0", "--sim-lenient", "--mqtt", "mqtt://127.0.0.1:1/lbr/state")
    assert res.returncode == 1 and "Traceback" not in res.stderr
    assert res.stderr.strip().splitlines()[-1].startswith("lbr: failed: telemetry: nothing was published")


def test_in_lock_step_a_module_line_is_readable_when_its_cycle_ends():
    """settle_s (a simulator in lock-step): send returns once the reader's side holds the line, so the client's
    poll in the same cycle reads it however late the kernel hands pty bytes over on a busy machine."""
    from lbrcli.lab.pendulum_serial import COUNTS_PER_TURN, PendulumEmulator, PendulumReader, format_line

    emu = PendulumEmulator(rate_hz=200.0)
    emu.settle_s = 0.5
    reader = PendulumReader(emu.path, threaded=False).start()
    try:
        for k in range(1, 60):
            assert emu.send(format_line(0.01 * k, 0.0))  # this cycle's line
            reading = reader.latest  # the client's poll in the same cycle
            assert reading is not None and abs(reading.theta - 0.01 * k) <= math.pi / COUNTS_PER_TURN + 1e-12, k
    finally:
        reader.stop()
        emu.close()
