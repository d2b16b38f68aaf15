"""A result computed once per test run and shared by every xdist worker (pytest-xdist's documented file-lock pattern).

Under ``-n 2`` each worker runs its own session and module fixtures, so an expensive plan asked for by tests on both
workers was made twice. ``once`` makes it once: the first worker to ask computes it under an exclusive lock in the run's
shared temporary folder (the parent of the workers' base temps) and pickles it there; the others wait for the lock and
read it. Without xdist it is computed in the process (the parent folder is then shared by earlier runs).
"""

from __future__ import annotations

import fcntl
import hashlib
import os
import pickle
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import TypeVar
from unittest.mock import patch

import pytest

T = TypeVar("T")
_LOCAL: dict[str, object] = {}


def shared_dir(tmp_path_factory: pytest.TempPathFactory) -> Path | None:
    """The folder every worker of this run shares, or None when the run has no workers."""
    if not os.environ.get("PYTEST_XDIST_WORKER"):
        return None
    return tmp_path_factory.getbasetemp().parent


def once(tmp_path_factory: pytest.TempPathFactory, key: str, make: Callable[[Path], T]) -> T:
    """``make(folder)`` computed once per run for ``key`` (its files written into ``folder``), shared by the workers."""
    if key in _LOCAL:
        return _LOCAL[key]  # type: ignore[return-value]
    root = shared_dir(tmp_path_factory)
    name = "once-" + hashlib.sha1(key.encode()).hexdigest()[:16]
    if root is None:
        value = make(tmp_path_factory.mktemp(name, numbered=False))
    else:
        folder, done = root / name, root / f"{name}.pickle"
        with open(root / f"{name}.lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)  # the others wait here while the first computes
            if done.exists():
                value = pickle.loads(done.read_bytes())
            else:
                folder.mkdir(exist_ok=True)
                value = make(folder)
                part = done.with_suffix(".part")
                part.write_bytes(pickle.dumps(value))
                part.rename(done)
    _LOCAL[key] = value
    return value


def shared_optimise(tmp_path_factory: pytest.TempPathFactory) -> Callable:
    """``planners.swingup_fast.optimise`` with each search made once per run, shared by the workers.

    The differential evolution runs on the problem at the search's coarse step whatever the plan's step, so a plan at
    1 ms and one at 5 ms of the same request make the very same search (the key: the coarse problem, the settings and
    the start); the result at the asked step is evaluated here each time, as ``optimise`` does.
    """
    from planners.swingup_fast import evaluate, optimise

    def shared(problem, settings, start=None):
        coarse = replace(problem, dt=max(problem.dt, settings.coarse_dt))
        key = f"optimise {coarse!r} {settings!r} {start!r}"
        params = once(tmp_path_factory, key, lambda _folder: optimise(coarse, settings, start)[0])
        return params, evaluate(problem, params)

    return shared


def shared_swing_up(tmp_path_factory: pytest.TempPathFactory) -> Callable:
    """``planners.swingup.plan_swing_up`` with each fast request planned once per run, shared by the workers.

    The fast swing-up's optimisation takes 30 s or more on a busy machine; the planner's tests and the tutorial that
    runs `lbr plan swing-up --method fast` ask for the very same request (the key: the request and the limits); its
    searches are shared too (``shared_optimise``: the command's test plans the same request at 1 ms).
    """
    from planners import swingup

    plan = swingup.plan_swing_up

    def planned(request, robot, limits):
        with patch.object(swingup, "optimise", shared_optimise(tmp_path_factory)):
            return plan(request, robot, limits)

    def shared(request, robot, limits, progress=None):
        if request.method != "fast":
            return plan(request, robot, limits, progress=progress)
        key = f"plan_swing_up {request!r} {limits!r} {type(robot).__name__}"
        return once(tmp_path_factory, key, lambda _folder: planned(request, robot, limits))

    return shared
