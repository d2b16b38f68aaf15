"""Run the rod's identification outside the FRI loop: a worker process (spawned before the session, so its start-up
never costs a cycle) that computes :func:`planners.feedback.session.fit_rod`; the session polls the future once per
cycle. A thread would not do: the fit holds the interpreter's lock for most of its ≈ 0.5 s."""

from __future__ import annotations

import multiprocessing
from concurrent.futures import Future, ProcessPoolExecutor


def _warm(niceness: int = 15) -> None:
    """Import what the fit needs in the worker, before it is needed; and yield the CPU to the FRI loop and the
    controller whenever they want it (the fit is not urgent: the cart holds meanwhile)."""
    import os

    try:
        os.nice(niceness)
    except OSError:
        pass
    import planners.feedback.session  # noqa: F401
    import scipy.linalg  # noqa: F401
    import scipy.optimize  # noqa: F401


class ProcessFitter:
    """``fitter(args) -> Future`` for :class:`planners.feedback.session.UprightSession`; a context manager."""

    def __init__(self, niceness: int = 15) -> None:
        """``niceness``: the worker's (0 in a lock-step simulation, whose loop never leaves the CPU idle)."""
        self._pool = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"), initializer=_warm,
                                         initargs=(niceness,))  # fmt: skip
        self._pool.submit(int).result(timeout=120)  # the worker is up (and has imported) before the session

    def __call__(self, args: tuple) -> Future:
        from planners.feedback.session import fit_rod

        return self._pool.submit(fit_rod, *args)

    def close(self) -> None:
        """Stop the worker, a fit still running included, and wait for the pool's thread (left running, it raced the
        interpreter's exit and printed an ignored EBADF traceback)."""
        procs = list((getattr(self._pool, "_processes", None) or {}).values())
        self._pool.shutdown(wait=False, cancel_futures=True)
        for p in procs:
            p.terminate()
        self._pool.shutdown(wait=True)

    def __enter__(self) -> "ProcessFitter":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
