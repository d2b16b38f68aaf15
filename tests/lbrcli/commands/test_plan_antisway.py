"""`lbr plan anti-sway`: files, JSON figures, the check, and the sway of the path the joint CSV really produces."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from lbrcli.antisway import plan_anti_sway_files
from planners.antisway import DEFAULT_LAYOUT, residual_sway, simulate_path
from planners.sway_judge import judge_sway
from trajectories.csvio import read_joint_csv, read_table, read_task_csv
from trajectories.robot import Robot

from tests.helpers.shared import once

L = 0.25


def _fk_residual_deg(joint_csv, true_length, stop_time):
    """Residual [deg] of the nonlinear pendulum on the flange path of the written joint CSV (independent FK)."""
    traj = read_joint_csv(joint_csv)
    pos, rot = Robot().fk_path(traj.q)
    run = simulate_path(traj.t, pos, true_length, stop_time)
    return math.degrees(residual_sway(run, stop_time)), pos, rot


@pytest.fixture(scope="module")
def default_plan(tmp_path_factory):
    """The default plan made once per run (this module's tests on both workers share it; they only read its files)."""

    def make(d):
        from tests.helpers.cli import run_lbr

        files = {k: d / f"{k}" for k in ("joint.csv", "task.csv", "pred.csv", "plot.png")}
        proc = run_lbr(
            "plan",
            "anti-sway",
            "--length",
            L,
            "--a-max",
            2.0,
            "-o",
            files["joint.csv"],
            "--task-out",
            files["task.csv"],
            "--prediction",
            files["pred.csv"],
            "--plot",
            files["plot.png"],
            "--json",
        )
        return proc, files

    return once(tmp_path_factory, "lbr plan anti-sway default (test_plan_antisway)", make)


@pytest.mark.heavy
def test_default_plan_cli(default_plan):
    proc, files = default_plan
    assert proc.returncode == 0, proc.stderr
    figs = json.loads(proc.stdout)
    for key in ("duration_s", "peak_sway_deg", "residual_sway_deg", "max_ik_error_m", "limits_ok"):
        assert key in figs
    assert figs["limits_ok"] is True
    assert figs["residual_sway_deg"] <= 0.3
    assert figs["length_tolerance"] == 0.1 and len(figs["band_lengths_m"]) == 5
    assert figs["worst_residual_sway_deg"] <= 0.5  # the default is robust to ±10 % string length
    assert figs["max_ik_error_m"] < 1e-6
    assert figs["motion_s"] <= figs["baseline_motion_s"]
    assert figs["fallback"] is None
    assert files["plot.png"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    pred = read_table(files["pred.csv"], ("t", "theta", "phi", "theta_x", "theta_y"))
    assert math.degrees(pred.column("theta").max()) == pytest.approx(figs["peak_sway_deg"], rel=1e-6)


@pytest.mark.heavy
def test_no_length_in_the_band_is_worse_than_claimed(default_plan):
    """The band's worst residual is judged densely: an independent judge (spline path, DOP853) at lengths between the
    planner's 41 finds none worse than the reported worst."""
    proc, files = default_plan
    figs = json.loads(proc.stdout)
    traj = read_joint_csv(files["joint.csv"])
    pos, _ = Robot().fk_path(traj.q)
    assert figs["band_dense_lengths"] == 41
    worst = figs["worst_residual_sway_deg"]
    k = round((figs["worst_residual_length_m"] / L - 0.9) / 0.2 * 40)  # the worst of the dense grid, and around it
    lengths = L * (0.9 + 0.2 * (np.array([k - 0.5, k + 0.5, 4.5, 17.5, 33.5]) / 40))
    for ln in lengths[(lengths >= 0.9 * L) & (lengths <= 1.1 * L)]:
        residual, _ = judge_sway(pos, traj.dt, float(ln), figs["motion_s"])
        assert residual <= worst * 1.01 + 1e-3, ln


@pytest.mark.heavy
def test_joint_csv_is_what_was_predicted(default_plan):
    proc, files = default_plan
    figs = json.loads(proc.stdout)
    res, pos, rot = _fk_residual_deg(files["joint.csv"], L, figs["motion_s"])
    assert res == pytest.approx(figs["residual_sway_deg"], abs=1e-3)
    # an adaptive integration (scipy DOP853, tight tolerances) of the cubic-spline acceleration of the FK path
    for length, claimed in zip(figs["band_lengths_m"], figs["band_residual_sway_deg"]):
        assert judge_sway(pos, 0.005, length, figs["motion_s"])[0] == pytest.approx(claimed, abs=0.02)
    # flange straight down at z = 0.45 m through the turning points
    np.testing.assert_allclose(rot[:, :, 2], np.tile([0.0, 0.0, -1.0], (len(rot), 1)), atol=1e-8)
    np.testing.assert_allclose(pos[:, 2], 0.45, atol=1e-8)
    for p in DEFAULT_LAYOUT:
        assert np.min(np.linalg.norm(pos[:, :2] - p, axis=1)) < 1e-8
    task = read_task_csv(files["task.csv"])
    np.testing.assert_allclose(task.position, pos, atol=1e-7)


@pytest.mark.heavy  # the module's default plan (`lbr plan anti-sway`): seconds
def test_plan_passes_lbr_check(default_plan, lbr):
    _, files = default_plan
    proc = lbr("check", files["joint.csv"], "--json")
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["limits_ok"] is True


@pytest.mark.heavy
def test_baseline_reports_jerk_and_fails_only_when_asked(tmp_path):
    out = tmp_path / "base.csv"
    figs = plan_anti_sway_files(DEFAULT_LAYOUT, L, 1.0, None, "accel", 0.005, out)
    assert figs["limits_ok"] and figs["shaper"] == "accel"
    assert figs["jerk_ratio"] > 0 and figs["jerk_enforced"] is False
    assert figs["motion_s"] == pytest.approx(figs["baseline_motion_s"])


@pytest.mark.heavy
def test_length_tolerance_on_the_real_joint_path(tmp_path):
    out = tmp_path / "robust.csv"
    figs = plan_anti_sway_files(DEFAULT_LAYOUT, L, 2.0, None, "auto", 0.005, out, length_tolerance=0.2)
    assert figs["limits_ok"]
    base = plan_anti_sway_files(DEFAULT_LAYOUT, L, 2.0, None, "accel", 0.005, tmp_path / "b.csv")
    for err in (-0.2, 0.2):
        res, _, _ = _fk_residual_deg(out, L * (1 + err), figs["motion_s"])
        assert res <= 0.5
        res_base, _, _ = _fk_residual_deg(tmp_path / "b.csv", L * (1 + err), base["motion_s"])
        assert res < res_base
    assert figs["motion_s"] <= base["motion_s"]


@pytest.mark.heavy
def test_infeasible_acceleration_names_the_segment_and_a_verified_fit(tmp_path, lbr):
    pts = "0.40,-0.30;0.62,-0.30"
    proc = lbr(
        "plan", "anti-sway", "--length", L, "--a-max", 6, "--points", pts, "--no-fallback", "-o", tmp_path / "x.csv"
    )
    assert proc.returncode == 1
    line = proc.stderr.strip().splitlines()[-1]
    assert line.startswith("lbr: error:") and "segment 1" in line and "largest a_max that plans is" in line
    best = float(line.split("largest a_max that plans is ")[1].split()[0])
    assert 0.5 < best < 6
    assert not (tmp_path / "x.csv").exists()
    # the reported value plans with the very same command
    ok = lbr(
        "plan",
        "anti-sway",
        "--length",
        L,
        "--a-max",
        best,
        "--points",
        pts,
        "--no-fallback",
        "-o",
        tmp_path / "ok.csv",
        "--json",
    )
    assert ok.returncode == 0, ok.stderr
    assert json.loads(ok.stdout)["limits_ok"]


@pytest.mark.heavy
def test_default_falls_back_to_another_design_before_giving_up(tmp_path):
    figs = plan_anti_sway_files(DEFAULT_LAYOUT[:2], L, 6.0, None, "auto", 0.005, tmp_path / "fb.csv")
    assert figs["limits_ok"] and figs["fallback"] is not None
    assert figs["fallback"]["from"] == "auto" and "joint limits" in figs["fallback"]["reason"]
    assert figs["worst_residual_sway_deg"] <= 0.5


@pytest.mark.heavy
def test_a_layout_whose_middle_segments_break_a_joint_limit_lowers_a_max_there_only(tmp_path):
    """A generated layout where the robust design at a_max breaks A4's acceleration limit on two of four segments:
    the fallback keeps a_max on the others and lowers it on those, which stays quicker than the thesis baseline
    (a single lower a_max, or the box-zvd design, would not), with the residual still ≤ 0.5° across the band."""
    pts = np.array([[0.4084, -0.2578], [0.4084, 0.0506], [0.6703, 0.0506], [0.6703, 0.3132], [0.4786, 0.3132]])
    length, a_max = 0.13517, 2.3442
    base = plan_anti_sway_files(pts, length, a_max, None, "accel", 0.005, tmp_path / "b.csv")
    figs = plan_anti_sway_files(pts, length, a_max, None, "auto", 0.005, tmp_path / "g.csv")
    assert figs["limits_ok"] and "per segment" in figs["fallback"]["to"]
    per_segment = [float(v) for v in figs["fallback"]["to"].split("a_max ")[1].split(" m/s²")[0].split("/")]
    assert len(per_segment) == 4 and max(per_segment) == pytest.approx(a_max, abs=0.006) and min(per_segment) < a_max
    assert figs["motion_s"] <= base["motion_s"]
    pos = Robot().fk_path(read_joint_csv(tmp_path / "g.csv").q)[0]  # judged independently of the planner
    for e in (-0.1, 0.0, 0.1):
        assert judge_sway(pos, 0.005, length * (1 + e), figs["motion_s"])[0] <= 0.5  # [deg]


@pytest.mark.heavy
def test_max_sway_bounds_the_swing_for_every_length_in_the_band(tmp_path, lbr):
    proc = lbr(
        "plan",
        "anti-sway",
        "--length",
        L,
        "--a-max",
        2,
        "--max-sway",
        3,
        "-o",
        tmp_path / "m.csv",
        "--points",
        "0.40,-0.30;0.62,-0.30;0.62,0.05",
        "--json",
    )
    assert proc.returncode == 0, proc.stderr
    figs = json.loads(proc.stdout)
    assert figs["max_sway_deg"] == pytest.approx(3.0)
    assert figs["worst_peak_sway_deg"] <= 3.0
    pos = Robot().fk_path(read_joint_csv(tmp_path / "m.csv").q)[0]
    for length in (0.9 * L, 1.1 * L):
        run = simulate_path(np.arange(len(pos)) * 0.005, pos, length, figs["motion_s"])
        assert math.degrees(run.theta.max()) <= 3.0 + 1e-6


def _write(path, text):
    path.write_text(text)
    return path


@pytest.mark.heavy
def test_obstacle_on_the_ball_path_is_refused_with_its_name_and_time(tmp_path, lbr):
    pts = "0.40,-0.30;0.62,-0.30"
    obs = _write(
        tmp_path / "obs.csv",
        "name,x_min,y_min,z_min,x_max,y_max,z_max\n"
        "# a post the ball must pass beside\npost,0.50,-0.24,0.00,0.56,-0.20,0.25\n",
    )
    ok = lbr(
        "plan",
        "anti-sway",
        "--length",
        L,
        "--a-max",
        2,
        "--points",
        pts,
        "--obstacles",
        obs,
        "--ball-radius",
        0.02,
        "-o",
        tmp_path / "ok.csv",
        "--plot",
        tmp_path / "ok.png",
        "--json",
    )
    assert ok.returncode == 0, ok.stderr
    figs = json.loads(ok.stdout)
    assert figs["nearest_obstacle"]["name"] == "post"
    assert 0 < figs["min_clearance_m"] < 0.06 - 0.02 + 1e-3  # 60 mm from the path, minus the ball's radius
    assert (tmp_path / "ok.png").read_bytes()[:4] == b"\x89PNG"
    # a wider ball no longer passes
    bad = lbr(
        "plan",
        "anti-sway",
        "--length",
        L,
        "--a-max",
        2,
        "--points",
        pts,
        "--obstacles",
        obs,
        "--ball-radius",
        0.07,
        "-o",
        tmp_path / "bad.csv",
    )
    assert bad.returncode == 1
    line = bad.stderr.strip().splitlines()[-1]
    assert "obstacle 'post'" in line and "t = " in line
    assert not (tmp_path / "bad.csv").exists()


@pytest.mark.parametrize(
    "text, where",
    [
        ("name,x_min,y_min,z_min,x_max,y_max\n", "row 1, column 7"),
        ("name,x_min,y_min,z_min,x_max,y_max,z_max\np,0,0,0,1,x,1\n", "row 2, column 6 (y_max)"),
        ("name,x_min,y_min,z_min,x_max,y_max,z_max\np,0,0,0.5,1,1,0.2\n", "row 2, column 7 (z_max)"),
        ("name,x_min,y_min,z_min,x_max,y_max,z_max\np,0,0,0,1,1,1\np,0,0,0,1,1,1\n", "row 3, column 1"),
        ("name,x_min,y_min,z_min,x_max,y_max,z_max\np,0,0,0\n", "row 2, column 5"),
    ],
)
def test_bad_obstacle_file_exits_2_naming_row_and_column(tmp_path, lbr, text, where):
    obs = _write(tmp_path / "obs.csv", text)
    proc = lbr("plan", "anti-sway", "--length", L, "--a-max", 1, "--obstacles", obs, "-o", tmp_path / "x.csv")
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "obs.csv" in lines[0] and where in lines[0], lines


@pytest.mark.parametrize(
    "args, word",
    [
        (("--points", "0.4,0.1"), "--points"),
        (("--points", "0.4,0.1;0.4,0.1"), "zero length"),
        (("--shaper", "bogus"), "--shaper"),
        (("--length", "-1"), "--length"),
        (("--a-max", "0"), "--a-max"),
        (("--points", "0.4,a;0.5,0"), "--points"),
        (("--max-sway", "-2"), "--max-sway"),
        (("--max-sway", "abc"), "--max-sway"),
        (("--ball-radius", "-1"), "--ball-radius"),
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


@pytest.mark.heavy
def test_the_elbow_settles_before_the_file_ends(tmp_path):
    """The redundancy pull may still move the elbow once the pivot has stopped: the file holds the last pivot
    position until the joints are at rest (this layout's plan ended with A1 at 0.054 rad/s, refused by the check)."""
    from lbrcli.antisway import plan_anti_sway_files
    from trajectories.csvio import read_joint_csv, read_task_csv
    from trajectories.limits import default_limits

    pts = [[0.4939, -0.1612], [0.4939, -0.2763], [0.401, -0.2763]]
    out, task = tmp_path / "j.csv", tmp_path / "t.csv"
    figs = plan_anti_sway_files(pts, 0.26, 2.1136, None, "auto", 0.005, out, task_out=task)
    assert figs["fallback"] is None  # the default design itself plans
    q = read_joint_csv(out).q
    last_step = np.abs(q[-1] - q[-2])
    assert (last_step <= np.asarray(default_limits().acceleration) * 0.005**2).all()
    tt = read_task_csv(task)
    assert len(tt.position) == len(q) and np.allclose(tt.position[-1], tt.position[-2])


def test_a_layout_out_of_reach_says_where(lbr, tmp_path):
    """At z = 0.65 m the flange pointing down cannot follow the default layout's first segment: one line naming
    the place on it and the joint, before any planning."""
    proc = lbr("plan", "anti-sway", "--z", "0.65", "--length", "0.5", "--a-max", "2", "-o", tmp_path / "x.csv")
    assert proc.returncode == 1 and not (tmp_path / "x.csv").exists()
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "out of reach at z = 0.65 m" in lines[0]
    assert "segment 1 from point 0 (0.400, -0.300) to point 1 (0.620, -0.300)" in lines[0] and "A6" in lines[0]
