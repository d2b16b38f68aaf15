"""`lbr plan anti-sway`: files, JSON figures, the check, and the sway of the path the joint CSV really produces."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from lbrcli.commands.plan_antisway import plan_anti_sway_files
from planners.antisway import DEFAULT_LAYOUT, residual_sway, simulate_path
from trajectories.csvio import read_joint_csv, read_table, read_task_csv
from trajectories.robot import Robot

L = 0.25


def _fk_residual_deg(joint_csv, true_length, stop_time):
    """Residual [deg] of the nonlinear pendulum on the flange path of the written joint CSV (independent FK)."""
    traj = read_joint_csv(joint_csv)
    pos, rot = Robot().fk_path(traj.q)
    run = simulate_path(traj.t, pos, true_length, stop_time)
    return math.degrees(residual_sway(run, stop_time)), pos, rot


@pytest.fixture(scope="module")
def default_plan(tmp_path_factory):
    d = tmp_path_factory.mktemp("antisway")
    from conftest import run_lbr

    files = {k: d / f"{k}" for k in ("joint.csv", "task.csv", "pred.csv", "plot.png")}
    proc = run_lbr(
        "plan", "anti-sway", "--length", L, "--a-max", 2.0, "-o", files["joint.csv"], "--task-out", files["task.csv"],
        "--prediction", files["pred.csv"], "--plot", files["plot.png"], "--json",
    )
    return proc, files


def test_default_plan_cli(default_plan):
    proc, files = default_plan
    assert proc.returncode == 0, proc.stderr
    figs = json.loads(proc.stdout)
    for key in ("duration_s", "peak_sway_deg", "residual_sway_deg", "max_ik_error_m", "limits_ok"):
        assert key in figs
    assert figs["limits_ok"] is True
    assert figs["residual_sway_deg"] <= 0.1
    assert figs["max_ik_error_m"] < 1e-6
    assert figs["motion_s"] <= 1.05 * figs["baseline_motion_s"]
    assert files["plot.png"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    pred = read_table(files["pred.csv"], ("t", "theta", "phi", "theta_x", "theta_y"))
    assert math.degrees(pred.column("theta").max()) == pytest.approx(figs["peak_sway_deg"], rel=1e-6)


def test_joint_csv_is_what_was_predicted(default_plan):
    proc, files = default_plan
    figs = json.loads(proc.stdout)
    res, pos, rot = _fk_residual_deg(files["joint.csv"], L, figs["motion_s"])
    assert res == pytest.approx(figs["residual_sway_deg"], abs=1e-3)
    # flange straight down at z = 0.45 m through the turning points
    np.testing.assert_allclose(rot[:, :, 2], np.tile([0.0, 0.0, -1.0], (len(rot), 1)), atol=1e-8)
    np.testing.assert_allclose(pos[:, 2], 0.45, atol=1e-8)
    for p in DEFAULT_LAYOUT:
        assert np.min(np.linalg.norm(pos[:, :2] - p, axis=1)) < 1e-8
    task = read_task_csv(files["task.csv"])
    np.testing.assert_allclose(task.position, pos, atol=1e-7)


def test_plan_passes_lbr_check(default_plan, lbr):
    _, files = default_plan
    proc = lbr("check", files["joint.csv"], "--json")
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["limits_ok"] is True


def test_baseline_reports_jerk_and_fails_only_when_asked(tmp_path):
    out = tmp_path / "base.csv"
    figs = plan_anti_sway_files(DEFAULT_LAYOUT, L, 1.0, None, "accel", 0.005, out)
    assert figs["limits_ok"] and figs["shaper"] == "accel"
    assert figs["jerk_ratio"] > 0 and figs["jerk_enforced"] is False
    assert figs["motion_s"] == pytest.approx(figs["baseline_motion_s"])
    shaped = plan_anti_sway_files(DEFAULT_LAYOUT, L, 1.0, None, "auto", 0.005, tmp_path / "auto.csv")
    assert shaped["jerk_ratio"] < figs["jerk_ratio"] * 3  # reported for every plan


@pytest.mark.parametrize("err", [-0.2, 0.2])
def test_length_tolerance_on_the_real_joint_path(tmp_path, err):
    out = tmp_path / "robust.csv"
    figs = plan_anti_sway_files(DEFAULT_LAYOUT, L, 2.0, None, "auto", 0.005, out, length_tolerance=0.2)
    assert figs["limits_ok"]
    res, _, _ = _fk_residual_deg(out, L * (1 + err), figs["motion_s"])
    assert res <= 0.5
    base = plan_anti_sway_files(DEFAULT_LAYOUT, L, 2.0, None, "accel", 0.005, tmp_path / "b.csv")
    res_base, _, _ = _fk_residual_deg(tmp_path / "b.csv", L * (1 + err), base["motion_s"])
    assert res < res_base
    assert figs["motion_s"] <= base["motion_s"] + 4 * figs["period_s"]


def test_infeasible_acceleration_names_the_segment_and_the_largest_fit(tmp_path, lbr):
    proc = lbr("plan", "anti-sway", "--length", L, "--a-max", 6, "-o", tmp_path / "x.csv")
    assert proc.returncode == 1
    line = proc.stderr.strip().splitlines()[-1]
    assert line.startswith("lbr: error:") and "segment 1" in line and "largest a_max that fits is" in line
    best = float(line.split("largest a_max that fits is ")[1].split()[0])
    assert 0.5 < best < 6
    assert not (tmp_path / "x.csv").exists()
    # the reported value does fit
    figs = plan_anti_sway_files(DEFAULT_LAYOUT[:2], L, best, None, "auto", 0.005, tmp_path / "ok.csv")
    assert figs["limits_ok"]


@pytest.mark.parametrize(
    "args, word",
    [
        (("--points", "0.4,0.1"), "--points"),
        (("--points", "0.4,0.1;0.4,0.1"), "zero length"),
        (("--shaper", "bogus"), "--shaper"),
        (("--length", "-1"), "--length"),
        (("--a-max", "0"), "--a-max"),
        (("--points", "0.4,a;0.5,0"), "--points"),
    ],
)
def test_bad_input_exits_2_with_one_line(tmp_path, lbr, args, word):
    base = {"--length": "0.25", "--a-max": "1"}
    extra = dict(zip(args[::2], args[1::2]))
    base.update(extra)
    flat = [x for kv in base.items() for x in kv]
    proc = lbr("plan", "anti-sway", "-o", tmp_path / "x.csv", *flat)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and word in lines[0] and "Traceback" not in proc.stderr
