"""The foundation commands end to end, as a user runs them: fk, ik, check, retime, errors and exit codes."""

import json

import numpy as np
import pytest

from trajectories.csvio import read_joint_csv, read_task_csv, write_joint_csv, write_task_csv
from trajectories.poses import quaternions_from_matrices
from trajectories.trajectory import JointTrajectory, TaskTrajectory

from tests.helpers.cli import Q_START
from tests.helpers.cli import one_line_error


@pytest.fixture
def slow_csv(tmp_path):
    h = 0.005
    t = np.arange(0, 2.0 + h / 2, h)
    q = Q_START + np.outer(0.5 - 0.5 * np.cos(np.pi * t / 2), [0.3, 0.2, 0.1, 0.3, 0.2, 0.2, 0.4])
    p = tmp_path / "slow.csv"
    write_joint_csv(p, JointTrajectory(t=t, q=q))
    return p


def test_help_lists_commands(lbr):
    res = lbr("--help")
    assert res.returncode == 0
    for cmd in ("fk", "ik", "check", "retime", "plan", "track"):
        assert cmd in res.stdout


def test_check_ok_json(lbr, slow_csv):
    res = lbr("check", slow_csv, "--json")
    assert res.returncode == 0, res.stderr
    figures = json.loads(res.stdout)
    assert figures["limits_ok"] is True and figures["samples"] == 401
    assert 0 < figures["max_ratio"]["velocity"] < 1


@pytest.mark.heavy
def test_check_violation_exit_1_names_joint(lbr, tmp_path):
    h = 0.005
    t = np.arange(0, 1.0, h)
    q = Q_START + np.outer(np.sin(2 * np.pi * t), [0.5, 0, 0, 0, 0, 0, 0])  # A1 3.1 rad/s > 1.71
    p = tmp_path / "fast.csv"
    write_joint_csv(p, JointTrajectory(t=t, q=q))
    res = lbr("check", p, "--plot", tmp_path / "c.png")
    assert res.returncode == 1
    assert "A1 velocity" in res.stdout and "exceeds the limit 1.71 rad/s" in res.stdout
    assert (tmp_path / "c.png").stat().st_size > 10_000


def test_check_t1(lbr, slow_csv):
    res = lbr("check", slow_csv, "--t1", "--json")
    figures = json.loads(res.stdout)
    assert "cartesian_speed_peak_m_s" in figures
    assert res.returncode == (0 if figures["cartesian_speed_peak_m_s"] <= 0.25 else 1)


def test_fk_ik_round_trip_cli(lbr, slow_csv, tmp_path):
    task = tmp_path / "task.csv"
    assert lbr("fk", slow_csv, "-o", task).returncode == 0
    back = tmp_path / "back.csv"
    res = lbr("ik", task, "-o", back, "--q0", ",".join(f"{np.degrees(x):.6f}deg" for x in Q_START), "--json")
    assert res.returncode == 0, res.stderr
    figures = json.loads(res.stdout)
    assert figures["max_position_error_m"] < 1e-6 and figures["max_rotation_error_rad"] < 1e-5
    # the same poses (the redundant elbow may differ from the original path: it is pulled toward --q0)
    from trajectories.robot import Robot

    pos, _ = Robot().fk_path(read_joint_csv(back).q)
    assert np.abs(pos - read_task_csv(task).position).max() < 1e-6


def test_ik_unreachable_exit_1(lbr, tmp_path, robot):
    M = robot.fk(Q_START)
    n = 20
    pos = np.tile(M.translation, (n, 1))
    pos[10:, 0] += 1.5
    quat = quaternions_from_matrices(np.tile(M.rotation, (n, 1, 1)))
    task = tmp_path / "far.csv"
    write_task_csv(task, TaskTrajectory(t=np.arange(n) * 0.01, position=pos, quaternion=quat))
    line = one_line_error(lbr("ik", task, "-o", tmp_path / "j.csv"), code=1)
    assert "pose 10 " in line and "out of reach by" in line and " mm" in line


def test_retime_cli(lbr, tmp_path):
    h = 0.005
    s = 0.5 - 0.5 * np.cos(np.pi * np.linspace(0, 1, 201))
    q = Q_START + np.outer(s, [1.5, 0.5, 0.5, 0.5, 0.5, 0.5, 1.0])
    p = tmp_path / "fast.csv"
    write_joint_csv(p, JointTrajectory.from_samples(q, h))
    assert lbr("check", p).returncode == 1
    out = tmp_path / "re.csv"
    res = lbr("retime", p, "-o", out, "--json")
    assert res.returncode == 0, res.stderr
    assert json.loads(res.stdout)["duration_s"] > 1.0
    assert lbr("check", out).returncode == 0
    assert "anti-sway" in lbr("retime", "--help").stdout


@pytest.mark.parametrize(
    "args, words",
    [
        (["check", "{missing}"], "file not found"),
        (["check", "{bad}"], "row 3, column 4 (q3): not a number"),
        (["check", "{slow}", "--margin", "1.5"], "--margin must be in [0, 1)"),
        (["ik", "{slow}", "-o", "{out}"], "expected 'x'"),
        (
            ["fk", "{slow}", "-o", "{out}", "--flange", "huge"],
            "--flange must be one of touch-electric, standard, touch-pneumatic, got 'huge'",
        ),
        (["fk", "{slow}", "-o", "{out}", "--tool", "0,0"], "--tool"),
        (["ik", "{task}", "-o", "{out}", "--q0", "0,0,0,0,0,0,abc"], "--q0: not an angle"),
        (["check", "{slow}", "--limits", "{missing}"], "limits file not found"),
        (["check", "{headerless}"], "--dt"),
    ],
)
def test_bad_input_is_one_line_exit_2(lbr, tmp_path, slow_csv, args, words):
    bad = tmp_path / "bad.csv"
    bad.write_text("t,q1,q2,q3,q4,q5,q6,q7\n0,0,0,0,0,0,0,0\n0.005,0,0,x,0,0,0,0\n")
    headerless = tmp_path / "hl.csv"
    headerless.write_text("0,0,0,0,0,0,0\n" * 3)
    task = tmp_path / "task.csv"
    task.write_text("t,x,y,z,qw,qx,qy,qz\n0,0.5,0,0.8,1,0,0,0\n")
    names = dict(
        missing=tmp_path / "nope.csv", bad=bad, slow=slow_csv, out=tmp_path / "o.csv", task=task, headerless=headerless
    )
    line = one_line_error(lbr(*[a.format(**names) for a in args]))
    assert words in line


def test_headerless_with_dt(lbr, tmp_path):
    p = tmp_path / "hl.csv"
    p.write_text("".join(",".join(f"{x:.6f}" for x in Q_START) + "\n" for _ in range(5)))
    res = lbr("check", p, "--dt", "0.005", "--json")
    assert res.returncode == 0 and json.loads(res.stdout)["duration_s"] == pytest.approx(0.02)


@pytest.mark.heavy
@pytest.mark.parametrize(
    "args",
    [
        ["fk", "{slow}", "-o", "{bad}"],
        ["check", "{slow}", "--plot", "{badpng}"],
        ["check", "{slow}", "--plot", "{csvplot}"],
        ["retime", "{slow}", "-o", "{bad}"],
        ["plan", "anti-sway", "--length", "0.25", "--a-max", "1", "-o", "{bad}"],
        [
            "plan",
            "swing-up",
            "--length",
            "0.25",
            "--mass",
            "0.01",
            "--theta-d",
            "60deg",
            "--theta0",
            "0.1",
            "-o",
            "{bad}",
        ],
        ["plan", "anti-sway", "--length", "0.25", "--a-max", "1", "-o", "{folder}"],
    ],
)
def test_unwritable_output_is_one_line_exit_2(lbr, tmp_path, slow_csv, args):
    names = dict(
        slow=slow_csv,
        bad=tmp_path / "missing" / "out.csv",
        folder=tmp_path,
        csvplot=tmp_path / "plot.csv",
        badpng=tmp_path / "missing" / "plot.png",
    )
    line = one_line_error(lbr(*[a.format(**names) for a in args]))
    assert line.startswith("lbr: error: ") and str(tmp_path) in line
    assert any(w in line for w in ("No such file or directory", "Is a directory", "not an image format"))
