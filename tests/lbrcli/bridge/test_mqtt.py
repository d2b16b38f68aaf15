"""`lbr serve --mqtt` against a real Mosquitto broker with user accounts: a 30 Hz teleoperation source of TCP poses
followed smoothly, the state published back, unsigned messages ignored, source loss braking within the limits, the
end message, a refused log-in."""

from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from tests.helpers.cli import run_lbr
from tests.helpers.bridge import PERIOD_S, judge_following
from tests.helpers.cli import Q_START
from tests.helpers.broker import Broker, free_tcp_port

from lbrcli.bridge import MqttBridgeClient
from lbrcli.fri.log import LOG_COLUMNS, PHASE_BRAKE
from trajectories.csvio import read_table
from trajectories.robot import Robot

SECRET = b"a-shared-secret-for-the-bridge-test"
USERS = {"lbr": "robot-pw", "op": "operator-pw"}


@pytest.fixture
def broker(tmp_path):
    exe = shutil.which("mosquitto") or ("/usr/sbin/mosquitto" if Path("/usr/sbin/mosquitto").exists() else None)
    if exe is None:
        pytest.skip("mosquitto broker binary not installed (apt-get install mosquitto)")
    conf = tmp_path / "broker"
    conf.mkdir()
    b = Broker(exe, conf, free_tcp_port(), users=USERS)
    yield b
    b.stop()


def _serve(tmp_path, url: str, *extra: str) -> subprocess.Popen:
    (tmp_path / "secret").write_bytes(SECRET + b"\n")
    return subprocess.Popen(
        [sys.executable, "-m", "lbrcli", "serve", "--listen", "off", "--mqtt", url, "--secret", str(tmp_path / "secret"),
         "--port", "0", "--period", str(round(PERIOD_S * 1e3)), "--sim-lenient", "--log", str(tmp_path / "serve.csv"),
         "--json", *extra],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip


def _wait_for_session(proc, client: MqttBridgeClient, timeout: float = 30.0) -> None:
    """Until the bridge publishes states (it does once a source owns the session: send holding targets)."""
    t0 = time.monotonic()
    while not client.states and time.monotonic() - t0 < timeout and proc.poll() is None:
        time.sleep(0.05)


@pytest.mark.heavy
def test_a_30hz_teleoperation_source_over_mosquitto_is_followed_smoothly_and_its_loss_brakes(tmp_path, broker):
    url = f"mqtt://lbr:robot-pw@127.0.0.1:{broker.port}/lab/iiwa/cmd"
    start = np.array([0.0, 0.5, 0.0, -1.2, 0.0, 0.8, 0.0])  # a teleoperation posture, away from the wrist singularity
    proc = _serve(tmp_path, url, "--timeout", "0.2", "--mqtt-state-hz", "50", "--speed-scale", "0.5",
                  "--sim-start", ",".join(map(str, start)))  # fmt: skip
    op = MqttBridgeClient(f"mqtt://op:operator-pw@127.0.0.1:{broker.port}/lab/iiwa/cmd", source_id=7, secret=SECRET)
    stranger = MqttBridgeClient(f"mqtt://op:operator-pw@127.0.0.1:{broker.port}/lab/iiwa/cmd", source_id=7)
    robot = Robot()
    home = robot.fk(start)
    zyx = home.rotation  # keep the orientation: fixed angles of the start
    gamma, beta, alpha = (math.atan2(zyx[2, 1], zyx[2, 2]), -math.asin(zyx[2, 0]), math.atan2(zyx[1, 0], zyx[0, 0]))
    rng = np.random.default_rng(3)
    sent = []
    try:
        t_hold = time.monotonic()  # simulator and bridge starting (seconds on a loaded machine): hold the start
        while not op.states and time.monotonic() < t_hold + 60:  # pose until the state comes back, so that the
            op.send_pose_zyx(home.translation, (alpha, beta, gamma), t=time.monotonic() - t_hold)  # whole circle
            time.sleep(1 / 30)  # reaches a session
        t0 = time.monotonic()
        k = 0
        while time.monotonic() - t0 < 4.0:
            t = time.monotonic() - t0
            phi = 2 * math.pi * 0.25 * t
            p = home.translation + 0.06 * np.array([math.cos(phi) - 1, math.sin(phi), 0.0])  # a 6 cm circle
            op.send_pose_zyx(p, (alpha, beta, gamma), t=t0 - t_hold + t)
            sent.append((t, p))
            if k % 3 == 0:  # unsigned, with a far target: must be ignored
                stranger.send_joint(Q_START + 0.4)
            k += 1
            time.sleep(max(0.0, 1 / 30 + rng.uniform(-0.01, 0.01)))  # 30 Hz with jitter
        out, err = proc.communicate(timeout=60)  # then silence: the dead-man
    finally:
        proc.kill()
        op.close()
        stranger.close()
    assert proc.returncode == 1 and "dead-man" in err, err
    f = json.loads(out)
    assert f["targets_unauthenticated"] >= 0.8 * len(sent) / 3 and f["targets_bad"] == 0
    assert f["targets_accepted"] >= 0.9 * len(sent) and f["poses_unreached"] == 0
    tab = read_table(tmp_path / "serve.csv", LOG_COLUMNS, time="increasing")
    judge_following(tab, f)  # a smooth stream from a 30 Hz source; the braking stop: the full limits at most
    assert f["braking_cycles"] >= 1 and np.sum(tab.column("phase") == PHASE_BRAKE) == f["braking_cycles"]
    # the TCP followed the circle (behind by the 30 Hz steps and ruckig's lag), and never went toward the stranger
    following = (tab.column("state") == 4) & (np.cumsum(tab.column("phase") == PHASE_BRAKE) == 0)
    cmd = np.column_stack([tab.column(f"cmd_q{k}") for k in range(1, 8)])[following]
    tcp, _ = robot.fk_path(cmd[::20])
    circle = np.array([p for _, p in sent])
    dist = np.linalg.norm(tcp[:, None, :] - circle[None, :, :], axis=2).min(axis=1)
    # within 5 cm of the drawn path (median 6 mm) (≈ 2 mm on a quiet machine; a loaded one delivers the targets in bursts; the
    # accuracy is judged in lock step, test_bridge_timeline.py), round (the circle spans 0.12 m in y; ruckig's lag at
    # --speed-scale 0.5 and late bursts cut its extremes by up to 2 cm under load)
    assert dist.max() < 0.05 and np.median(dist) < 0.006 and np.ptp(tcp[:, 1]) > 0.08, (
        dist.max(),
        np.median(dist),
        np.ptp(tcp[:, 1]),
    )
    assert np.abs(cmd - (Q_START + 0.4)).max(axis=1).min() > 0.2  # never near the stranger's configuration
    # the state came back on lab/iiwa/cmd/state at ≈ 50 Hz with the commanded TCP
    states = list(op.states)
    assert 0.5 * 50 * 4 < len(states) < 1.5 * 50 * 6
    s = states[len(states) // 2]
    assert s.following and np.linalg.norm(np.array(s.tcp[:3]) - robot.fk(np.array(s.commanded)).translation) < 1e-9


@pytest.mark.heavy
def test_the_end_message_over_mqtt_ends_the_session_and_a_refused_log_in_is_an_option_error(tmp_path, broker):
    url = f"mqtt://lbr:robot-pw@127.0.0.1:{broker.port}/lbr/cmd"
    proc = _serve(tmp_path, url)
    op = MqttBridgeClient(url, source_id=1, secret=SECRET)
    try:
        time.sleep(1.5)
        for _ in range(100):
            op.send_joint(Q_START)
            time.sleep(0.01)
        op.end()
        out, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
        op.close()
    assert proc.returncode == 0, err
    assert json.loads(out)["reason"] == "finished"
    bad = run_lbr(
        "serve", "--listen", "off", "--port", "0", "--mqtt", f"mqtt://lbr:wrong@127.0.0.1:{broker.port}/lbr/cmd"
    )
    assert bad.returncode == 2 and "--mqtt" in bad.stderr and "refused" in bad.stderr
    assert len(bad.stderr.strip().splitlines()) == 1
