"""Where the runs execute: a Dask cluster (a local one of worker processes by default, or the scheduler at an address),
or this process (``inline``: no Dask, for debugging).

Dask does the distribution, the retries of runs lost with a worker (a run is re-run elsewhere; a run that kills
three workers becomes a ``crashed`` row), and the bookkeeping; this module submits the runs, hands each completed
one to ``on_result`` exactly once, and stops cleanly on Ctrl-C (the local workers ignore the terminal's SIGINT: only
this process reacts, cancels what is queued and closes the cluster).
"""

from __future__ import annotations

import contextlib
import logging
import signal
import time
from dataclasses import dataclass
from typing import Callable, Iterator, Sequence

from .spec import Run
from .worker import RunResult, execute_batch, record

INLINE = "inline"
CONNECT_TIMEOUT_S = 15.0


@dataclass(frozen=True)
class ClusterSpec:
    """``scheduler``: None (a local cluster), ``inline``, or a Dask address (``tcp://host:8786``, a scheduler
    file path); ``workers``: local worker processes (one thread each); ``batch``: runs per Dask task."""

    scheduler: str | None = None
    workers: int = 2
    batch: int = 1


@dataclass(frozen=True)
class Execution:
    """What the cluster was and took: its workers and the wall time from the first submit to the last result [s]."""

    where: str
    workers: int
    wall_s: float
    startup_s: float


@contextlib.contextmanager
def sigint_ignored() -> Iterator[None]:
    """SIGINT ignored while local workers start: they inherit it (across exec), so the terminal's Ctrl-C reaches only
    this process, which then stops them in order."""
    try:
        old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:  # not the main thread: nothing to inherit
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


def _lbr_version() -> str:
    from importlib.metadata import version

    return version("lbr")


def _crashed(runs: Sequence[Run], exc: BaseException) -> list[RunResult]:
    """Rows for runs whose task failed in Dask itself (e.g. KilledWorker: it took down three workers)."""
    text = f"{type(exc).__name__}: {exc}".splitlines()[0]
    return [RunResult(record(r, 1, text, {}, {}, 0.0, crashed=True, worker="?")) for r in runs]


def run_inline(runs: Sequence[Run], joints: frozenset[str], on_result: Callable[[RunResult], None]) -> Execution:
    t0 = time.perf_counter()
    for r in runs:
        on_result(execute_batch((r,), joints)[0])
    return Execution("this process (inline)", 1, time.perf_counter() - t0, 0.0)


def run_dask(
    runs: Sequence[Run],
    cluster: ClusterSpec,
    joints: frozenset[str],
    on_result: Callable[[RunResult], None],
    on_ready: Callable[[str, int], None] | None = None,
) -> Execution:
    """Submit ``runs`` (``cluster.batch`` per task) and call ``on_result`` once per run as results arrive."""
    from distributed import Client, LocalCluster, as_completed

    from trajectories.errors import CheckFailed

    t_start = time.perf_counter()
    local = None
    if cluster.scheduler is None:
        with sigint_ignored():
            local = LocalCluster(n_workers=cluster.workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                                 dashboard_address=None, silence_logs=logging.ERROR)  # fmt: skip
        client = Client(local)
        where = f"local cluster ({cluster.workers} worker processes)"
    else:
        from pathlib import Path

        try:
            if Path(cluster.scheduler).is_file():  # a scheduler file (dask scheduler --scheduler-file, dask-jobqueue)
                client = Client(scheduler_file=cluster.scheduler, timeout=CONNECT_TIMEOUT_S)
            else:
                client = Client(cluster.scheduler, timeout=CONNECT_TIMEOUT_S)
        except (OSError, TimeoutError) as exc:
            raise CheckFailed(f"no Dask scheduler answered at {cluster.scheduler} ({exc})") from None
        where = f"Dask scheduler {cluster.scheduler}"
    futures = []
    try:
        try:
            versions = client.run(_lbr_version)
        except Exception as exc:  # noqa: BLE001
            raise CheckFailed(
                f"the Dask workers cannot run lbr ({type(exc).__name__}: {exc}): install lbr on every worker"
            ) from None
        mine = _lbr_version()
        stale = sorted(addr for addr, v in versions.items() if v != mine)
        if stale:
            raise CheckFailed(f"workers {', '.join(stale)} run lbr {versions[stale[0]]}, this is lbr {mine}: install "
                              "the same lbr on every worker")  # fmt: skip
        n_workers = len(versions)
        from .kinds import warm_up

        client.run(warm_up, runs[0].kind if runs else "probe")
        if on_ready is not None:
            on_ready(where, n_workers)
        startup = time.perf_counter() - t_start
        t0 = time.perf_counter()
        batches = [tuple(runs[i : i + cluster.batch]) for i in range(0, len(runs), cluster.batch)]
        keys = [f"lbr-run-{b[0].key}-{len(b)}" for b in batches]
        by_key = dict(zip(keys, batches))
        futures = client.map(execute_batch, batches, joints=joints, key=keys, pure=False)
        for fut, results in as_completed(futures, with_results=True, raise_errors=False):
            if fut.status != "finished":  # the task, not the run, failed: KilledWorker (it took down 3 workers)
                exc = results[1] if isinstance(results, tuple) and len(results) == 3 else results
                results = _crashed(by_key[fut.key], exc if isinstance(exc, BaseException) else
                                   RuntimeError(f"the Dask task ended {fut.status}"))  # fmt: skip
            fut.release()
            for res in results:
                on_result(res)
        return Execution(where, n_workers, time.perf_counter() - t0, startup)
    finally:
        with sigint_ignored():  # a second Ctrl-C must not leave the cluster half closed
            if futures:
                with contextlib.suppress(Exception):
                    client.cancel(futures, force=True)
            with contextlib.suppress(Exception):
                client.close(timeout=5)
            if local is not None:
                with contextlib.suppress(Exception):
                    local.close(timeout=5)


def run_runs(
    runs: Sequence[Run],
    cluster: ClusterSpec,
    joints: frozenset[str],
    on_result: Callable[[RunResult], None],
    on_ready: Callable[[str, int], None] | None = None,
) -> Execution:
    """Execute ``runs`` where ``cluster`` says."""
    if cluster.scheduler == INLINE:
        if on_ready is not None:
            on_ready("this process (inline)", 1)
        return run_inline(runs, joints, on_result)
    return run_dask(runs, cluster, joints, on_result, on_ready)
