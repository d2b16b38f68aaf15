"""Strict CSV reader vs numpy.loadtxt on a 60 s, 1 kHz execution log (60,000 rows × 74 columns).

Goal: ``read_table`` (strict: header, finiteness, time rule, one-line errors naming file, row and column) costs
≤ 1.5× ``numpy.loadtxt`` on the same file, with identical values.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

GOAL_RATIO = 1.5


def _log_like(rows: int, seed: int = 0, sparse: bool = False) -> tuple[tuple[str, ...], np.ndarray]:
    """An execution-log-shaped table: the logger's columns, 1 kHz time; dense: every cell a 12-digit number;
    sparse: as a simulator run writes it (zero external torques, commanded torques and idle ball columns)."""
    from lbrcli.fri.log import CONTROL_COLUMNS, CTL_Q_COLUMNS, LOG_COLUMNS

    rng = np.random.default_rng(seed)
    names = tuple(LOG_COLUMNS + CONTROL_COLUMNS + CTL_Q_COLUMNS) + (
        "ball_theta",
        "ball_phi",
        "ball_theta_x",
        "ball_theta_y",
    )
    data = rng.normal(scale=1.0, size=(rows, len(names)))
    data[:, 0] = np.arange(rows) * 1e-3
    counters = [names.index(c) for c in CONTROL_COLUMNS]  # integer counters and codes, as the logger writes them
    data[:, counters] = np.round(np.abs(data[:, counters]) * 1e3)
    if sparse:
        zero = [k for k, n in enumerate(names) if n.startswith(("ext_tau", "cmd_tau", "ball_"))]
        data[:, zero] = 0.0
        data[:, [names.index(n) for n in ("state", "quality")]] = 4.0
    return names, data


def _best(fn, repeats: int) -> float:
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def measure(quick: bool = False, sparse: bool = False) -> dict:
    from lbrcli.fri.log import LOG_COLUMNS, NAN_COLUMNS
    from trajectories.csvio import read_table, write_table

    rows = 6_000 if quick else 60_000
    repeats = 2 if quick else 3
    names, data = _log_like(rows, sparse=sparse)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "log.csv"
        fmt = ["%.6f"] + ["%.12g"] * (len(names) - 1)  # the logger's resolution
        write_table(path, names, data, fmt=fmt)
        size_mb = path.stat().st_size / 1e6
        ref = np.loadtxt(path, delimiter=",", skiprows=1)
        table = read_table(path, LOG_COLUMNS, time="increasing", nan_columns=NAN_COLUMNS)
        identical = bool(np.array_equal(ref, table.data))
        t_loadtxt = t_read = float("inf")
        for _ in range(repeats):  # interleaved: both see the same machine load
            t0 = time.perf_counter()
            np.loadtxt(path, delimiter=",", skiprows=1)
            t_loadtxt = min(t_loadtxt, time.perf_counter() - t0)
            t0 = time.perf_counter()
            read_table(path, LOG_COLUMNS, time="increasing", nan_columns=NAN_COLUMNS)
            t_read = min(t_read, time.perf_counter() - t0)
        # a bad cell in the last row: the strict reader must still name it (cost of the fallback, reported only)
        bad = Path(tmp) / "bad.csv"
        text = path.read_text().splitlines()
        cells = text[-1].split(",")
        cells[5] = "x"
        text[-1] = ",".join(cells)
        bad.write_text("\n".join(text) + "\n")
        t0 = time.perf_counter()
        try:
            read_table(bad, LOG_COLUMNS, time="increasing", nan_columns=NAN_COLUMNS)
            message = "not detected"
        except Exception as exc:  # noqa: BLE001
            message = str(exc)
        t_bad = time.perf_counter() - t0
    ratio = t_read / t_loadtxt
    return {
        "rows": rows,
        "columns": len(names),
        "file_mb": round(size_mb, 1),
        "loadtxt_s": round(t_loadtxt, 3),
        "read_table_s": round(t_read, 3),
        "ratio": round(ratio, 2),
        "goal_ratio": GOAL_RATIO,
        "ok": ratio <= GOAL_RATIO and identical,
        "identical_values": identical,
        "bad_cell_error": message,
        "bad_cell_s": round(t_bad, 3),
    }


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    out = []
    for sparse in (True, False):
        m = measure(quick, sparse)
        kind = "sparse (as the simulator writes it)" if sparse else "dense (12 digits in every cell)"
        out += [
            (f"{kind}: numpy.loadtxt, {m['rows']:,} x {m['columns']}, {m['file_mb']} MB", m["loadtxt_s"], "s"),
            (f"{kind}: strict read_table", m["read_table_s"], "s"),
            (f"{kind}: read_table / loadtxt (goal <= {GOAL_RATIO})", m["ratio"], "x"),
            (f"{kind}: identical values (1 = yes)", float(m["identical_values"]), ""),
            (f"{kind}: bad cell in the last row, time to name it", m["bad_cell_s"], "s"),
        ]
    return out


if __name__ == "__main__":
    import json
    import sys

    print(json.dumps([measure("--quick" in sys.argv, sparse) for sparse in (True, False)], indent=2))
