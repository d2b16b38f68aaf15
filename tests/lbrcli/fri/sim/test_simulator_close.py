"""However the simulator stops (timeout, stop(), Ctrl-C, SIGTERM, its parent gone), its last messages carry IDLE:
KUKA's example clients block in recv and leave only on IDLE. Raw sockets and lbrcli.fri.codec only."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys

import pytest

from lbrcli.fri.codec import FriCodec
from lbrcli.fri.constants import SessionState
from lbrcli.fri.sim import SimConfig, Simulator, SimulatorProcess

from tests.helpers.scripted_client import ScriptedClient

MW, CA, IDLE = int(SessionState.MONITORING_WAIT), int(SessionState.COMMANDING_ACTIVE), int(SessionState.IDLE)
LENIENT = dict(commanding_after_s=0.05, quality_window=25, quality_good=0.5, quality_fair=0.3, quality_excellent=0.9)


def _silent() -> socket.socket:
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 22)  # keep every datagram of the run
    return sock


def _states(sock: socket.socket, version: str = "1.15", quiet_s: float = 1.0, first_s: float = 30.0) -> list[int]:
    """Session states of every datagram until ``quiet_s`` [s] without one."""
    codec, states = FriCodec(version), []
    sock.settimeout(first_s)
    try:
        while True:
            data, _ = sock.recvfrom(2048)
            states.append(codec.decode_monitoring(data).connectionInfo.sessionState)
            sock.settimeout(quiet_s)
    except socket.timeout:
        return states


def _closed_with_idle(states: list[int], n: int = 3) -> None:
    assert states and states[-n:] == [IDLE] * n and IDLE not in states[:-n]


@pytest.mark.heavy
@pytest.mark.parametrize("version", ["1.15", "2.7"])
def test_timeout_closes_the_session_with_idle(version):
    sock = _silent()
    try:
        with SimulatorProcess(
            SimConfig(client_port=sock.getsockname()[1], version=version, period_ms=4, max_runtime_s=0.3)
        ) as sim:
            stats = sim.wait(20.0)
        states = _states(sock, version)
    finally:
        sock.close()
    assert stats is not None and stats.end_reason == "max_runtime" and stats.states_seen == (MW, IDLE)
    _closed_with_idle(states)


@pytest.mark.heavy
def test_timeout_while_commanding_closes_the_session_and_a_kuka_like_client_leaves():
    client = ScriptedClient()
    config = SimConfig(client_port=client.port, period_ms=4, max_runtime_s=0.8, **LENIENT)
    try:
        with SimulatorProcess(config) as sim:
            run = client.run(timeout=20.0)  # answers until IDLE, like KUKA's clients
            stats = sim.wait(10.0)
    finally:
        client.close()
    assert stats is not None and stats.end_reason == "max_runtime"
    assert CA in run.states and run.states[-1] == IDLE and stats.states_seen[-1] == IDLE


@pytest.mark.heavy
def test_stop_closes_the_session_with_idle():
    sock = _silent()
    try:
        with SimulatorProcess(SimConfig(client_port=sock.getsockname()[1], period_ms=2)) as sim:
            assert sim.wait(0.3) is None
            stats = sim.stop()
        states = _states(sock)
    finally:
        sock.close()
    assert stats.end_reason == "stopped" and stats.states_seen == (MW, IDLE)
    _closed_with_idle(states)


@pytest.mark.heavy
def test_keyboard_interrupt_closes_the_session_then_is_raised():
    sock = _silent()
    calls = [0]

    def stop() -> bool:
        calls[0] += 1
        if calls[0] == 40:
            raise KeyboardInterrupt
        return False

    try:
        sim = Simulator(SimConfig(client_port=sock.getsockname()[1], period_ms=2), stop=stop)
        with pytest.raises(KeyboardInterrupt):
            sim.run()
        states = _states(sock, quiet_s=0.3)
    finally:
        sock.close()
    _closed_with_idle(states)
    assert calls[0] == 40  # no further stop() calls while closing


@pytest.mark.heavy
def test_lbr_sim_sigterm_closes_the_session_and_reports():
    sock = _silent()
    try:
        client = f"127.0.0.1:{sock.getsockname()[1]}"
        proc = subprocess.Popen(
            [sys.executable, "-m", "lbrcli", "sim", "--client", client, "--period", "5", "--json", "--timeout", "60"],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        sock.settimeout(60.0)
        sock.recvfrom(2048)  # it runs
        proc.send_signal(signal.SIGTERM)
        states = _states(sock)
        out, err = proc.communicate(timeout=30)
    finally:
        sock.close()
    assert proc.returncode == 0, err
    assert json.loads(out)["end_reason"] == "stopped"
    _closed_with_idle(states)


@pytest.mark.heavy
def test_parent_exit_closes_the_session_with_idle():
    """The simulator process notices its parent is gone (checked every 512 cycles) and closes the session."""
    sock = _silent()
    code = (
        "import os, sys; from lbrcli.fri.sim import SimConfig, SimulatorProcess; "
        f"SimulatorProcess(SimConfig(client_port={sock.getsockname()[1]}, period_ms=1)).start(); os._exit(0)"
    )
    try:
        parent = subprocess.run(
            [sys.executable, "-c", code],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            timeout=60,
            env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)},
        )
        assert parent.returncode == 0  # (no pipes: the simulator process would hold them open)
        states = _states(sock, quiet_s=2.0, first_s=10.0)
    finally:
        sock.close()
    _closed_with_idle(states)
