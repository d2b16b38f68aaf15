"""The cache of completed runs: ``RESULTS/runs.jsonl``, one JSON record per line, keyed by the hash of the run's inputs.

Written like the FRI execution log: a line per completed run, appended and flushed as it arrives (synced to disk at
least every second and at the end), so a study that crashes or is interrupted keeps every run it completed; a
torn last line is ignored. A rerun reads it and computes only the runs whose keys it does not hold — the same study
after a crash, or one with a longer grid or more samples.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import time
from pathlib import Path
from typing import Iterator

STORE_NAME = "runs.jsonl"
SYNC_EVERY_S = 1.0


def read_records(path: Path) -> Iterator[dict]:
    """The records of a store file in order; lines that are not complete JSON records are skipped."""
    if not path.exists():
        return
    with open(path, encoding="utf-8") as fh:
        for line in fh:
            try:
                rec = json.loads(line)
            except json.JSONDecodeError:
                continue  # a line torn by a crash
            if isinstance(rec, dict) and "key" in rec:
                yield rec


@contextlib.contextmanager
def _interrupts_deferred():
    """SIGINT held back while the block runs (delivered right after it), where the platform allows it."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


class RunStore:
    """The completed runs of a results folder, by key; :meth:`add` appends one."""

    def __init__(self, folder: Path) -> None:
        self.path = Path(folder) / STORE_NAME
        self.records: dict[str, dict] = {}
        for rec in read_records(self.path):
            self.records[rec["key"]] = rec  # a key written twice (a store merged by hand): the last one
        self._fh = None
        self._synced = time.monotonic()

    def __contains__(self, key: str) -> bool:
        return key in self.records

    def __len__(self) -> int:
        return len(self.records)

    def add(self, rec: dict) -> bool:
        """Append a completed run; False (and nothing written) when its key is already stored."""
        if rec["key"] in self.records:
            return False
        if self._fh is None:
            self._fh = open(self.path, "a", encoding="utf-8")
            if self._fh.tell() and not self._ends_with_newline():
                self._fh.write("\n")  # after a torn line: start on a fresh one
        line = json.dumps(rec, separators=(",", ":"), allow_nan=False) + "\n"
        with _interrupts_deferred():  # a Ctrl-C between the write and the record would leave the file a run ahead
            self._fh.write(line)
            self._fh.flush()
            self.records[rec["key"]] = rec
        if time.monotonic() - self._synced >= SYNC_EVERY_S:
            self.sync()
        return True

    def _ends_with_newline(self) -> bool:
        with open(self.path, "rb") as fh:
            fh.seek(-1, os.SEEK_END)
            return fh.read(1) == b"\n"

    def sync(self) -> None:
        if self._fh is not None:
            self._fh.flush()
            os.fsync(self._fh.fileno())
        self._synced = time.monotonic()

    def close(self) -> None:
        if self._fh is not None:
            self.sync()
            self._fh.close()
            self._fh = None
