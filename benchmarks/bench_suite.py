"""The test suite as a benchmark: how many tests, how long `pytest -n 2` takes, and whether it passes with both
cores saturated by two busy loops (CI machines and laptops are busy machines; issue #34).

`--quick` only counts the tests.
"""

from __future__ import annotations

import re
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _pytest(*args: str, timeout: float = 3600) -> tuple[subprocess.CompletedProcess, float]:
    t0 = time.perf_counter()
    res = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", *args], cwd=ROOT,
                         capture_output=True, text=True, timeout=timeout)  # fmt: skip
    return res, time.perf_counter() - t0


def _outcome(text: str) -> dict[str, int]:
    """{'passed': n, 'failed': n, ...} from pytest's last summary line."""
    last = [line for line in text.splitlines() if " in " in line and ("passed" in line or "failed" in line)]
    return {word: int(n) for n, word in re.findall(r"(\d+) (passed|failed|skipped|errors?)", last[-1] if last else "")}


def _busy_loops(n: int) -> list[subprocess.Popen]:
    return [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(n)]


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    res, _ = _pytest("--collect-only", "-q")
    collected = sum(1 for line in res.stdout.splitlines() if "::" in line)
    rows = [("tests collected", collected, "")]
    if quick:
        return rows
    for label, loops in (("the machine as it is", 0), ("two busy loops beside it", 2)):
        busy = _busy_loops(loops)
        try:
            res, seconds = _pytest("-n", "2", "-q")
        finally:
            for p in busy:
                p.kill()
                p.wait()
        out = _outcome(res.stdout)
        for line in res.stdout.splitlines():
            if line.startswith(("FAILED", "ERROR")):
                print(f"{label}: {line}", file=sys.stderr)
        rows += [
            (f"pytest -n 2, {label}: wall time", seconds, "s"),
            (f"pytest -n 2, {label}: passed", out.get("passed", 0), ""),
            (f"pytest -n 2, {label}: failed", out.get("failed", 0) + out.get("error", 0) + out.get("errors", 0), ""),
        ]
    return rows


if __name__ == "__main__":
    for name, value, unit in run("--quick" in sys.argv):
        print(f"{name}: {value:.4g} {unit}")
