"""Run every benchmark in this folder and print its figures: `python benchmarks/run_all.py [--quick] [--json]
[--kuka PATH ...] [NAME ...]`.

Each ``bench_*.py`` module exposes ``run(quick: bool) -> list[tuple[str, float, str]]`` (name, value, unit). A full
run (not ``--quick``) also writes each benchmark's figures to ``benchmarks/results/NAME.json`` (with the date and
the machine's load); ``python benchmarks/figures_page.py`` turns those files into the docs page the docs quote.
"""

from __future__ import annotations

import argparse
import datetime
import importlib.util
import json
import os
import sys
import time
from pathlib import Path

RESULTS = Path(__file__).parent / "results"


def own_results(path: Path) -> bool:
    """True when ``path`` is a results file a benchmark writes itself (its own layout, quoted by its own guide, e.g.
    bench_catch's catch.json), not one of :func:`save_results`'s records."""
    try:
        record = json.loads(path.read_text())
    except (OSError, ValueError):
        return False
    return not (isinstance(record, dict) and "benchmark" in record and "figures" in record)


def save_results(name: str, rows, seconds: float, folder: Path = RESULTS) -> Path | None:
    """Write one benchmark's figures as ``folder/NAME.json``: what was measured, when, on how loaded a machine.
    None (nothing written) when the benchmark writes its own ``NAME.json`` there."""
    folder.mkdir(exist_ok=True)
    if own_results(folder / f"{name}.json"):
        return None
    record = {
        "benchmark": name,
        "command": f"python benchmarks/run_all.py {name}",
        "measured": datetime.datetime.now().isoformat(timespec="seconds"),
        "seconds": round(seconds, 1),
        "cpus": os.cpu_count(),
        "load_1min_before": round(os.getloadavg()[0], 2),
        "figures": [{"name": k, "value": v, "unit": u} for k, v, u in rows],
    }
    path = folder / f"{name}.json"
    tmp = path.with_suffix(".json.part")
    tmp.write_text(json.dumps(record, indent=1, allow_nan=True) + "\n")
    os.replace(tmp, path)
    return path


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="shorter runs (smoke test)")
    parser.add_argument("--json", action="store_true", help="print all figures as one JSON object")
    parser.add_argument(
        "--kuka",
        action="append",
        default=[],
        metavar="PATH",
        help="fri: also measure this KUKA example client (built from KUKA's FRI client SDK)",
    )
    parser.add_argument("--no-save", action="store_true", help="do not write benchmarks/results/NAME.json")
    parser.add_argument("only", nargs="*", help="names of benchmarks to run (e.g. ik fri)")
    args = parser.parse_args()
    here = Path(__file__).parent
    sys.path.insert(0, str(here))  # spawned worker processes import bench modules by name
    figures: dict[str, dict[str, object]] = {}
    for path in sorted(here.glob("bench_*.py")):
        name = path.stem.removeprefix("bench_")
        if args.only and name not in args.only:
            continue
        spec = importlib.util.spec_from_file_location(path.stem, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[path.stem] = module  # functions handed to worker processes pickle by module name
        spec.loader.exec_module(module)  # type: ignore[union-attr]
        t0 = time.perf_counter()
        rows = module.run(quick=args.quick, kuka=args.kuka) if name == "fri" else module.run(quick=args.quick)
        figures[name] = {k: {"value": v, "unit": u} for k, v, u in rows}
        if not (args.quick or args.no_save):
            save_results(name, rows, time.perf_counter() - t0)
        if not args.json:
            print(f"== {name} ({time.perf_counter() - t0:.1f} s)")
            for k, v, u in rows:
                print(f"  {k:<55} {v:>12.4g} {u}")
            sys.stdout.flush()
    if args.json:
        print(json.dumps(figures))
    return 0


if __name__ == "__main__":
    sys.exit(main())
