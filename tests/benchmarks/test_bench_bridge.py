"""The bridge benchmark's judge of which replies reached the controller in time."""

import sys
from pathlib import Path

import numpy as np


def _bench():
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
    try:
        import bench_bridge
    finally:
        sys.path.pop(0)
    return bench_bridge


class _Table:
    def __init__(self, **cols):
        self.cols = {k: np.asarray(v) for k, v in cols.items()}

    def column(self, name):
        return self.cols[name]


def test_a_reply_is_on_time_when_the_next_message_reflects_its_own_counter():
    """Our counter lags the controller's by the messages never answered (here 4 at the start): replies reflected by
    the next message are on time whatever that offset; one the next message does not reflect is late, and so is the
    first row after a message the log skipped (the old judge, message counter − reflected == 1, read all as late)."""
    seq = np.array([10, 11, 12, 13, 14, 16, 17])
    client = seq - 4
    refl = np.array([5, 6, 7, 7, 9, 11, 12])  # row 3 reflects the reply before the last: ours to 12 was late
    tab = _Table(seq=seq, client_seq=client, reflected_seq=refl, answered=np.ones(7))
    on_time = _bench()._on_time(tab)
    assert on_time.tolist() == [False, True, True, False, True, False, True]
    assert not (seq - refl == 1).any()  # what the previous judge asked
