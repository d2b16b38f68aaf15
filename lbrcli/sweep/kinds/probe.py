"""Kind ``probe``: a synthetic run that keeps a core busy (or sleeps) for ``seconds`` and exits with ``exit-code`` — to
measure what a cluster costs per run before a real study, and how failures look in the table."""

from __future__ import annotations

import os
import socket
import time
from typing import Any, Mapping

from . import Outcome, RunKind


def run(options: Mapping[str, Any], timeout: float | None = None) -> Outcome:
    """Busy-loop (``busy = true``, default) or sleep for ``seconds`` [s]; figures: the time taken and where."""
    from trajectories.errors import OptionError

    seconds = float(options.get("seconds", 0.0))
    code = int(options.get("exit-code", 0))
    if not (0.0 <= seconds <= 3600.0):
        raise OptionError(f"--seconds must be in [0, 3600] s, got {seconds:g}")
    t0 = time.perf_counter()
    if options.get("busy", True):
        n = 0
        while time.perf_counter() - t0 < seconds:
            n += 1
    else:
        time.sleep(seconds)
    figures = {"elapsed_s": time.perf_counter() - t0, "pid": os.getpid(), "host": socket.gethostname(),
               "value": options.get("value")}
    return Outcome(figures, code, f"probe asked to exit {code}" if code else None)


KIND = RunKind(
    name="probe",
    command=None,
    run=run,
    options=("seconds", "busy", "exit-code", "value"),
    summary="a synthetic run (busy or sleeping for --seconds): what the cluster costs per run; no lbr command",
)
