"""Plants for the simulator (lbrcli.plants): specs, the ball as a stand-alone plant, the pendulum module on a pty."""

from __future__ import annotations

import pickle
import socket
import time

import numpy as np
import pytest

from lbrcli.fri.sim import Plant, PlantContext, SimConfig, SimulatorProcess
from lbrcli.plants import BALL_IO_NAMES, BallSpec, PendulumModuleSpec, default_plants
from trajectories.errors import OptionError
from tests.helpers.cli import Q_START


def test_default_plants_and_validation():
    assert default_plants(None) == () and default_plants(0.0) == ()
    assert default_plants(0.3, 0.1) == (BallSpec(0.3, 0.1),)
    assert default_plants(0.3, pendulum_pty=True, pendulum_rate_hz=100.0) == (BallSpec(0.3), PendulumModuleSpec(100.0))
    with pytest.raises(OptionError, match="needs a simulated ball"):
        default_plants(None, pendulum_pty=True)
    with pytest.raises(OptionError, match="BallSpec.length"):  # the field: the command names its option
        default_plants(-0.2)
    with pytest.raises(OptionError, match="rate"):
        default_plants(0.3, pendulum_pty=True, pendulum_rate_hz=0.0)
    with pytest.raises(OptionError, match="BallSpec.damping"):  # refused when it is made
        BallSpec(0.3, -1.0)
    specs = default_plants(0.3, pendulum_pty=True)
    assert pickle.loads(pickle.dumps(specs)) == specs  # they cross into the simulator process


def test_ball_plant_on_a_horizontal_tcp_acceleration_swings_backwards(robot):
    """Built stand-alone: a TCP accelerating along +x tilts the string towards −x (θx < 0), and θ grows."""
    q0 = tuple(Q_START.tolist())
    h = 0.002
    ball = BallSpec(0.5).build(PlantContext(h, robot, q0))
    assert isinstance(ball, Plant) and tuple(ball.inputs) == BALL_IO_NAMES
    p0 = robot.fk(np.array(q0)).translation
    out = [list(ball.step(k * h, p0 + np.array([0.5 * 2.0 * (k * h) ** 2, 0.0, 0.0]))) for k in range(1, 60)]
    theta, _, theta_x, theta_y = np.array(out).T[:4]
    assert theta_x[-1] < -0.01 and abs(theta_y[-1]) < 1e-12 and theta[-1] == pytest.approx(-theta_x[-1])
    assert ball.figures()["max_ball_theta"] == pytest.approx(theta.max())


@pytest.mark.heavy
def test_pendulum_module_plant_writes_lines_on_its_pty():
    import os

    silent = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    silent.bind(("127.0.0.1", 0))
    cfg = SimConfig(client_port=silent.getsockname()[1], period_ms=2, plants=default_plants(0.4, pendulum_pty=True))
    try:
        with SimulatorProcess(cfg) as sim:
            path = sim.pendulum_path
            assert path is not None and path.startswith("/dev/")
            fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
            data = b""
            end = time.monotonic() + 5.0
            while data.count(b"\n") < 3 and time.monotonic() < end:
                try:
                    data += os.read(fd, 4096)
                except BlockingIOError:
                    time.sleep(0.02)
            os.close(fd)
            stats = sim.stop()
    finally:
        silent.close()
    lines = data.split(b"\n")[1:-1]  # whole lines only
    assert lines and all(line.startswith(b"0,") for line in lines)  # the ball hangs still: θy = 0 counts
    assert stats.plants["pendulum_module"]["lines_sent"] >= 3 and stats.max_ball_theta == 0.0
