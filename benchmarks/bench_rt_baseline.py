"""What this machine itself allows a 1 ms real-time loop: a bare SCHED_FIFO loop with nothing in it, no network, no FRI.

A loop at SCHED_FIFO priority 30 sleeps to each 1 ms grid point and records how late it woke (the time from the grid
point to the wake-up), once with nothing added and once beside two processes spinning at default priority (as the
``busy`` condition and the ``--realtime`` run of bench_fri_timing). Figures per condition: wake-up lateness p50 /
p99 / p99.9 / max [ms] and the periods it woke more than 2 ms and more than 5 ms late. A controller's quality rule
ends a session after 5 untimely replies in 50 periods: one wake-up 5 ms late drops a 1 ms session whatever the
client does. When the wake-ups of this empty loop stall that long, the FRI results of the busy condition say more
about the machine than about any client (KUKA's included). The spinners are started before the loop raises its
priority (a child inherits SCHED_FIFO). Needs the privilege SCHED_FIFO needs (root, CAP_SYS_NICE or an ``rtprio``
limit); without it the figures say so and nothing is measured.

Run: `python benchmarks/run_all.py rt_baseline` (writes benchmarks/results/rt_baseline.json) or
`python benchmarks/bench_rt_baseline.py [--quick]`.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time

PERIOD_S = 1e-3  # [s]
PRIORITY = 30  # SCHED_FIFO, above the simulator's (10) and the client's --realtime (20)


def _spinners(n: int) -> list[subprocess.Popen]:
    return [subprocess.Popen([sys.executable, "-c", "while True: pass"], start_new_session=True) for _ in range(n)]


def lateness(seconds: float, busy: int) -> list[float]:
    """Wake-up lateness [s] of a SCHED_FIFO loop sleeping to a 1 ms grid for ``seconds``, beside ``busy`` spinning
    processes. PermissionError when SCHED_FIFO is not granted."""
    procs = _spinners(busy)  # (before the priority: a child would inherit SCHED_FIFO)
    old = os.sched_getscheduler(0), os.sched_getparam(0)
    try:
        time.sleep(0.5)  # the spinners running
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(PRIORITY))
        try:
            late: list[float] = []
            t = time.perf_counter()
            end = t + seconds
            while t < end:
                t += PERIOD_S
                pause = t - time.perf_counter()
                if pause > 0.0:
                    time.sleep(pause)
                now = time.perf_counter()
                late.append(now - t)
                if now - t > PERIOD_S:  # fell behind: back onto the grid from here (as the simulator does)
                    t = now
            return late
        finally:
            os.sched_setscheduler(0, old[0], old[1])
    finally:
        for p in procs:
            p.kill()
            p.wait()


def _figures(label: str, late: list[float]) -> list[tuple[str, float, str]]:
    s = sorted(late)
    n = len(s)
    pick = lambda q: s[min(n - 1, int(q * n))] * 1e3  # noqa: E731
    return [
        (f"{label}: periods", float(n), ""),
        (f"{label}: wake-up lateness p50", pick(0.5), "ms"),
        (f"{label}: wake-up lateness p99", pick(0.99), "ms"),
        (f"{label}: wake-up lateness p99.9", pick(0.999), "ms"),
        (f"{label}: wake-up lateness max", s[-1] * 1e3, "ms"),
        (f"{label}: periods woken > 2 ms late", float(sum(x > 2e-3 for x in s)), ""),
        (f"{label}: periods woken > 5 ms late", float(sum(x > 5e-3 for x in s)), ""),
    ]


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    seconds = 5.0 if quick else 30.0
    rows: list[tuple[str, float, str]] = []
    try:
        for label, busy in (("quiet", 0), ("two spinning processes", 2)):
            load = os.getloadavg()[0]
            rows += _figures(label, lateness(seconds, busy))
            rows.append((f"{label}: load average (1 min) before", load, ""))
    except PermissionError:
        return [("SCHED_FIFO granted", 0.0, "bool")]
    return [("SCHED_FIFO granted", 1.0, "bool"), ("seconds per condition", seconds, "s")] + rows


if __name__ == "__main__":
    for name, value, unit in run("--quick" in sys.argv):
        print(f"{name:<55} {value:>10.4g} {unit}")
