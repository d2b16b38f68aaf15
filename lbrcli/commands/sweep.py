"""`lbr sweep STUDY.toml -o RESULTS`: a parameter study of a planner or controller, run on Dask.

Option parsing, the results folder and printing; the study file is :mod:`lbrcli.sweep.spec`, the runs
:mod:`lbrcli.sweep.kinds`, the cluster :mod:`lbrcli.sweep.engine`.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Annotated, Optional

import typer

from ..options import JsonOpt, number

TABLE_NAMES = ("results.parquet", "results.csv")


def _list_kinds(value: bool) -> None:
    if not value:
        return
    from ..sweep.kinds import registry

    for name, kind in sorted(registry().items()):
        typer.echo(f"{name:16s} {kind.summary}")
        if kind.options is not None:
            typer.echo(f"{'':16s} options: {', '.join(kind.options)}")
    raise typer.Exit(0)


def parse_selection(text: str, n: int, option: str, words: tuple[str, ...] = ()) -> tuple[set[int], set[str]]:
    """'0-9,15' → run indices; ``words`` (e.g. all, ok, failed) are returned apart. OptionError on anything else."""
    from trajectories.errors import OptionError

    picked: set[int] = set()
    named: set[str] = set()
    for part in (p.strip() for p in text.split(",") if p.strip()):
        if part in words:
            named.add(part)
            continue
        lo, sep, hi = part.partition("-")
        try:
            a, b = int(lo), int(hi) if sep else int(lo)
        except ValueError:
            raise OptionError(
                f"{option}: expected run numbers like 0-9,15{' or ' + ', '.join(words) if words else ''}, got {part!r}"
            ) from None
        if not (0 <= a <= b < n):
            raise OptionError(f"{option}: {part} is outside the study's runs 0-{n - 1}")
        picked.update(range(a, b + 1))
    return picked, named


def auto_batch(runs: int, workers: int) -> int:
    """Runs per Dask task: 1 up to 100 tasks per worker, then as many as keep it at ≈ 100 (at most 50 runs)."""
    return max(1, min(50, runs // (100 * max(workers, 1))))


def _prepare_folder(out: Path) -> None:
    """Create RESULTS, or accept it when it holds a study's results (or nothing); a folder of other files is refused."""
    from trajectories.errors import OptionError

    from ..sweep.store import STORE_NAME

    if out.exists() and not out.is_dir():
        raise OptionError(f"-o {out}: exists and is not a folder")
    if out.is_dir() and any(out.iterdir()) and not (out / STORE_NAME).exists():
        raise OptionError(f"-o {out}: a folder that holds no study results ({STORE_NAME}); choose a new or empty one")
    if not out.parent.is_dir():
        raise OptionError(f"-o {out}: no folder {out.parent}")
    out.mkdir(exist_ok=True)
    (out / "plots").mkdir(exist_ok=True)
    (out / STORE_NAME).touch()  # marks the folder as a study's, also when this first attempt stops early


def sweep(
    study_file: Annotated[
        Path,
        typer.Argument(
            help="Study file (TOML): kind, fixed options, parameters to vary, figures; see docs/guides/sweep.md."
        ),
    ],
    out: Annotated[
        Path,
        typer.Option(
            "-o", "--out", help="Results folder: runs.jsonl (the cache), results.parquet, results.csv, plots/, joints/."
        ),
    ],
    scheduler: Annotated[
        Optional[str],
        typer.Option(
            "--scheduler",
            help="Dask scheduler address (tcp://HOST:8786 or a scheduler file); 'inline' runs in this process without Dask. Default: a local cluster of --workers processes.",
        ),
    ] = None,
    workers: Annotated[
        Optional[int],
        number(
            "--workers",
            low=1,
            high=512,
            integer=True,
            help="Worker processes of the local cluster (one run each at a time); default: the CPU count.",
        ),
    ] = None,
    batch: Annotated[
        Optional[int],
        number(
            "--batch",
            low=1,
            high=10_000,
            integer=True,
            help="Runs per Dask task; default: 1, or enough for ≈ 100 tasks per worker in large studies (a task costs the scheduler ≈ 1–10 ms).",
        ),
    ] = None,
    runs_sel: Annotated[
        Optional[str],
        typer.Option("--runs", help="Only these runs of the study, e.g. 0-9,15 (try a study before the cluster)."),
    ] = None,
    joints: Annotated[
        Optional[str],
        typer.Option(
            "--joints",
            help="Write the joint files of these runs to RESULTS/joints/: run numbers (0-9,15), ok, failed or all; cached runs are re-run for them.",
        ),
    ] = None,
    fresh: Annotated[
        bool,
        typer.Option(
            "--fresh",
            help="Ignore the cache: run everything again (the new records replace nothing; the table uses them).",
        ),
    ] = False,
    dry_run: Annotated[
        bool,
        typer.Option(
            "--dry-run",
            help="Check the study and show its runs (how many, how many cached, the first command lines); run nothing.",
        ),
    ] = False,
    strict: Annotated[
        bool, typer.Option("--strict", help="Exit 1 when any run did not exit 0 (default: only when runs crashed).")
    ] = False,
    plots: Annotated[
        bool,
        typer.Option(
            "--plots/--no-plots",
            help="Draw the study's \\[\\[plot]] maps (default: success map and figures over the first two varied options).",
        ),
    ] = True,
    kinds: Annotated[
        bool,
        typer.Option(
            "--kinds", callback=_list_kinds, is_eager=True, help="List the run kinds and their options, and exit."
        ),
    ] = False,
    json_out: JsonOpt = False,
) -> None:
    """Run a parameter study: every combination of the varied options (grids, lists, seeded random samples) as one run
    of a planner or controller, on a Dask cluster; one table row per run (inputs, figures, exit code, error, time).

    Completed runs are cached in RESULTS/runs.jsonl by their inputs: a rerun after a crash or Ctrl-C, or with a longer
    grid or more samples, computes only what is new. A failing run is a row with its exit code and error line.
    Exit 0 when every run has its row, 1 when runs crashed (an exception, a lost worker, a timeout; with --strict also
    when any run exited non-zero) or the scheduler cannot be reached, 2 for a bad study file or option, 130 on Ctrl-C
    (the runs completed so far are kept and tabled).
    """
    import time

    from trajectories.errors import CheckFailed

    from ..console import Reporter
    from ..sweep.engine import INLINE, ClusterSpec, run_runs
    from ..sweep.spec import Run, expand, read_study
    from ..sweep.store import RunStore

    rep = Reporter(json_out)
    study = read_study(study_file)
    runs = all_runs = expand(study)
    if runs_sel is not None:
        chosen, _ = parse_selection(runs_sel, len(runs), "--runs")
        runs = [r for r in runs if r.index in chosen]
    joint_idx, joint_words = parse_selection(joints, len(all_runs), "--joints", ("all", "ok", "failed")) \
        if joints is not None else (set(), set())  # fmt: skip
    store = RunStore(out) if (out / "runs.jsonl").exists() and not fresh else None
    cached = {r.key for r in runs if store is not None and r.key in store}
    if dry_run:
        kind_runs = runs[:5]
        from ..sweep.kinds import get_kind
        from ..sweep.values import plain

        kind = get_kind(study.kind)
        rep.print(f"{study.path}: {study.name} — {len(runs)} runs of {study.kind} ({len(cached)} cached in {out})")
        for r in kind_runs:
            line = kind.shell_line({k: plain(v) for k, v in r.options})
            rep.print(
                f"  {r.index}: "
                + (line or "(no single lbr command: " + ", ".join(f"{k}={plain(v)}" for k, v in r.options) + ")"),
                markup=False,
            )
        rep.emit({"runs": len(runs), "cached": len(cached), "kind": study.kind, "study": study.name})
        return
    _prepare_folder(out)
    store = RunStore(out)
    if fresh:
        store.records.clear()
    _copy_study(study_file, out)
    want_joints = _joint_keys(runs, joint_idx, joint_words, store)
    unique: dict[str, Run] = {}
    for r in runs:
        if r.key not in store or r.key in want_joints:
            unique.setdefault(r.key, r)
    todo = list(unique.values())
    cached_n = len({r.key for r in runs}) - len({r.key for r in todo if r.key not in store})
    counts = {"computed": 0, "done": 0, "run_seconds": 0.0}
    joint_files: list[str] = []
    where = {"text": INLINE, "workers": 1}
    index_of: dict[str, list[int]] = {}
    for r in runs:
        index_of.setdefault(r.key, []).append(r.index)

    def ready(text: str, n: int) -> None:
        where.update(text=text, workers=n)
        rep.print(
            f"{study.name}: {len(runs)} runs of {study.kind}, {cached_n} cached, {len(todo)} to run on {text}"
            + ("" if "local" in text or "inline" in text else f" ({n} workers)")
        )

    t0 = time.perf_counter()
    interrupted = False
    execution = None
    with rep.progress(f"sweep {study.name}", len(todo)) as update:

        def on_result(res) -> None:
            if store.add(res.record):
                counts["computed"] += 1
                counts["run_seconds"] += res.record["seconds"]
            if res.joints is not None:
                joint_files.extend(_write_joints(out, res.joints, index_of[res.record["key"]], joint_idx, joint_words,
                                                 res.record))  # fmt: skip
            counts["done"] += 1
            update(counts["done"])

        n_workers = workers or os.cpu_count() or 1
        cluster = ClusterSpec(scheduler, n_workers, batch or auto_batch(len(todo), n_workers))
        try:
            execution = run_runs(todo, cluster, frozenset(want_joints), on_result, ready)
        except KeyboardInterrupt:
            interrupted = True
        finally:
            store.close()
    wall = time.perf_counter() - t0
    figures = _finish(study, all_runs, runs, store, out, plots and not interrupted)
    figures.update(
        cached=cached_n,
        computed=counts["computed"],
        wall_s=wall,
        where=where["text"],
        workers=where["workers"],
        startup_s=execution.startup_s if execution else None,
        joint_files=joint_files,
        interrupted=interrupted,
    )
    if execution and counts["computed"]:
        busy = execution.wall_s * execution.workers
        figures["runs_per_s"] = counts["computed"] / execution.wall_s
        figures["run_s_mean"] = counts["run_seconds"] / counts["computed"]
        figures["overhead_per_run_s"] = (busy - counts["run_seconds"]) / counts["computed"]
    if interrupted:
        rep.print(
            f"interrupted: {counts['computed']} runs completed in this session are kept in {store.path}; "
            "run the same command again to continue"
        )
        rep.emit(figures)
        raise KeyboardInterrupt
    rep.print(
        f"{figures['rows']} rows ({figures['ok']} ok, {figures['failed']} failed, {figures['bad_input']} bad input, "
        f"{figures['crashed']} crashed); {counts['computed']} computed in {wall:.1f} s"
        + (
            f", {figures['overhead_per_run_s'] * 1e3:.1f} ms overhead per run"
            if "overhead_per_run_s" in figures
            else ""
        )
    )
    rep.print(f"table: {out / TABLE_NAMES[0]}, {out / TABLE_NAMES[1]}" + (f"; plots: {len(figures['plots'])} in {out / 'plots'}"
                                                                         if figures["plots"] else ""))  # fmt: skip
    rep.emit(figures)
    if figures["crashed"]:
        raise CheckFailed(f"{figures['crashed']} runs crashed (status 'crashed' in the table)")
    if strict and figures["rows"] != figures["ok"]:
        raise CheckFailed(f"{figures['rows'] - figures['ok']} of {figures['rows']} runs did not exit 0 (--strict)")
    if figures["missing"]:
        raise CheckFailed(f"{figures['missing']} runs of the study have no result")


def _copy_study(study_file: Path, out: Path) -> None:
    from ..outputs import atomic_open

    target = out / "study.toml"
    if target.resolve() == study_file.resolve():
        return
    with atomic_open(target, "w", encoding="utf-8") as fh:
        fh.write(study_file.read_text(encoding="utf-8"))


def _joint_keys(runs, idx: set[int], words: set[str], store) -> set[str]:
    """Keys of the runs whose joint files are wanted and not yet written (by number, or all/ok/failed; for ok and
    failed the cached status decides, uncached runs are all asked for)."""
    keys = set()
    for r in runs:
        rec = store.records.get(r.key)
        status = rec["status"] if rec else None
        if (
            r.index in idx
            or "all" in words
            or ("ok" in words and status in (None, "ok"))
            or ("failed" in words and status in (None, "failed"))
        ):
            keys.add(r.key)
    return keys


def _write_joints(out: Path, traj, indices: list[int], idx: set[int], words: set[str], rec: dict) -> list[str]:
    from trajectories.csvio import write_joint_csv

    status = rec["status"]
    wanted = [i for i in indices if i in idx or "all" in words or ("ok" in words and status == "ok")
              or ("failed" in words and status == "failed")]  # fmt: skip
    folder = out / "joints"
    folder.mkdir(exist_ok=True)
    written = []
    for i in wanted:
        path = folder / f"run-{i:06d}.csv"
        write_joint_csv(path, traj)
        written.append(str(path))
    return written


def _finish(study, all_runs, runs, store, out: Path, draw: bool) -> dict:
    """Table and plots from every run of the study that has a record; the summary figures (``missing``: runs of
    ``runs``, those asked for, without a record)."""
    from ..sweep.table import rows, to_arrow, write_tables

    columns, table_rows = rows(study, all_runs, store.records)
    write_tables(to_arrow(study, columns, table_rows), out / TABLE_NAMES[0], out / TABLE_NAMES[1])
    by_status = {s: sum(r["status"] == s for r in table_rows) for s in ("ok", "failed", "bad-input", "crashed")}
    plot_files = _plots(study, table_rows, out) if draw and table_rows else []
    return {
        "study": study.name,
        "kind": study.kind,
        "runs": len(runs),
        "rows": len(table_rows),
        "missing": sum(r.key not in store for r in runs),
        "ok": by_status["ok"],
        "failed": by_status["failed"],
        "bad_input": by_status["bad-input"],
        "crashed": by_status["crashed"],
        "table": [str(out / n) for n in TABLE_NAMES],
        "plots": plot_files,
        "store": str(store.path),
    }


def _plots(study, table_rows: list[dict], out: Path) -> list[str]:
    from ..plots.sweep import numeric, plot_study

    specs = [(p.x, p.y, p.value) for p in study.plots]
    if not specs and study.varied:
        axes = [a for a in study.varied if numeric(table_rows, a)] or list(study.varied[:1])
        x, y = axes[0], axes[1] if len(axes) > 1 else None
        specs = [(x, y, "ok")] + [(x, y, f) for f in (study.figures or ())[:4] if numeric(table_rows, f)]
        specs += [(x, y, k) for k in table_rows[0] if k.startswith("judged_") and numeric(table_rows, k)][:2]
    files = []
    for x, y, value in specs:
        name = f"{'success' if value == 'ok' else value}-over-{x}{'-' + y if y else ''}.png".replace("/", "_")
        path = out / "plots" / name
        plot_study(table_rows, x, y, value, path, f"{study.name}: {value} ({len(table_rows)} runs)")
        files.append(str(path))
    return files


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("sweep")(sweep)
