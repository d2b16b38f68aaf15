"""The FRI commands' shared options with --robot (pointed at a scripted controller on loopback, never a real robot):
--period is the send period the robot must have — a controller at another is refused at its first message with one
line (exit 2, nothing commanded), one at that period runs."""

from __future__ import annotations

import json

import pytest

from lbrcli.fri.testing import CA, CW, MR, MW, Cycle, ScriptedController
from lbrcli.fri.testing.relay import free_udp_port
from lbrcli.lab.pendulum_serial import PendulumEmulator
from tests.helpers.cli import Q_START, run_lbr


def _controller(send_period_ms: int, n_active: int = 0) -> ScriptedController:
    """A controller on a free loopback port at ``send_period_ms``, reaching COMMANDING_ACTIVE for ``n_active``
    messages after the monitoring ones."""
    script = [Cycle(state=MW, quality=1, send_period=send_period_ms)] * 40
    if n_active:
        script += [Cycle(state=MR, send_period=send_period_ms)] * 3 + [Cycle(state=CW, send_period=send_period_ms)] * 4
        script += [Cycle(state=CA, send_period=send_period_ms)] * n_active
    return ScriptedController(free_udp_port(), script, tuple(Q_START.tolist()), wait_for_client=30,
                              pace_s=send_period_ms * 1e-3).start()  # fmt: skip  # a robot keeps its period


def _run(ctl: ScriptedController, *args: str):
    try:
        return run_lbr(*args, "--robot", "127.0.0.1", "--port", str(ctl.client_port), "--wait", "10", "--json")
    finally:
        ctl.client_done.set()
        ctl.join()


@pytest.mark.heavy
@pytest.mark.parametrize(
    "command",
    [
        ("monitor", "--duration", "1"),
        ("ptp", ",".join(map(str, Q_START + 0.01)), "--time", "1"),
        ("serve", "--duration", "1", "--listen", "127.0.0.1:0"),
        ("control", "upright", "--pendulum", "PTY"),
    ],
    ids=["monitor", "ptp", "serve", "control upright"],
)
def test_a_robot_at_another_send_period_is_refused_at_its_first_message(command):
    emulator = PendulumEmulator(rate_hz=100) if "PTY" in command else None  # the pendulum module on a pty
    ctl = _controller(send_period_ms=2)
    try:
        res = _run(ctl, *[emulator.path if a == "PTY" else a for a in command], "--period", "4")
    finally:
        if emulator is not None:
            emulator.close()
    errors = [line for line in res.stderr.splitlines() if line.startswith("lbr: ")]
    assert res.returncode == 2, res.stderr
    assert len(errors) == 1 and "2 ms" in errors[0] and "4 ms" in errors[0] and "Traceback" not in res.stderr, errors
    assert not [r for r in ctl.replies if r.state == CA]  # nothing was commanded


def test_a_robot_at_the_send_period_asked_runs_at_it():
    ctl = _controller(send_period_ms=2)
    res = _run(ctl, "monitor", "--duration", "0.05", "--period", "2")
    assert res.returncode == 0, res.stderr
    figures = json.loads(res.stdout)
    assert figures["period_s"] == pytest.approx(0.002) and figures["robot"] == "127.0.0.1"
