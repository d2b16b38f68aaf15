"""`lbr sweep`: study files, their runs and cache keys, runs that reproduce the command's --json, failures as rows, the
shipped example studies."""

from __future__ import annotations

import json
import shlex
import sys
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from lbrcli.sweep.spec import expand, parse_study, read_study
from trajectories.errors import InputError

EXAMPLES = Path(__file__).resolve().parents[3] / "examples" / "studies"


def _study(doc: dict, path: Path):
    return parse_study(doc, str(path))


def test_grids_lists_and_samples_expand_in_order_with_stable_keys(tmp_path):
    doc = {"study": {"kind": "probe", "samples": 3, "seed": 5},
           "vary": {"seconds": {"from": 0.0, "to": 0.2, "steps": 3}, "busy": [True, False],
                    "value": {"uniform": [1.0, 2.0]}, "exit-code": {"integers": [0, 2]}}}  # fmt: skip
    runs = expand(_study(doc, tmp_path / "s.toml"))
    assert len(runs) == 3 * 2 * 3 and [r.index for r in runs] == list(range(18))
    p = [dict(r.params) for r in runs]
    assert [x["seconds"] for x in p[::6]] == [0.0, 0.1, 0.2] and [x["busy"] for x in p[:6]] == [True] * 3 + [False] * 3
    # sample i draws the same values at every grid point (common random numbers), from its own stream
    for i in range(3):
        assert len({(x["value"], x["exit-code"]) for x in p[i::3]}) == 1
    assert all(1.0 <= x["value"] <= 2.0 and x["exit-code"] in (0, 1, 2) for x in p)
    assert len({x["value"] for x in p}) == 3
    assert [r.key for r in expand(_study(doc, tmp_path / "s.toml"))] == [r.key for r in runs]  # deterministic
    # a longer grid and more samples keep every run the study had (same inputs, same keys)
    doc["study"]["samples"] = 5
    doc["vary"]["seconds"] = {"from": 0.0, "to": 0.2, "steps": 5}
    bigger = {r.key for r in expand(_study(doc, tmp_path / "s.toml"))}
    assert len(bigger) == 5 * 2 * 5 and {r.key for r in runs} <= bigger
    doc["study"]["seed"] = 6
    assert not {r.key for r in runs} & {r.key for r in expand(_study(doc, tmp_path / "s.toml"))}


def test_layouts_paths_and_integer_grids(tmp_path):
    (tmp_path / "paths").mkdir()
    for name in ("b.csv", "a.csv"):
        (tmp_path / "paths" / name).write_text("t,x,y,z,qw,qx,qy,qz\n")
    doc = {"study": {"kind": "ik"}, "fixed": {"limits": "limits.toml"}, "vary": {"task": {"glob": "paths/*.csv"}}}
    runs = expand(_study(doc, tmp_path / "s.toml"))
    assert [dict(r.params)["task"] for r in runs] == [str(tmp_path / "paths" / n) for n in ("a.csv", "b.csv")]
    assert dict(runs[0].options)["limits"] == str(tmp_path / "limits.toml")  # relative to the study file
    doc = {"study": {"kind": "ik"}, "vary": {"suite-path": {"from": 0, "to": 75, "steps": 76}}}
    assert [dict(r.params)["suite-path"] for r in expand(_study(doc, tmp_path / "s.toml"))] == list(range(76))
    box = {"segments": [2, 4], "x": [0.4, 0.6], "y": [-0.2, 0.2], "step": [0.05, 0.15]}
    doc = {"study": {"kind": "anti-sway", "samples": 30}, "fixed": {"length": 0.3, "a-max": 1.0},
           "vary": {"points": {"layout": box}}}  # fmt: skip
    for r in expand(_study(doc, tmp_path / "s.toml")):
        pts = np.array(dict(r.params)["points"])
        assert 3 <= len(pts) <= 5 and np.all((pts[:, 0] >= 0.4) & (pts[:, 0] <= 0.6) & (np.abs(pts[:, 1]) <= 0.2))
        steps = np.diff(pts, axis=0)
        assert np.all(np.count_nonzero(np.abs(steps) > 1e-9, axis=1) == 1)  # along x or y
        assert np.all(np.abs(steps).max(axis=1) >= 0.05 - 1e-4) and np.all(np.abs(steps).max(axis=1) <= 0.15 + 1e-4)
        axes = np.argmax(np.abs(steps), axis=1)
        assert np.all(axes[1:] != axes[:-1])  # a 90° turn at every point


@pytest.mark.parametrize("text, message", [
    ('[study]\nkind = "antisway"', "unknown kind 'antisway'"),
    ('[study]\nkind = "anti-sway"\n[fixed]\nlenght = 0.3\na-max = 1', "'lenght' is not an option of anti-sway"),
    ('[study]\nkind = "anti-sway"\n[fixed]\na-max = 1', "anti-sway needs 'length'"),
    ('[study]\nkind = "probe"\n[fixed]\nseconds = 1\n[vary]\nseconds = [1, 2]', "'seconds' is both in [fixed] and [vary]"),
    ('[study]\nkind = "probe"\n[vary]\nvalue = { uniform = [0, 1] }', "samples is needed with random parameters"),
    ('[study]\nkind = "probe"\nsamples = 2\n[vary]\nvalue = { gauss = [0, 1] }', "[vary] value: unknown 'gauss'"),
    ('[study]\nkind = "probe"\n[vary]\nvalue = { from = 1, to = 2 }', "[vary] value: expected a list"),
    ('[study]\nkind = "probe"\n[judge]\nstring-errors = [0.1]', "the kind probe has no judged figures"),
    ('[study]\nkind = "probe"\n[vary]\nvalue = [1]\n[[plot]]\nx = "seconds"\nvalue = "ok"', "x = 'seconds' is not a varied"),
    ('[study]\nkind = "probe"\n[vary]\nvalue = []', "the study has no runs"),
])  # fmt: skip
def test_bad_study_files_name_the_file_and_the_key(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(InputError) as exc:
        read_study(path)
    assert message in str(exc.value) and str(path) in str(exc.value)


def test_a_toml_syntax_error_is_one_line_with_row_and_column(tmp_path, lbr):
    path = tmp_path / "bad.toml"
    path.write_text('[study]\nkind = "probe"\n[vary]\nvalue = = [1, 2]\n')
    p = lbr("sweep", path, "-o", tmp_path / "out")
    assert p.returncode == 2 and p.stdout == ""
    assert p.stderr.count("\n") == 1 and f"{path}, row 4, column 9: not valid TOML" in p.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.heavy
def test_anti_sway_runs_reproduce_the_command_and_failures_are_rows(tmp_path, lbr):
    """Figures and joint file of a run equal `lbr plan anti-sway --json`'s (the table's command line, run as a
    process); the judged sway of the planners' pendulum model agrees with the independent DOP853 judge; an option
    out of range is a bad-input row, not the end of the study."""
    from lbrcli.options import DEFAULT_FLANGE, make_robot
    from planners.sway_judge import judge_sway
    from trajectories.csvio import read_joint_csv

    study = tmp_path / "study.toml"
    study.write_text("""
[study]
kind = "anti-sway"
figures = ["motion_s", "residual_sway_deg", "max_ratio.jerk"]
[fixed]
points = [[0.45, -0.2], [0.62, -0.2], [0.62, 0.05]]
dt = 0.01
shaper = "zv"
length-tolerance = 0.0
[vary]
length = [0.3]
a-max = [1.5, 25.0]
[judge]
string-errors = [-0.2, 0.0, 0.2]
""")
    out = tmp_path / "res"
    p = lbr("sweep", study, "-o", out, "--scheduler", "inline", "--joints", "0", "--json")
    assert p.returncode == 0, p.stderr
    figs = json.loads(p.stdout)
    assert (figs["rows"], figs["ok"], figs["bad_input"]) == (2, 1, 1)
    rows = pq.read_table(out / "results.parquet").to_pylist()
    assert rows[1]["status"] == "bad-input" and rows[1]["exit_code"] == 2 and "--a-max must be in" in rows[1]["error"]
    record = next(json.loads(line) for line in (out / "runs.jsonl").read_text().splitlines()
                  if json.loads(line)["key"] == rows[0]["key"])  # fmt: skip
    cli = lbr(*shlex.split(rows[0]["command"])[1:], "-o", tmp_path / "cli.csv", "--json")
    assert cli.returncode == 0
    expected = json.loads(cli.stdout)
    for key in ("compute_s", "out", "task_out", "prediction", "plot"):
        expected.pop(key, None)
        record["figures"].pop(key, None)
    assert record["figures"] == expected
    assert rows[0]["max_ratio.jerk"] == expected["max_ratio"]["jerk"]
    mine, theirs = read_joint_csv(out / "joints" / "run-000000.csv"), read_joint_csv(tmp_path / "cli.csv")
    assert np.array_equal(mine.q, theirs.q) and np.array_equal(mine.t, theirs.t)
    pos, _ = make_robot(DEFAULT_FLANGE, None).fk_path(theirs.q)
    judged = record["judged"]["judged_residual_sway_by_error_deg"]
    independent = [judge_sway(pos, 0.01, 0.3 * (1 + e), expected["motion_s"])[0] for e in (-0.2, 0.0, 0.2)]
    assert judged[0] > 1.0 and judged[2] > 1.0  # a ZV plan for 0.3 m leaves sway when the string is 20 % off
    assert np.allclose(judged, independent, atol=0.02)
    pngs = list((out / "plots").glob("*.png"))
    assert pngs and all(f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for f in pngs)
    assert (out / "results.csv").read_text().count("\n") == 3


def test_failing_and_crashing_runs_are_rows_and_set_the_exit_code(tmp_path, lbr):
    study = tmp_path / "study.toml"
    study.write_text('[study]\nkind = "probe"\n[vary]\nexit-code = [0, 1]\nseconds = [0.0, -1.0, "soon"]\n')
    out = tmp_path / "res"
    p = lbr("sweep", study, "-o", out, "--scheduler", "inline", "--no-plots", "--json")
    assert p.returncode == 1 and p.stderr.rstrip().endswith("2 runs crashed (status 'crashed' in the table)")
    rows = pq.read_table(out / "results.parquet").to_pylist()
    status = [(r["exit-code"], r["seconds"], r["status"], r["exit_code"]) for r in rows]
    assert status == [(0, "0.0", "ok", 0), (0, "-1.0", "bad-input", 2), (0, "soon", "crashed", 1),
                      (1, "0.0", "failed", 1), (1, "-1.0", "bad-input", 2), (1, "soon", "crashed", 1)]  # fmt: skip
    assert "ValueError" in rows[2]["error"] and rows[3]["error"] == "probe asked to exit 1"
    assert json.loads(p.stdout)["crashed"] == 2
    study.write_text('[study]\nkind = "probe"\n[vary]\nexit-code = [0, 1]\n')  # cached: nothing crashed
    p = lbr("sweep", study, "-o", out, "--scheduler", "inline", "--no-plots", "--strict")
    assert p.returncode == 1 and "1 of 2 runs did not exit 0 (--strict)" in p.stderr


def test_a_results_folder_of_other_files_is_refused(tmp_path, lbr):
    study = tmp_path / "study.toml"
    study.write_text('[study]\nkind = "probe"\n')
    (tmp_path / "busy").mkdir()
    (tmp_path / "busy" / "thesis.pdf").write_text("x")
    p = lbr("sweep", study, "-o", tmp_path / "busy", "--scheduler", "inline")
    assert p.returncode == 2 and "holds no study results" in p.stderr
    assert sorted(f.name for f in (tmp_path / "busy").iterdir()) == ["thesis.pdf"]


@pytest.mark.heavy
def test_example_studies_parse_and_a_subset_runs(tmp_path, lbr):
    files = sorted(EXAMPLES.glob("*.toml"))
    assert len(files) >= 7
    for f in files:
        assert expand(read_study(f))
    for name, runs in (("antisway_10k", "0-1"), ("ik_paths", "40")):
        p = lbr("sweep", EXAMPLES / f"{name}.toml", "-o", tmp_path / name, "--runs", runs, "--scheduler", "inline",
                "--no-plots", "--json", timeout=300)  # fmt: skip
        assert p.returncode == 0, p.stderr
        figs = json.loads(p.stdout)
        assert figs["ok"] == figs["rows"] == figs["runs"]
    row = pq.read_table(tmp_path / "ik_paths" / "results.parquet").to_pylist()[0]
    assert row["solved"] is True and row["path"] and row["max_position_error_m"] < 1e-6


if __name__ == "__main__":
    sys.exit(pytest.main([__file__, "-q"]))
