"""Shared fixtures: the thesis start pose, a robot, the default limits, CLI runner (helpers: tests/helpers)."""

from __future__ import annotations

import signal

import numpy as np
import pytest

from tests.helpers.broker import broker, broker_process  # noqa: F401  (fixtures: a real Mosquitto broker on loopback)
from tests.helpers.cli import Q_START, run_lbr

# A suite started as a background job of a non-interactive shell (`bash .ci/run &`, nohup) inherits SIGINT ignored,
# and so would every `lbr` the tests start: the tests of Ctrl-C would send it to a process that, as a background job
# should, ignores it. The tests' processes get Ctrl-C as a terminal's foreground job does.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


@pytest.fixture
def q_start() -> np.ndarray:
    return Q_START.copy()


@pytest.fixture(scope="session")
def robot():
    from trajectories.robot import Robot

    return Robot()


@pytest.fixture(scope="session")
def limits():
    from trajectories.limits import default_limits

    return default_limits()


@pytest.fixture
def lbr():
    return run_lbr
