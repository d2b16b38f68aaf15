"""--realtime (``lbrcli.fri.realtime``): SCHED_FIFO, one CPU and locked memory for the session, restored after; a
system that refuses any of it is told in one line with exit 2, before anything starts."""

from __future__ import annotations

import ctypes
import errno
import os
import subprocess
import sys

import numpy as np
import pytest

from lbrcli.fri import realtime as rt
from trajectories.csvio import write_joint_csv
from trajectories.trajectory import JointTrajectory
from tests.helpers.cli import Q_START

Q0 = tuple(Q_START.tolist())  # [rad]


def _permitted() -> bool:
    return rt.permitted()


_REFUSING = """
import os, sys
def refuse(*a):
    raise PermissionError(1, "Operation not permitted")
os.sched_setscheduler = refuse
from lbrcli.app import main
main(sys.argv[1:])
"""


@pytest.mark.heavy
@pytest.mark.parametrize("command", ["execute", "ptp"])
def test_a_refused_realtime_exits_2_with_one_line_before_anything_starts(tmp_path, command):
    traj = tmp_path / "t.csv"
    write_joint_csv(traj, JointTrajectory(t=np.arange(50) * 1e-3, q=np.tile(Q0, (50, 1))))
    args = [str(traj)] if command == "execute" else ["0,0.1,0,-1.3,0,0.1,0", "--time", "2"]
    log = tmp_path / "log.csv"
    proc = subprocess.run([sys.executable, "-c", _REFUSING, command, *args, "--robot", "127.0.0.1", "--port", "0",
                           "--realtime", "--wait", "1", *(["--log", str(log)] if command == "execute" else [])],
                          capture_output=True, text=True, timeout=120)  # fmt: skip
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "--realtime" in lines[0] and "SCHED_FIFO" in lines[0] and "CAP_SYS_NICE" in lines[0]
    assert "waiting for FRI messages" not in proc.stderr and not log.exists()  # refused before binding or logging


def test_the_settings_hold_in_the_block_and_are_restored_after():
    if not _permitted():
        pytest.skip("SCHED_FIFO is not permitted here (the refusal is tested above)")
    cpus = os.sched_getaffinity(0)
    policy = os.sched_getscheduler(0)
    with rt.realtime() as cpu:
        assert os.sched_getscheduler(0) == os.SCHED_FIFO and os.sched_getparam(0).sched_priority == rt.DEFAULT_PRIORITY
        assert os.sched_getaffinity(0) == {cpu} and cpu == max(cpus)
        with open("/proc/self/status") as f:
            locked_kb = next(int(line.split()[1]) for line in f if line.startswith("VmLck:"))
        assert locked_kb > 0  # the pages touched so far are locked
    assert os.sched_getscheduler(0) == policy and os.sched_getaffinity(0) == cpus


def test_a_refused_memory_lock_undoes_the_scheduling(monkeypatch):
    if not _permitted():
        pytest.skip("SCHED_FIFO is not permitted here (the refusal is tested above)")

    class NoLock:
        def mlockall(self, flags):
            ctypes.set_errno(errno.EPERM)
            return -1

    monkeypatch.setattr(rt, "_libc", lambda: NoLock())
    cpus, policy = os.sched_getaffinity(0), os.sched_getscheduler(0)
    with pytest.raises(rt.RealtimeRefused, match="mlockall.*CAP_IPC_LOCK"):
        with rt.realtime():
            pass
    assert os.sched_getscheduler(0) == policy and os.sched_getaffinity(0) == cpus


def test_the_demo_asks_for_realtime_only_where_it_is_granted(monkeypatch):
    from lbrcli.demo.pipeline import demo_steps

    def refuse(*a):
        raise PermissionError(1, "Operation not permitted")

    monkeypatch.setattr(os, "sched_setscheduler", refuse)
    assert not rt.permitted()
    executes = [s for s in demo_steps() if s.argv and s.argv[0] == "execute"]
    assert executes and all("--realtime" not in s.argv for s in executes)
