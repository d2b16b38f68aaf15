"""The fast subset of the test suite as a benchmark: how many tests `python -m pytest -n 2 -m "not slow and not
heavy"` runs, its wall and CPU time and outcome, and how loaded the machine was (the goal: ≤ 60 s wall on 2 cores,
for a developer's edit-test loop; CI runs the whole suite, `bench_suite`).

`--quick` only counts the tests.
"""

from __future__ import annotations

import os
import re
import resource
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FAST = "not slow and not heavy"  # the marker expression of the fast subset (README's Tests section)


def _children_cpu_s() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _pytest(*args: str, timeout: float = 1800) -> tuple[subprocess.CompletedProcess, float, float]:
    """(the run, wall time [s], CPU time of pytest and its workers [s])."""
    cpu0, t0 = _children_cpu_s(), time.perf_counter()
    res = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-m", FAST, *args], cwd=ROOT,
                         capture_output=True, text=True, timeout=timeout)  # fmt: skip
    return res, time.perf_counter() - t0, _children_cpu_s() - cpu0


def _outcome(text: str) -> dict[str, int]:
    """{'passed': n, 'failed': n, ...} from pytest's last summary line."""
    last = [line for line in text.splitlines() if " in " in line and ("passed" in line or "failed" in line)]
    return {word: int(n) for n, word in re.findall(r"(\d+) (passed|failed|skipped|errors?)", last[-1] if last else "")}


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    res, _, _ = _pytest("--collect-only", "-q")
    collected = sum(1 for line in res.stdout.splitlines() if "::" in line)
    rows = [("fast subset: tests collected", collected, "")]
    if quick:
        return rows
    load = os.getloadavg()[0]
    res, wall, cpu = _pytest("-n", "2", "-q")
    out = _outcome(res.stdout)
    for line in res.stdout.splitlines():
        if line.startswith(("FAILED", "ERROR")):
            print(line, file=sys.stderr)
    return rows + [
        ("fast subset, pytest -n 2: wall time", wall, "s"),
        ("fast subset, pytest -n 2: CPU time (pytest and its workers)", cpu, "s"),
        ("fast subset: load average (1 min) at the start", load, ""),
        ("fast subset: passed", out.get("passed", 0), ""),
        ("fast subset: failed", out.get("failed", 0) + out.get("error", 0) + out.get("errors", 0), ""),
    ]


if __name__ == "__main__":
    for name, value, unit in run("--quick" in sys.argv):
        print(f"{name}: {value:.4g} {unit}")
