"""Python's settings while an FRI loop runs: no garbage-collector pauses, a short GIL hand-over interval."""

from __future__ import annotations

import contextlib
import gc
import os
import sys
from typing import Iterator

SWITCH_INTERVAL_S = 1e-4  # [s] Python's GIL hand-over interval during a session (default 5 ms): a loop woken by a
# message waits at most this long for a busy thread of the process (a bridge, a sensor, telemetry) to let it run


PROFILE_ENV = "LBR_FRI_PROFILE"  # a file name: the loop of every client runs under cProfile, its stats written there


def _profiler():
    """cProfile running, when ``LBR_FRI_PROFILE`` names a file (the benchmarks' per-cycle profile of any client;
    it slows each cycle several times over: for where the time goes, not how much)."""
    if not os.environ.get(PROFILE_ENV):
        return None
    import cProfile

    profile = cProfile.Profile()
    profile.enable()
    return profile


@contextlib.contextmanager
def loop_settings() -> Iterator[None]:
    """No automatic collection (its pauses would land in cycles) and the short switch interval; both restored after.
    The objects that exist are frozen rather than collected first: a full collection of a large heap (a long-lived
    process, e.g. a notebook or a test worker) holds the GIL for tenths of a second while sensor threads wait."""
    gc.freeze()
    was = gc.isenabled()
    gc.disable()
    switch = sys.getswitchinterval()
    sys.setswitchinterval(min(switch, SWITCH_INTERVAL_S))
    profile = _profiler()
    try:
        yield
    finally:
        sys.setswitchinterval(switch)
        if profile is not None:
            profile.disable()
            profile.dump_stats(os.environ[PROFILE_ENV])
        gc.unfreeze()
        if was:
            gc.enable()
