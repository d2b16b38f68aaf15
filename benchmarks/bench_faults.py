"""FRI fault campaign (tests/lbrcli/fault_campaign.py): every case against the scripted controller, with the largest
commanded step / velocity limit and second difference / acceleration limit relative to what the robot executed.

Run: `python benchmarks/run_all.py faults` (prints the figures; `python benchmarks/bench_faults.py` prints the
table of cases too)."""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "lbrcli"))

from fault_campaign import cases, run_case  # noqa: E402


def results(quick: bool = False):
    all_cases = cases()
    if quick:
        all_cases = all_cases[::4]
    with tempfile.TemporaryDirectory() as tmp:
        return [run_case(c, Path(tmp)) for c in all_cases]


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    rs = results(quick)
    return [
        ("cases", len(rs), ""),
        ("categories", len({r.category for r in rs}), ""),
        ("cases ok (expected end, ≤ limits, no traceback, log readable)", sum(r.ok for r in rs), ""),
        ("largest step / velocity limit", max(r.step_ratio for r in rs), "×"),
        ("largest second difference / acceleration limit", max(r.second_ratio for r in rs), "×"),
        ("tracebacks", sum(r.traceback is not None for r in rs), ""),
        ("unreadable logs", sum(not r.log_readable for r in rs), ""),
    ]


if __name__ == "__main__":
    rs = results("--quick" in sys.argv)
    print(f"{'case':<40} {'category':<20} {'end':<18} {'step/v':>7} {'2nd/a':>7}  log   ok")
    for r in rs:
        print(f"{r.name:<40} {r.category:<20} {r.reason:<18} {r.step_ratio:7.3f} {r.second_ratio:7.3f}  "
              f"{'yes' if r.log_readable else 'NO':<4}  {'ok' if r.ok else 'FAIL'}")  # fmt: skip
    print(f"{sum(r.ok for r in rs)}/{len(rs)} ok; max step/v {max(r.step_ratio for r in rs):.3f}, "
          f"max 2nd/a {max(r.second_ratio for r in rs):.3f}")  # fmt: skip
