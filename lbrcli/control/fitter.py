"""Run the rod's identification outside the FRI loop: a worker process (spawned before the session, so its start-up
never costs a cycle) that computes :func:`planners.feedback.session.fit_rod`; the session polls the future once per
cycle. A thread would not do: the fit holds the interpreter's lock for most of its ≈ 0.5 s."""

from __future__ import annotations

import multiprocessing
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures import TimeoutError as FutureTimeout

LOCKSTEP_FIT_S = 1.5  # [s] of simulated time from asking for the rod's fit to taking its result, in lock-step
LOCKSTEP_POLL_WAIT_S = 0.3  # [s] the longest one cycle waits for the fit in lock-step (the simulator waits 0.5 s)


class _AfterCycles:
    """A fit's handle that is done only from its ``cycles``-th poll on (one poll per cycle), waiting for the worker
    then: the result arrives at the same cycle of a lock-step session however long the worker took."""

    def __init__(self, future: Future, cycles: int) -> None:
        self._future, self._left = future, cycles

    def done(self) -> bool:
        if self._left > 0:
            self._left -= 1
            return False
        try:
            self._future.exception(timeout=LOCKSTEP_POLL_WAIT_S)
        except FutureTimeout:
            return False  # slower than the cycles allowed: taken at a later cycle (the machine was very busy)
        return True

    def result(self):
        return self._future.result()


def _warm(niceness: int) -> None:
    """Import what the fit needs in the worker, before it is needed; and (``niceness`` > 0) yield the CPU to the FRI
    loop and the controller whenever they want it (the fit is not urgent: the cart holds meanwhile)."""
    import os

    try:
        if niceness:
            os.nice(niceness)
    except OSError:
        pass
    import planners.feedback.session  # noqa: F401
    import scipy.linalg  # noqa: F401
    import scipy.optimize  # noqa: F401


class ProcessFitter:
    """``fitter(args) -> handle`` for :class:`planners.feedback.session.UprightSession`; a context manager.

    ``lockstep_cycles``: for a simulator in lock-step, the fit's result is taken exactly that many cycles (polls)
    after it was asked for — waited for then, ``LOCKSTEP_POLL_WAIT_S`` [s] per cycle, below the simulator's reply wait
    — so that a run does not depend on how busy the machine is (in real time it is taken as soon as it is ready)."""

    def __init__(self, lockstep_cycles: int | None = None) -> None:
        self.lockstep_cycles = lockstep_cycles
        niceness = 15 if lockstep_cycles is None else 0  # in lock-step the loop waits for the fit: no reason to yield
        self._pool = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"), initializer=_warm,
                                         initargs=(niceness,))  # fmt: skip
        self._pool.submit(int).result(timeout=120)  # the worker is up (and has imported) before the session

    def __call__(self, args: tuple) -> "Future | _AfterCycles":
        from planners.feedback.session import fit_rod

        future = self._pool.submit(fit_rod, *args)
        return future if self.lockstep_cycles is None else _AfterCycles(future, self.lockstep_cycles)

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
