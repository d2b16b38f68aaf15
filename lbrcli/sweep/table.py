"""The results table of a study: one row per run — its inputs, its figures, exit code, error line and time — written
as Parquet and CSV (pyarrow), each atomically."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Sequence

from .kinds import get_kind
from .spec import Run, Study
from .values import plain, table_cell

META = ("run", "sample", "status", "exit_code", "error", "run_s", "worker", "key", "command")


def figure_value(figures: dict, name: str) -> Any:
    """A figure by name; dotted names reach into nested objects (``max_ratio.jerk``); None when absent."""
    if name in figures:
        return figures[name]
    value: Any = figures
    for part in name.split("."):
        if not isinstance(value, dict) or part not in value:
            return None
        value = value[part]
    return value


def figure_names(study: Study, records: Sequence[dict]) -> list[str]:
    """The study's figures, or every top-level scalar figure the runs reported (in order of appearance)."""
    if study.figures:
        return list(study.figures)
    names: dict[str, None] = {}
    for rec in records:
        for k, v in rec["figures"].items():
            if v is None or isinstance(v, (bool, int, float, str)):
                names.setdefault(k, None)
    return list(names)


def rows(study: Study, runs: Sequence[Run], records: dict[str, dict]) -> tuple[list[str], list[dict]]:
    """(columns, one dict per run) for the runs that have a record."""
    kind = get_kind(study.kind)
    done = [(r, records[r.key]) for r in runs if r.key in records]
    figs = figure_names(study, [rec for _, rec in done])
    judged: dict[str, None] = {}
    for _, rec in done:
        for k in rec.get("judged", {}):
            judged.setdefault(k, None)
    params = [(p, p if p not in META else f"option.{p}") for p in study.varied]
    taken = set(META) | {c for _, c in params}
    fig_cols = [(f, f if f not in taken else f"figure.{f}") for f in figs]
    columns = ["run", "sample", *(c for _, c in params), "status", "exit_code", "error", "run_s", "worker", "key"]
    columns += [c for _, c in fig_cols] + list(judged) + ["command"]
    out = []
    for run, rec in done:
        values = dict(run.params)
        row = {
            "run": run.index,
            "sample": run.sample,
            **{c: table_cell(values[p]) for p, c in params},
            "status": rec["status"],
            "exit_code": rec["exit_code"],
            "error": rec["error"],
            "run_s": rec["seconds"],
            "worker": rec["worker"],
            "key": run.key,
        }
        for f, col in fig_cols:
            row[col] = table_cell(figure_value(rec["figures"], f))
        for k in judged:
            row[k] = table_cell(rec.get("judged", {}).get(k))
        row["command"] = kind.shell_line({k: plain(v) for k, v in run.options})
        out.append(row)
    return columns, out


def _column(values: list) -> "Any":
    """A pyarrow array: bool, int64 or float64 when every value is one (None allowed), else text."""
    import pyarrow as pa

    present = [v for v in values if v is not None]
    if present and all(isinstance(v, bool) for v in present):
        return pa.array(values, pa.bool_())
    if all(isinstance(v, int) and not isinstance(v, bool) for v in present):
        return pa.array(values, pa.int64())
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in present):
        return pa.array([None if v is None else float(v) for v in values], pa.float64())
    return pa.array([None if v is None else v if isinstance(v, str) else json.dumps(v) for v in values], pa.string())


def to_arrow(study: Study, columns: list[str], table_rows: list[dict]):
    import pyarrow as pa

    arrays = [_column([r.get(c) for r in table_rows]) for c in columns]
    meta = {"lbr.study": json.dumps({"name": study.name, "kind": study.kind, "file": study.path,
                                     "fixed": {k: plain(v) for k, v in study.fixed},
                                     "samples": study.samples, "seed": study.seed})}  # fmt: skip
    return pa.Table.from_arrays(arrays, names=columns).replace_schema_metadata(meta)


def write_tables(table, parquet: Path, csv: Path) -> None:
    """Parquet and CSV, each under a temporary name renamed when complete."""
    import pyarrow.csv as pcsv
    import pyarrow.parquet as pq

    from trajectories.atomic import atomic_path

    with atomic_path(parquet) as tmp:
        pq.write_table(table, tmp)
    with atomic_path(csv) as tmp:
        pcsv.write_csv(table, tmp)
