import pytest

"""`lbr ik` end to end: the start chosen for the whole path, joint speeds inside the limits, honest exit 1."""

import json

import numpy as np

from trajectories.csvio import read_joint_csv, write_task_csv
from trajectories.ik_paths import issue_circle, random_joint_path, verify_joint_path
from trajectories.poses import quaternions_from_matrices
from trajectories.trajectory import TaskTrajectory

from tests.helpers.cli import Q_START


def _write(path, file):
    write_task_csv(
        file, TaskTrajectory(t=path.t, position=path.position, quaternion=quaternions_from_matrices(path.rotation))
    )
    return file


@pytest.mark.heavy
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


@pytest.mark.heavy
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
    # A1 is not set by the poses: a fact of the path from that start, and the automatic start is suggested
    assert "the path from the start given (--q0)" in lines[0] and "without --q0" in lines[0]


def test_bad_nullspace_rate_is_exit_2(lbr, tmp_path):
    path = issue_circle(0.05)
    task = _write(path, tmp_path / "c.csv")
    res = lbr("ik", task, "-o", tmp_path / "q.csv", "--nullspace-rate", "-1")
    assert res.returncode == 2 and "--nullspace-rate" in res.stderr


@pytest.mark.heavy
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


@pytest.mark.heavy
def test_pen_line_at_rest_passes_lbr_check_and_says_so(lbr, tmp_path, robot, limits):
    """`lbr ik T.csv -o q.csv --tool 0,0,0.1 && lbr check q.csv`: a rest-to-rest line (flange yawing 90°) drawn
    with a 10 cm pen — the file starts and ends at rest and passes the check; --json says so with its figures."""
    from trajectories.ik_paths import cartesian_path
    from trajectories.robot import Robot, RobotConfig

    pen = Robot(RobotConfig(tool=(0.0, 0.0, 0.1)))
    line = cartesian_path("line", 0.002, center=(0.4, -0.2, 0.45), size=0.2, plane="yz", timing="smooth",
                          yaw_deg=90, duration=6.0)  # fmt: skip
    task = _write(line, tmp_path / "line.csv")  # the poses are the pen tip's
    out = tmp_path / "q.csv"
    res = lbr("ik", task, "-o", out, "--tool", "0,0,0.1", "--json")
    assert res.returncode == 0, res.stderr
    figures = json.loads(res.stdout)
    assert figures["rest_at_ends"] is True and figures["task_at_rest"] == {"start": True, "end": True}
    assert figures["limits_ok"] is True and not [v for v in figures["check"]["violations"] if v["fails"]]
    assert figures["check"]["max_ratio"]["acceleration"] <= 1.0 and figures["jerk_ratio"] > 0
    assert lbr("check", out).returncode == 0
    pos, _ = pen.fk_path(read_joint_csv(out).q)
    assert np.abs(pos - line.position).max() < 1e-6


def test_refusal_names_the_first_unreachable_pose_in_json(lbr, tmp_path):
    from trajectories.ik_paths import move_path

    path = move_path("out", 0.005, 3.0, (0.5, 0.0, 0.3), (1.0, 0.0, 0.3))  # flange down, outward beyond reach
    task = _write(path, tmp_path / "out.csv")
    res = lbr("ik", task, "-o", tmp_path / "q.csv", "--json")
    assert res.returncode == 1 and not (tmp_path / "q.csv").exists()
    figures = json.loads(res.stdout)
    refusal = figures["refusal"]
    assert refusal["kind"] in ("pose", "path") and refusal["index"] > 0
    assert abs(refusal["t_s"] - path.t[refusal["index"]]) < 1e-9
    lines = [l for l in res.stderr.splitlines() if l.strip()]
    assert len(lines) == 1 and f"pose {refusal['index']} " in lines[0] and "cannot be reached" in lines[0]
