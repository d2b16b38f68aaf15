"""The fault campaign over every surface that moves the robot (lbrcli.campaign): each case against the scripted
controller, judged on what the robot executed — per surface the cases, the worst velocity / acceleration / jerk
ratio of the commands, stops that were not braking stops, tracebacks, unreadable logs, unexpected ends.

Run: `python benchmarks/bench_faults.py [--quick] [SURFACE ...]` prints every case and the table per surface and
writes benchmarks/results/faults.json (the docs quote that file); `python benchmarks/run_all.py faults`
prints the totals."""

from __future__ import annotations

import json
import sys
import tempfile
import time
from dataclasses import asdict
from pathlib import Path

from lbrcli.campaign import all_cases
from lbrcli.fri.testing.campaign import CaseResult, run_case, summarize

RESULTS = Path(__file__).parent / "results" / "faults.json"


def results(quick: bool = False, surfaces: tuple[str, ...] = (), verbose: bool = False, prefixes: tuple[str, ...] = (),
            categories: tuple[str, ...] = ()):  # fmt: skip
    cases = [c for c in all_cases() if (not surfaces or c.surface in surfaces)
             and (not prefixes or c.name.startswith(prefixes)) and (not categories or c.category in categories)]  # fmt: skip
    if quick:
        cases = cases[::4]
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for c in cases:
            t0 = time.perf_counter()
            r = run_case(c, Path(tmp))
            out.append(r)
            if verbose:
                print(f"{'ok  ' if r.ok else 'FAIL'} {r.name[:62]:<62} {r.reason:<16} v {r.velocity_ratio:5.3f} "
                      f"a {r.acceleration_ratio:5.3f} j {r.jerk_ratio:7.2f} {'NON-BRAKING ' if r.non_braking_stop else ''}"
                      f"{time.perf_counter() - t0:5.1f} s" + ("" if r.expected else f"  unexpected: {r.detail[:120]}")
                      + (f"  {r.traceback}" if r.traceback else ""), flush=True)  # fmt: skip
    return out


def write(rs) -> dict:
    table = summarize(rs)
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(json.dumps({"date": time.strftime("%Y-%m-%d"), "surfaces": table,
                                   "cases": [asdict(r) for r in rs]}, indent=1, default=float))  # fmt: skip
    return table


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    rs = results(quick)
    write(rs)
    return [
        ("cases", len(rs), ""),
        ("surfaces", len({r.surface for r in rs}), ""),
        ("cases ok (expected end, ≤ limits, braking stops, no traceback, log readable)", sum(r.ok for r in rs), ""),
        ("largest step / velocity limit", max(r.velocity_ratio for r in rs), "×"),
        ("largest second difference / acceleration limit", max(r.acceleration_ratio for r in rs), "×"),
        ("stops that were not braking stops", sum(r.non_braking_stop for r in rs), ""),
        ("tracebacks", sum(r.traceback is not None for r in rs), ""),
        ("unreadable logs", sum(not r.log_readable for r in rs), ""),
    ]


def merge(rs) -> dict:
    """Replace the cases of ``rs`` (by name) in the results file and rewrite its table: a rerun of some cases."""
    old = json.loads(RESULTS.read_text())
    new = {r.name: asdict(r) for r in rs}
    cases = [new.pop(c["name"], c) for c in old["cases"]] + list(new.values())
    table = summarize([CaseResult(**c) for c in cases])
    RESULTS.write_text(json.dumps({"date": time.strftime("%Y-%m-%d"), "surfaces": table, "cases": cases}, indent=1,
                                  default=float))  # fmt: skip
    return table


if __name__ == "__main__":
    # NAME: a surface; --case=PREFIX: the cases whose name starts so; --category=C: of that category; --merge: write
    # them into the results file
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    prefixes = tuple(a.split("=", 1)[1] for a in sys.argv[1:] if a.startswith("--case="))
    cats = tuple(a.split("=", 1)[1] for a in sys.argv[1:] if a.startswith("--category="))
    rs = results("--quick" in sys.argv, tuple(args), verbose=True, prefixes=prefixes, categories=cats)
    table = (
        write(rs)
        if not args and not prefixes and not cats and "--quick" not in sys.argv
        else merge(rs)
        if "--merge" in sys.argv
        else __import__("lbrcli.fri.testing.campaign", fromlist=["summarize"]).summarize(rs)
    )
    print(f"\n{'surface':<10} {'cases':>5} {'ok':>5} {'v/lim':>6} {'a/lim':>6} {'j/lim':>7} {'non-brk':>7} {'tb':>3} "
          f"{'log':>3} {'unexp':>5} {'clamped':>8}")  # fmt: skip
    for s, f in table.items():
        print(f"{s:<10} {f['cases']:>5} {f['ok']:>5} {f['worst_velocity_ratio']:6.3f} {f['worst_acceleration_ratio']:6.3f} "
              f"{f['worst_jerk_ratio']:7.2f} {f['non_braking_stops']:>7} {f['tracebacks']:>3} {f['unreadable_logs']:>3} "
              f"{f['unexpected_ends']:>5} {f['clamped_cycles']:>8}")  # fmt: skip
