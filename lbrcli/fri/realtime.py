"""Real-time settings for an FRI loop (Linux): SCHED_FIFO, one CPU, memory locked — all or none.

``with realtime(): app.run()`` is what the commands' real-time option does:

- **SCHED_FIFO** at ``priority`` (default 20): the loop preempts every normally scheduled process the moment its
  message arrives, however busy the PC is (needs root, CAP_SYS_NICE or an ``rtprio`` limit, ``ulimit -r``);
- **CPU affinity** to one CPU (default: the last one the process may use — keep other work off it with ``taskset``
  or ``isolcpus`` for the best result): the loop's code and data stay in that CPU's caches;
- **mlockall** (current and future pages, locked as they are touched; needs CAP_IPC_LOCK or a ``memlock`` limit
  above the process size, ``ulimit -l``): a page the loop has used is never paged out — its first touch is still a
  minor fault, in the loop's first cycles.

Anything the system refuses raises :class:`RealtimeRefused` (exit 2 at the CLI, one line naming the setting and
what grants it) after undoing what was set; leaving the block restores the previous scheduling, affinity and
memory. The loop must sleep between messages (the default wait): the kernel throttles a real-time task that never
sleeps (``/proc/sys/kernel/sched_rt_runtime_us``, 95 % of each second by default).
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import os
from typing import Iterator

from trajectories.errors import InputError

DEFAULT_PRIORITY = 20  # SCHED_FIFO priority 1..99 (the simulator's real-time loop uses 10)
MCL_CURRENT, MCL_FUTURE, MCL_ONFAULT = 1, 2, 4  # <sys/mman.h>, Linux


class RealtimeRefused(InputError):
    """The system refused a real-time setting (exit 2)."""


def _libc() -> ctypes.CDLL:
    return ctypes.CDLL(None, use_errno=True)


def _lock_memory() -> None:
    libc = _libc()
    if libc.mlockall(MCL_CURRENT | MCL_FUTURE | MCL_ONFAULT) == 0:
        return
    err = ctypes.get_errno()
    if err == errno.EINVAL and libc.mlockall(MCL_CURRENT | MCL_FUTURE) == 0:  # a kernel before 4.4
        return
    err = ctypes.get_errno() or err
    raise RealtimeRefused(f"locking the memory (mlockall) was refused ({os.strerror(err)}): it needs "
                          "CAP_IPC_LOCK or a memlock limit above the process size (ulimit -l)")  # fmt: skip


@contextlib.contextmanager
def realtime(priority: int = DEFAULT_PRIORITY, cpu: int | None = None, lock_memory: bool = True) -> Iterator[int]:
    """SCHED_FIFO at ``priority``, pinned to ``cpu`` (None: the last allowed one), memory locked; yields the CPU.
    RealtimeRefused when the system does not permit one of them (nothing stays changed)."""
    if not hasattr(os, "sched_setscheduler") or not hasattr(os, "sched_setaffinity"):
        raise RealtimeRefused("this system has no SCHED_FIFO scheduling (Linux only)")
    old_policy, old_param = os.sched_getscheduler(0), os.sched_getparam(0)
    old_cpus = os.sched_getaffinity(0)
    cpu = max(old_cpus) if cpu is None else cpu
    if cpu not in old_cpus:
        raise RealtimeRefused(f"CPU {cpu} is not one this process may use ({sorted(old_cpus)})")
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    except OSError as exc:
        raise RealtimeRefused(f"real-time scheduling (SCHED_FIFO) was refused ({exc.strerror}): it needs "
                              "root, CAP_SYS_NICE or an rtprio limit (ulimit -r); run without real-time or grant "
                              "it") from None  # fmt: skip
    locked = False
    try:
        os.sched_setaffinity(0, {cpu})
        if lock_memory:
            _lock_memory()
            locked = True
        yield cpu
    finally:
        if locked:
            _libc().munlockall()
        os.sched_setaffinity(0, old_cpus)
        os.sched_setscheduler(0, old_policy, old_param)


def permitted() -> bool:
    """Whether this process may have the real-time settings (tried, then undone)."""
    try:
        with realtime():
            return True
    except RealtimeRefused:
        return False
