"""The execution log written by a child process (``lbrcli.fri.logwriter.LogProcess``): the same rows as the
in-process log, every row handed over is written, and a writer that cannot write stops the session."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

from lbrcli.fri import EndReason, ExecutionLog, LogObserver, Outcome, TrajectoryPlayer
from lbrcli.fri.logwriter import LogProcess
from lbrcli.fri.log import LOG_COLUMNS, NAN_COLUMNS, PHASE_BRAKE
from trajectories.csvio import read_table

from lbrcli.fri.testing import CA, Cycle

from tests.helpers.fri_session import LIM, min_jerk, preamble, run


@pytest.mark.heavy
@pytest.mark.parametrize("version", ["1.15", "2.7"])
def test_the_writer_process_writes_the_rows_the_in_process_log_writes(tmp_path, version):
    n = 300
    traj = min_jerk(n)
    inproc = ExecutionLog(tmp_path / "in.csv")
    child = LogProcess(tmp_path / "child.csv", extra_names=("row_x2",), extra=lambda s: (2.0 * s.timestamp_sec,))
    try:
        res, ctl, _, err = run(preamble() + [Cycle(state=CA)] * (n + 50), TrajectoryPlayer(traj, LIM, period_s=1e-3),
                               version=version,
                               observers=[LogObserver(inproc, ("row_x2",), lambda s: (2.0 * s.timestamp_sec,)), child])  # fmt: skip
    finally:
        inproc.close()
        child.close()
    assert err is None and res.ok, res.detail if res else err
    assert child.error is None and child.written == child.rows == inproc.rows > n
    # byte for byte the same file: decoded again from the datagram in the writer, formatted by the same layout
    assert (tmp_path / "child.csv").read_bytes() == (tmp_path / "in.csv").read_bytes()
    table = read_table(tmp_path / "child.csv", LOG_COLUMNS, time="increasing")
    assert len(table.data) == inproc.rows


def _pendulum_columns(state):
    """Extra columns as the pendulum module's: nan before its first reading (every third second of sequence
    counters here), then values of every size (a whole number, a tiny one, a negative zero)."""
    k = state.sequence_counter
    if k % 300 < 100:
        return (math.nan, math.nan, -1.0)
    return (k * 1e-3 - 0.25, -0.0 if k % 7 == 0 else 3.5e-7 * k, float(k % 5))


@pytest.mark.heavy
def test_the_writer_writes_nan_extra_columns_and_the_braking_stop_as_the_in_process_log(tmp_path):
    n = 1500
    names = NAN_COLUMNS
    inproc = ExecutionLog(tmp_path / "in.csv")
    child = LogProcess(tmp_path / "child.csv", extra_names=names, extra=_pendulum_columns)

    def stop(i, app):  # Ctrl-C mid-move: a braking stop, its rows logged with the braking phase
        if i == 700:
            app.interrupt()

    try:
        res, ctl, _, err = run(preamble() + [Cycle(state=CA)] * (n + 50), TrajectoryPlayer(min_jerk(n), LIM,
                               period_s=1e-3), version="2.7", on_cycle=stop,
                               observers=[LogObserver(inproc, names, _pendulum_columns), child])  # fmt: skip
    finally:
        inproc.close()
        child.close()
    assert err is None and res.outcome is Outcome.INTERRUPTED and res.braking_cycles > 0, (err, res)
    assert child.error is None and child.written == child.rows == inproc.rows
    assert (tmp_path / "child.csv").read_bytes() == (tmp_path / "in.csv").read_bytes()
    table = read_table(tmp_path / "child.csv", LOG_COLUMNS, time="increasing", nan_columns=names)
    phase, row = table.column("phase"), table.column("row")
    assert np.sum(phase == PHASE_BRAKE) == res.braking_cycles and np.all(row[phase == PHASE_BRAKE] == -1)
    theta = table.column("pend_theta")
    assert 0 < np.isnan(theta).sum() < len(theta)
    assert b",-0," in (tmp_path / "child.csv").read_bytes()  # a negative zero stays one


@pytest.mark.heavy
def test_a_writer_that_cannot_write_brakes_and_ends_the_session():
    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full on this system")
    # a 6 s move at ≈ 0.47 rad/s (within every limit, so only the log can end it). The writer runs at nice 19: on
    # an idle machine it finds the disk full within milliseconds and the session brakes mid-move; on a machine whose
    # cores are taken by other work it can be starved for the whole move — then the close says so (lbr exits 1)
    n = 6000
    player = TrajectoryPlayer(min_jerk(n, amp=1.5), LIM, period_s=1e-3)
    log = LogProcess("/dev/full")
    try:
        res, ctl, _, err = run(preamble() + [Cycle(state=CA)] * (n + 300), player, observers=[log])
    finally:
        log.close()
    assert err is None, err
    if res.outcome is Outcome.FAILED:
        assert res.reason is EndReason.OBSERVER_FAILED, res.detail
        assert "cannot write the log" in res.detail and "No space left" in res.detail
        assert res.braking_cycles > 0  # it was moving: a braking stop, not a cut
    else:  # starved until the end: never a silent success
        assert res.ok and log.error is not None and "cannot write the log" in log.error, (res.detail, log.error)


def test_a_log_that_cannot_be_created_is_refused_at_once(tmp_path):
    from trajectories.errors import InputError

    with pytest.raises(InputError, match="cannot write the log"):
        LogProcess(tmp_path / "no" / "such" / "dir.csv")


def _fake_app(codec, k):
    """What LogProcess.on_cycle reads of an application, for monitoring message ``k`` (a valid datagram)."""
    from types import SimpleNamespace

    m = codec.new_monitoring()
    m.header.messageIdentifier, m.header.sequenceCounter, m.header.reflectedSequenceCounter = 0x245142, k, 0
    m.connectionInfo.sessionState, m.connectionInfo.quality, m.connectionInfo.sendPeriod = 3, 3, 1
    m.monitorData.measuredJointPosition.value.extend([0.1 * k + j for j in range(7)])
    cycle = SimpleNamespace(braking=False, answered=True, t=k * 1e-3, sent_position=True, phase=2, row=k, state=3,
                            command=tuple(0.1 * k + j for j in range(7)))  # fmt: skip
    return SimpleNamespace(cycle=cycle, state=None, _last_data=codec.encode(m), client_sequence=k,
                           version=codec.version)  # fmt: skip


@pytest.mark.heavy
@pytest.mark.parametrize("version", ["1.15", "2.7"])
def test_a_loop_that_dies_loses_at_most_the_rows_not_yet_handed_over_and_signals_do_not_stop_the_writer(
    tmp_path, version
):
    import signal

    from lbrcli.fri.codec import FriCodec
    from lbrcli.fri.logwriter import FLUSH_ROWS

    codec = FriCodec(version)
    log = LogProcess(tmp_path / "log.csv")
    n = 5 * FLUSH_ROWS + 7
    for k in range(n):
        log.on_cycle(_fake_app(codec, k))
        if k == FLUSH_ROWS:  # Ctrl-C and SIGTERM reach the writer too (the process group): it writes on
            log._proc.send_signal(signal.SIGINT)
            log._proc.send_signal(signal.SIGTERM)
    # the loop dies (kill -9): the pipe closes without the last hand-over; the writer writes what it was handed
    log._proc.stdin.close()
    assert log._proc.wait(30) == 0
    assert log._proc.stdout.read().strip() == f"rows {n - n % FLUSH_ROWS}".encode()
    log._proc.stdout.close()
    rows = read_table(tmp_path / "log.csv", LOG_COLUMNS, time="increasing")
    handed = n - n % FLUSH_ROWS
    assert len(rows.data) == handed
    np.testing.assert_allclose(rows.column("row"), np.arange(handed))
    np.testing.assert_allclose(rows.column("msr_q3"), 0.1 * np.arange(handed) + 2)


@pytest.mark.heavy
@pytest.mark.skipif(not hasattr(os, "SCHED_IDLE") or not os.path.exists("/proc/self/stat"), reason="Linux only")
def test_the_writer_runs_under_sched_idle_so_a_woken_loop_preempts_it_at_once(tmp_path):
    log = LogProcess(tmp_path / "log.csv")
    try:
        pid = log._proc.pid
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        assert int(fields[41 - 3]) == os.SCHED_IDLE  # field 41 (policy); the split starts at field 3
        assert int(fields[19 - 3]) == 19  # nice
    finally:
        log.close()
