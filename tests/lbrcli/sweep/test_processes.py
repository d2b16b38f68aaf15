"""`lbr sweep` on real Dask clusters of separate processes: a worker killed mid-study, a study interrupted by Ctrl-C and
resumed with a longer grid. Runs are the sleeping ``probe`` kind (their length is no wall-clock assertion: the tests
wait for records, never for times)."""

from __future__ import annotations

import pytest

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pyarrow.parquet as pq

from lbrcli.sweep.processes import local_dask_cluster


def _records(folder: Path) -> list[dict]:
    path = folder / "runs.jsonl"
    if not path.exists():
        return []
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def _wait_records(folder: Path, n: int, proc: subprocess.Popen, timeout: float = 120) -> None:
    t_end = time.monotonic() + timeout
    while len(_records(folder)) < n:
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < t_end, "the study did not progress"
        time.sleep(0.02)


def _study(path: Path, values: int, seconds: float) -> Path:
    path.write_text(f"""
[study]
kind = "probe"
[fixed]
busy = false
seconds = {seconds}
[vary]
value = {{ from = 1, to = {values}, steps = {values} }}
""")
    return path


def _sweep(*args) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "lbrcli", "sweep", *map(str, args), "--no-plots", "--json"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)  # fmt: skip


@pytest.mark.heavy
def test_worker_killed_mid_study_loses_nothing_and_counts_nothing_twice(tmp_path):
    study = _study(tmp_path / "study.toml", 24, 0.25)
    out = tmp_path / "results"
    with local_dask_cluster(tmp_path, workers=2) as cluster:
        proc = _sweep(study, "-o", out, "--scheduler", cluster.file)
        _wait_records(out, 4, proc)
        victim = cluster.kill(0)  # busy with a run: the queue is far from empty
        stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 0, stderr
    figs = json.loads(stdout)
    recs = _records(out)
    assert len(recs) == 24 and len({r["key"] for r in recs}) == 24  # every run once, none twice
    assert figs["rows"] == 24 and figs["ok"] == 24 and figs["computed"] == 24
    by_pid = {}
    for r in recs:
        by_pid.setdefault(r["figures"]["pid"], []).append(r)
    assert victim in by_pid and len(by_pid) == 2  # the killed worker had finished some, the other did the rest
    table = pq.read_table(out / "results.parquet").to_pylist()
    assert sorted(r["value"] for r in table) == list(range(1, 25))


@pytest.mark.heavy
def test_interrupted_study_resumes_and_an_extended_grid_computes_only_the_new_runs(tmp_path):
    out = tmp_path / "results"
    # 40 sleeping runs of 0.25 s: ≈ 5 s on 2 workers, so the interrupt lands mid-study however late this loaded
    # machine delivers it (20 of 0.15 s once finished first beside two busy loops)
    proc = _sweep(_study(tmp_path / "study.toml", 40, 0.25), "-o", out, "--workers", "2")
    _wait_records(out, 4, proc)
    os.killpg(proc.pid, signal.SIGINT)  # what a terminal's Ctrl-C does: the whole foreground group
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130
    assert "Traceback" not in stderr and stderr.rstrip().endswith("lbr: interrupted")
    done = len(_records(out))
    figs = json.loads(stdout)
    assert figs["interrupted"] and figs["rows"] == done and 4 <= done < 40
    assert len(pq.read_table(out / "results.parquet")) == done  # the partial table

    # the same study with the grid extended from 40 to 46 values: only the runs not yet done are computed
    proc = _sweep(_study(tmp_path / "study.toml", 46, 0.25), "-o", out, "--workers", "2")
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 0, stderr
    figs = json.loads(stdout)
    assert figs["cached"] == done and figs["computed"] == 46 - done and figs["rows"] == 46
    recs = _records(out)
    assert len(recs) == 46 and len({r["key"] for r in recs}) == 46
    assert sorted(r["value"] for r in pq.read_table(out / "results.parquet").to_pylist()) == list(range(1, 47))


@pytest.mark.heavy
def test_a_run_that_kills_its_workers_is_a_crashed_row(tmp_path):
    """Dask gives a run lost with its worker to another; one that takes the workers down (here the first: allowed
    failures 0) ends as a row naming KilledWorker, the study goes on, and the sweep exits 1."""
    study = tmp_path / "study.toml"
    study.write_text('[study]\nkind = "probe"\n[fixed]\nbusy = false\n[vary]\ncrash = ["none", "worker"]\n')
    out = tmp_path / "results"
    proc = subprocess.Popen([sys.executable, "-m", "lbrcli", "sweep", str(study), "-o", str(out), "--workers", "2",
                             "--no-plots", "--json"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES": "0"})  # fmt: skip
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 1 and "1 runs crashed" in stderr
    rows = pq.read_table(out / "results.parquet").to_pylist()
    assert [(r["crash"], r["status"]) for r in rows] == [("none", "ok"), ("worker", "crashed")]
    assert rows[1]["error"].startswith("KilledWorker") and rows[1]["worker"] == "?"
    assert json.loads(stdout)["crashed"] == 1
