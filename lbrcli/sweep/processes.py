"""A Dask cluster of separate local processes: `dask scheduler` and `dask worker`s on loopback, started as a lab starts
them on its machines (the recipe of docs/guides/sweep.md) — for the tests and benchmarks of `lbr sweep`."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Iterator

SCHEDULER = [sys.executable, "-m", "distributed.cli.dask_scheduler"]
WORKER = [sys.executable, "-m", "distributed.cli.dask_worker"]


def _wait_for(predicate, timeout: float, what: str) -> None:
    t_end = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > t_end:
            raise TimeoutError(what)
        time.sleep(0.05)


class LocalDaskCluster:
    """``dask scheduler --scheduler-file F`` and ``dask worker --scheduler-file F --nthreads 1 --no-nanny`` processes
    on 127.0.0.1; :meth:`kill` ends one worker with SIGKILL (no goodbye to the scheduler)."""

    def __init__(self, folder: Path, workers: int = 2) -> None:
        self.file = folder / "scheduler.json"
        self.scheduler = subprocess.Popen(
            SCHEDULER + ["--host", "127.0.0.1", "--port", "0", "--no-dashboard", "--scheduler-file", str(self.file)],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip
        _wait_for(self.file.exists, 60, "the dask scheduler did not write its file")
        self.workers = [
            subprocess.Popen(
                WORKER
                + [
                    "--scheduler-file",
                    str(self.file),
                    "--nthreads",
                    "1",
                    "--no-nanny",
                    "--no-dashboard",
                    "--host",
                    "127.0.0.1",
                    "--name",
                    f"w{k}",
                ],
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )  # fmt: skip
            for k in range(workers)
        ]
        _wait_for(lambda: self.n_workers() == workers, 60, "the dask workers did not register")

    @property
    def address(self) -> str:
        return json.loads(self.file.read_text())["address"]

    def n_workers(self) -> int:
        from distributed import Client

        with Client(scheduler_file=str(self.file), timeout=10) as c:
            return len(c.scheduler_info(n_workers=-1)["workers"])

    def kill(self, k: int) -> int:
        pid = self.workers[k].pid
        os.kill(pid, signal.SIGKILL)
        self.workers[k].wait(10)
        return pid

    def close(self) -> None:
        """Workers first, then the scheduler; whatever does not end within 3 s is killed."""
        for group in (self.workers, [self.scheduler]):
            for p in group:
                if p.poll() is None:
                    p.terminate()
            for p in group:
                with contextlib.suppress(subprocess.TimeoutExpired):
                    p.wait(3)
                if p.poll() is None:
                    p.kill()
                    p.wait(5)


@contextlib.contextmanager
def local_dask_cluster(folder: Path, workers: int = 2) -> Iterator[LocalDaskCluster]:
    cluster = LocalDaskCluster(folder, workers)
    try:
        yield cluster
    finally:
        cluster.close()
