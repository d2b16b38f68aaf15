"""CPU per row of the execution log: the FRI loop's share (``LogProcess.on_cycle``: the hand-over) and the writer
process's (``RowWriter.take``: decode the datagram again, format, write), against the in-process log
(``LogObserver``: decode already done by the loop, format and one write per row).

A scripted session of `lbr execute`'s client (a trajectory player, one extra column, FRI 1.15 and 2.7) is run over
loopback with both logs attached; the frames the loop handed to the writer are recorded and then converted again by a
``RowWriter`` in this process, in the pipe's batches (``FLUSH_ROWS`` rows), into a file in a temporary folder — the
file must equal the in-process log byte for byte. Figures: the best of ``REPEATS`` timed conversions [µs per row]
(the best, as timeit: other work on a shared machine only ever slows a run), and the loop's share per row over the
session. It measures the code per row, not the writer process's wake-ups (once per hand-over) or the pipe.

Run: `python benchmarks/run_all.py fri_log` or `python benchmarks/bench_fri_log.py [--quick] [--profile]`.
"""

from __future__ import annotations

import cProfile
import pstats
import sys
import tempfile
import time
from pathlib import Path

from lbrcli.fri import ClientApplication, ExecutionLog, LogObserver, LogProcess, TrajectoryPlayer
from lbrcli.fri.logwriter import RowWriter
from trajectories.limits import default_limits

from bench_fri_step import ROWS, main as bench_main, scripted_session, trajectory

REPEATS = 7
LIM = default_limits()
EXTRA = ("row_x2",)


def _extra(state) -> tuple[float]:
    return (2e-3 * state.sequence_counter,)


class _Timed:
    """An observer's ``on_cycle`` with its thread CPU time summed [ns]."""

    def __init__(self, inner) -> None:
        self.inner, self.ns, self.calls, self.name = inner, 0, 0, inner.name

    def on_cycle(self, app) -> None:
        t0 = time.thread_time_ns()
        self.inner.on_cycle(app)
        self.ns += time.thread_time_ns() - t0
        self.calls += 1


def record(folder: Path, version: str) -> tuple[list[bytes], float, float]:
    """The frames handed to the writer in one scripted session, and the loop's CPU per row [µs] of the hand-over
    and of the in-process log (both attached to the same session)."""
    inproc = ExecutionLog(folder / f"in{version}.csv")
    child = LogProcess(folder / f"child{version}.csv", EXTRA, _extra)
    frames: list[bytes] = []
    send = child._send
    child._send = lambda frame: (frames.append(bytes(frame)), send(frame))[1]  # type: ignore[method-assign]
    hand, own = _Timed(child), _Timed(LogObserver(inproc, EXTRA, _extra))
    player = TrajectoryPlayer(trajectory(ROWS), LIM, period_s=1e-3, settle_cycles=4)
    app = ClientApplication(player, "127.0.0.1", 0, bind_host="127.0.0.1", version=version, limits=LIM,
                            observers=[hand, own]).connect()  # fmt: skip
    try:
        scripted_session(app, version)
    finally:
        inproc.close()
        child.close()
    assert child.error is None, child.error
    return frames, hand.ns * 1e-3 / hand.calls, own.ns * 1e-3 / own.calls


def convert(folder: Path, frames: list[bytes], version: str, profile: cProfile.Profile | None = None) -> float:
    """[µs] per row of converting the recorded frames again (checked against the in-process log)."""
    log = ExecutionLog(folder / "again.csv")
    writer = RowWriter(log)
    if profile is not None:
        profile.enable()
    t0 = time.thread_time_ns()
    for frame in frames:
        writer.take(frame)
    t1 = time.thread_time_ns()
    if profile is not None:
        profile.disable()
    rows = log.rows
    log.close()
    if (folder / "again.csv").read_bytes() != (folder / f"in{version}.csv").read_bytes():
        raise AssertionError("the writer's rows differ from the in-process log's")
    return (t1 - t0) * 1e-3 / rows


def run(quick: bool = False, profile: bool = False) -> list[tuple[str, float, str]]:
    """The figures (name, value, unit) per FRI version: the writer's CPU per row (best of the repeats), the loop's
    hand-over and the in-process log per row."""
    repeats = 3 if quick else REPEATS
    rows: list[tuple[str, float, str]] = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for version in ("1.15", "2.7"):
            frames, hand_us, own_us = record(folder, version)
            best = min(convert(folder, frames, version) for _ in range(repeats))
            rows += [(f"FRI {version}: log writer process, CPU per row (decode, format, write), best of {repeats}",
                      round(best, 2), "µs"),
                     (f"FRI {version}: FRI loop, hand-over to the writer per row", round(hand_us, 2), "µs"),
                     (f"FRI {version}: FRI loop, in-process log per row (LogObserver)", round(own_us, 2), "µs")]  # fmt: skip
            if profile:
                prof = cProfile.Profile()
                convert(folder, frames, version, prof)
                pstats.Stats(prof).sort_stats("tottime").print_stats(10)
    return rows


if __name__ == "__main__":
    sys.exit(bench_main(sys.argv[1:], "fri_log", run))
