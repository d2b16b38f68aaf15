"""The execution log: columns from the first message, IO values kept when missing, complete rows only."""

from __future__ import annotations

import numpy as np

from lbrcli.fri.codec import FriCodec
from lbrcli.fri.log import LOG_COLUMNS, ExecutionLog, LogLayout
from trajectories.csvio import read_table
from tests.helpers.cli import Q_START

Q0 = tuple(Q_START.tolist())  # [rad]


def test_log_layout_io_columns_and_missing_values(tmp_path):
    codec = FriCodec("1.15")
    m = codec.new_monitoring()
    m.header.messageIdentifier, m.header.sequenceCounter, m.header.reflectedSequenceCounter = 0x245142, 0, 0
    m.connectionInfo.sessionState, m.connectionInfo.quality = 2, 3
    for name, val in (("ball_theta", 0.2), ("t", 1.0), ("a,b", 2.0)):
        io = m.monitorData.readIORequest.add()
        io.name, io.type, io.direction, io.analogValue = name, 2, 0, val
    layout = LogLayout(m, "1.15", extra=("flange_x",))
    assert layout.names[-4:] == ("flange_x", "ball_theta", "io_t", "a_b")
    path = tmp_path / "l.csv"
    with ExecutionLog(path) as log:
        log.start(layout)
        log.write(layout.format(0.0, m, Q0, -1, 0, 0, 0, -1, (0.5,)))
        del m.monitorData.readIORequest[:]  # later message without IO values: keep the last ones
        log.write(layout.format(0.001, m, Q0, 0, 1, 0, 0, -1, (0.6,)))
    tab = read_table(path, LOG_COLUMNS, time="increasing")
    np.testing.assert_array_equal(tab.column("ball_theta"), [0.2, 0.2])
    np.testing.assert_array_equal(tab.column("a_b"), [2.0, 2.0])
    np.testing.assert_array_equal(tab.column("msr_q1"), [0.0, 0.0])  # not sent → 0
    np.testing.assert_array_equal(tab.column("cmd_q4"), [Q0[3]] * 2)


def test_log_without_any_message_is_removed(tmp_path):
    log = ExecutionLog(tmp_path / "empty.csv")
    assert (tmp_path / "empty.csv").exists()
    log.close()
    assert not (tmp_path / "empty.csv").exists()


def test_numpy_commands_are_logged_as_the_exact_doubles_sent(tmp_path):
    """A client commanding numpy scalars or an array (the upright controller does) gets a readable log, each value
    the exact double sent (numpy 2 writes ``np.float64(…)`` for ``%r``)."""
    codec = FriCodec("1.15")
    m = codec.new_monitoring()
    m.header.messageIdentifier = 0x245142
    layout = LogLayout(m, "1.15")
    q = np.array(Q0) + np.array([1e-17, 1 / 3, -2e-9, 1e16, 0.1, -0.0, 123.456])
    path = tmp_path / "l.csv"
    with ExecutionLog(path) as log:
        log.start(layout)
        log.write(layout.format(0.0, m, q, -1, 0, 0, 0, -1))
        log.write(layout.format(0.001, m, tuple(np.float64(v) for v in q), 0, 1, 0, 0, -1))
        log.write(layout.format(0.002, m, tuple(q.tolist()), 0, 1, 0, 0, -1))
    tab = read_table(path, LOG_COLUMNS, time="increasing")
    for j in range(7):
        np.testing.assert_array_equal(tab.column(f"cmd_q{j + 1}"), [q[j]] * 3)
