"""Kind ``probe``: a synthetic run that keeps a core busy for ``seconds`` of CPU time (or sleeps) and exits with ``exit-code`` — to
measure what a cluster costs per run before a real study, and how failures look in the table (``crash``: "exception"
raises one, "worker" kills the worker process running it)."""

from __future__ import annotations

import os
import socket
import time
from typing import Any, Mapping

from . import Outcome, RunKind


def run(options: Mapping[str, Any], timeout: float | None = None) -> Outcome:
    """Busy-loop for ``seconds`` of CPU time (``busy = true``, default) or sleep ``seconds`` [s]; figures: the wall
    time taken and where."""
    from trajectories.errors import SettingError

    seconds = float(options.get("seconds", 0.0))
    code = int(options.get("exit-code", 0))
    if not (0.0 <= seconds <= 3600.0):
        raise SettingError("probe", "seconds", f"must be in [0, 3600] s, got {seconds:g}")
    crash = options.get("crash", "none")
    if crash not in ("none", "exception", "worker"):
        raise SettingError("probe", "crash", f"must be none, exception or worker, got {crash!r}")
    if crash == "exception":
        raise RuntimeError("probe asked to crash")
    if crash == "worker":
        import signal

        os.kill(os.getpid(), signal.SIGKILL)
    t0 = time.perf_counter()
    if options.get("busy", True):  # CPU seconds of this thread: on a shared core the run takes longer, as real ones
        c0 = time.thread_time()
        while time.thread_time() - c0 < seconds:
            pass
    else:
        time.sleep(seconds)
    figures = {
        "elapsed_s": time.perf_counter() - t0,
        "pid": os.getpid(),
        "host": socket.gethostname(),
        "value": options.get("value"),
    }
    return Outcome(figures, code, f"probe asked to exit {code}" if code else None)


KIND = RunKind(
    name="probe",
    command=None,
    run=run,
    options=("seconds", "busy", "exit-code", "value", "crash"),
    summary="a synthetic run (busy or sleeping for its seconds): what the cluster costs per run; no lbr command",
)
