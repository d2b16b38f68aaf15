"""A real Mosquitto broker on a loopback port for the MQTT tests (fixtures ``broker_process`` and ``broker``; they
skip when the mosquitto binary is not installed)."""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import time
import pytest
from lbrcli.lab.telemetry import MqttTarget


def wait_for(predicate, timeout=5.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.01)
    return False


def free_tcp_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Broker:
    """A real Mosquitto broker on a loopback port; ``restart()`` brings a fresh one up on the same port."""

    def __init__(self, exe: str, conf_dir, port: int, users: dict[str, str] | None = None) -> None:
        self.exe, self.port = exe, port
        self.conf = conf_dir / "mosquitto.conf"
        auth = "allow_anonymous true\n"
        if users:  # only these users may connect (mosquitto_passwd hashes the passwords)
            pw = conf_dir / "passwd"
            pw.write_text("".join(f"{u}:{p}\n" for u, p in users.items()))
            pw.chmod(0o600)
            subprocess.run([shutil.which("mosquitto_passwd") or "/usr/bin/mosquitto_passwd", "-U", str(pw)], check=True)
            auth = f"allow_anonymous false\npassword_file {pw}\n"
            if os.geteuid() == 0:  # as root mosquitto drops to its own user, which cannot read the test's files
                auth += "user root\n"
        self.conf.write_text(f"listener {port} 127.0.0.1\n{auth}persistence false\n")
        self.proc = None
        self.start()

    def up(self) -> bool:
        try:
            socket.create_connection(("127.0.0.1", self.port), timeout=0.2).close()
            return True
        except OSError:
            return False

    def start(self) -> None:
        self.proc = subprocess.Popen(
            [self.exe, "-c", str(self.conf)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
        )
        assert wait_for(self.up), "broker did not start"

    def stop(self) -> None:
        self.proc.terminate()
        self.proc.wait(5)

    def restart(self) -> None:
        self.stop()
        assert wait_for(lambda: not self.up(), 3)
        self.start()


@pytest.fixture
def broker_process(tmp_path):
    exe = shutil.which("mosquitto") or ("/usr/sbin/mosquitto" if shutil.os.path.exists("/usr/sbin/mosquitto") else None)
    if exe is None:
        pytest.skip("mosquitto broker binary not installed (apt-get install mosquitto)")
    b = Broker(exe, tmp_path, free_tcp_port())
    yield b
    b.stop()


@pytest.fixture
def broker(broker_process):
    return MqttTarget("127.0.0.1", broker_process.port, "lbr/test/state")
