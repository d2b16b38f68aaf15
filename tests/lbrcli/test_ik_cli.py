"""`lbr ik` end to end: the start chosen for the whole path, joint speeds inside the limits, honest exit 1."""

import json

import numpy as np

from trajectories.csvio import read_joint_csv, write_task_csv
from trajectories.ik_paths import issue_circle, random_joint_path, verify_joint_path
from trajectories.poses import quaternions_from_matrices
from trajectories.trajectory import TaskTrajectory

from conftest import Q_START


def _write(path, file):
    write_task_csv(file, TaskTrajectory(t=path.t, position=path.position,
                                        quaternion=quaternions_from_matrices(path.rotation)))
    return file


def test_issue_circle_auto_start_reported_and_inside_the_limits(lbr, tmp_path, robot, limits):
    path = issue_circle(0.005)
    task = _write(path, tmp_path / "circle.csv")
    out = tmp_path / "q.csv"
    res = lbr("ik", task, "-o", out, "--json")
    assert res.returncode == 0, res.stderr
    figures = json.loads(res.stdout)
    assert figures["start"].startswith("auto") and len(figures["q_start_rad"]) == 7
    assert "start (auto" in res.stderr
    assert figures["peak_velocity_ratio"] <= 1.0 and figures["limits_ok"] in (True, False)
    q = read_joint_csv(out).q
    check = verify_joint_path(robot, path, q, limits)
    assert check.position_error < 1e-6 and check.rotation_error < 1e-5 and check.velocity_ratio <= 1.0 + 1e-6
    assert np.allclose(q[0], figures["q_start_rad"], atol=1e-6)


def test_too_fast_path_exits_1_naming_joint_and_speed(lbr, tmp_path, robot, limits):
    dt = 0.005
    q = random_joint_path(np.random.default_rng(5), limits, dt, 2.0, Q_START + 0.3, np.full(7, 0.3), 0.5)
    t = np.arange(len(q)) * dt
    q[:, 0] = 0.4 * np.sin(2 * np.pi * 1.5 * t)  # A1 at up to 3.8 rad/s (limit 1.71)
    pos, rot = robot.fk_path(q)
    task = tmp_path / "fast.csv"
    write_task_csv(task, TaskTrajectory(t=t, position=pos, quaternion=quaternions_from_matrices(rot)))
    q0 = ",".join(f"{v:.9f}" for v in q[0])
    res = lbr("ik", task, "-o", tmp_path / "q.csv", "--q0", q0)
    assert res.returncode == 1
    lines = [l for l in res.stderr.splitlines() if l.strip()]
    assert len(lines) == 1 and "Traceback" not in res.stderr
    assert "rad/s, above its limit" in lines[0] and "pose " in lines[0]


def test_bad_nullspace_rate_is_exit_2(lbr, tmp_path):
    path = issue_circle(0.05)
    task = _write(path, tmp_path / "c.csv")
    res = lbr("ik", task, "-o", tmp_path / "q.csv", "--nullspace-rate", "-1")
    assert res.returncode == 2 and "--nullspace-rate" in res.stderr


def test_smooth_keeps_the_arm_angle_plan_when_its_accelerations_are_lower(lbr, tmp_path, robot, limits):
    """A fast FK-built 5 ms path whose locally resolved output reaches ≈ 26× the acceleration limit: --smooth
    compares it with the whole-path arm-angle plan's path and keeps that (≈ 2×), speeds still inside the limits."""
    from trajectories.ik_paths import build_suite

    path = next(p for p in build_suite(robot, limits) if p.name == "joint-c5-v0.9-5ms")
    task = _write(path, tmp_path / "fast.csv")
    plain = json.loads(lbr("ik", task, "-o", tmp_path / "a.csv", "--json").stdout)
    res = lbr("ik", task, "-o", tmp_path / "b.csv", "--json", "--smooth")
    assert res.returncode == 0, res.stderr
    smooth = json.loads(res.stdout)
    assert plain["peak_acceleration_ratio"] > 5.0
    assert smooth["peak_acceleration_ratio"] < 0.5 * plain["peak_acceleration_ratio"]
    assert "arm-angle plan" in smooth["start"] and smooth["peak_velocity_ratio"] <= 1.0
    check = verify_joint_path(robot, path, read_joint_csv(tmp_path / "b.csv").q, limits)
    assert check.ok(1e-6, 1e-5)
    assert abs(check.acceleration_ratio - smooth["peak_acceleration_ratio"]) < 0.05 * smooth["peak_acceleration_ratio"]
