"""Output safety and error contract across commands: inputs never overwritten, one-line errors (exit 2),
--json error objects, validated numeric options, exit 1 when a command did not do what was asked, Ctrl-C → 130.

Most cases run `lbrcli.app.main` in-process (the same code path as the `lbr` script, without a Python start-up
per case); Ctrl-C and the MQTT listener run as real processes.
"""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import lbrcli.console
from lbrcli.app import main
from trajectories.csvio import write_joint_csv
from trajectories.trajectory import JointTrajectory

from tests.helpers.cli import Q_START


def run(capsys, *argv):
    """(exit code, stdout, stderr) of `lbr ARGV` in this process."""
    lbrcli.console._emitted = False
    code = 0
    try:
        main([str(a) for a in argv])
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    out, err = capsys.readouterr()
    return code, out, err


def one_line(err):
    lines = [l for l in err.splitlines() if l.strip()]
    assert len(lines) == 1 and lines[0].startswith("lbr: error: "), err
    assert "Traceback" not in err
    return lines[0]


@pytest.fixture
def joint_csv(tmp_path):
    h = 0.01
    t = np.arange(0, 1.0 + h / 2, h)
    q = Q_START + np.outer(0.5 - 0.5 * np.cos(np.pi * t), [0.2, 0.1, 0.1, 0.2, 0.1, 0.1, 0.2])
    p = tmp_path / "move.csv"
    write_joint_csv(p, JointTrajectory(t=t, q=q))
    return p


# -- never overwrite an input ------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "argv",
    [
        ("fk", "{in}", "-o", "{in}"),
        ("retime", "{in}", "-o", "{in}"),
        ("check", "{in}", "--plot", "{in}"),
        ("fk", "{in}", "-o", "{same}"),  # the same file by another spelling
        # commands without their own guard are covered centrally (lbrcli.outputs.guarded, applied in app.py)
        ("execute", "{in}", "--log", "{in}"),
        ("track", "video", "{in}", "-o", "{other}", "--preview", "{in}"),
        ("track", "video", "{in}", "-o", "{in}"),
        ("compare", "{other}", "{in}", "--plot", "{in}"),
        ("ik", "{in}", "-o", "{same}"),
        ("plan", "anti-sway", "--length", "0.25", "--a-max", "2", "-o", "{other}", "--prediction", "{other}"),
    ],
)
def test_an_output_that_is_the_input_is_refused_and_the_input_kept(capsys, joint_csv, argv):
    before = joint_csv.read_bytes()
    same = joint_csv.parent / "." / joint_csv.name
    other = joint_csv.parent / "other.csv"
    code, out, err = run(capsys, *(a.format(**{"in": joint_csv, "same": same, "other": other}) for a in argv))
    line = one_line(err)
    assert code == 2 and (
        "refusing to overwrite an input" in line
        and joint_csv.name in line
        or "are the same file" in line
        and other.name in line
    )
    assert joint_csv.read_bytes() == before


@pytest.fixture
def no_planning(monkeypatch):
    """Fail the test if the swing-up planner runs: bad options must be refused before any work."""
    import planners.swingup

    def planner(*args, **kwargs):
        raise AssertionError("the planner ran although the options are bad")

    monkeypatch.setattr(planners.swingup, "plan_swing_up", planner)


def test_two_outputs_on_one_file_are_refused_before_planning(capsys, tmp_path, no_planning):
    code, _, err = run(
        capsys,
        "plan",
        "swing-up",
        "--length",
        "0.25",
        "--mass",
        "0.0139",
        "--theta-d",
        "115deg",
        "--theta0",
        "0.1",
        "-o",
        tmp_path / "f.csv",
        "--prediction",
        tmp_path / "f.csv",
    )
    assert code == 2 and "are the same file" in one_line(err)
    assert not (tmp_path / "f.csv").exists()


def test_fk_writes_through_a_temporary_name(capsys, joint_csv, tmp_path):
    out = tmp_path / "task.csv"
    code, _, err = run(capsys, "fk", joint_csv, "-o", out)
    assert code == 0, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["move.csv", "task.csv"]


# -- usage errors, --json, --version ------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "argv, words",
    [
        (("check",), "Missing argument"),
        (("check", "x.csv", "--bogus"), "No such option"),
        (("chek",), "No such command 'chek'"),
        (("check", "x.csv", "--margin", "lots"), "--margin"),
        (("plan", "swing-up", "--length", "0.25"), "Missing option"),
    ],
)
def test_usage_errors_are_one_line_exit_2(capsys, argv, words):
    code, out, err = run(capsys, *argv)
    line = one_line(err)
    assert code == 2 and words in line and "--help" in line


def test_json_errors_are_one_object_on_stdout(capsys, tmp_path):
    code, out, err = run(capsys, "check", tmp_path / "nope.csv", "--json")
    assert code == 2
    obj = json.loads(out)
    assert obj["ok"] is False and obj["exit_code"] == 2 and "file not found" in obj["error"]
    assert obj["file"] == str(tmp_path / "nope.csv")
    code, out, err = run(capsys, "check", "--json")  # a usage error too
    assert code == 2 and json.loads(out)["exit_code"] == 2


def test_json_after_figures_adds_no_second_object(capsys, tmp_path):
    h = 0.005
    t = np.arange(0, 1.0, h)
    p = tmp_path / "fast.csv"
    write_joint_csv(p, JointTrajectory(t=t, q=Q_START + np.outer(np.sin(2 * np.pi * t), [0.5, 0, 0, 0, 0, 0, 0])))
    code, out, err = run(capsys, "check", p, "--json")
    assert code == 1
    assert len(out.strip().splitlines()) == 1 and json.loads(out)["limits_ok"] is False


def test_version(capsys):
    code, out, _ = run(capsys, "--version")
    assert code == 0 and out.startswith("lbr ") and len(out.split()) == 2


def test_shell_completion_is_on(capsys, monkeypatch):
    code, out, _ = run(capsys, "--help")
    assert code == 0 and "--install-completion" in out
    monkeypatch.setenv("_LBR_COMPLETE", "complete_bash")  # what the installed bash completion script sets
    monkeypatch.setenv("COMP_WORDS", "lbr plan swing-up --me")
    monkeypatch.setenv("COMP_CWORD", "3")
    code, out, _ = run(capsys)
    assert code == 0 and out.split() == ["--method"]


# -- numeric options -----------------------------------------------------------------------------------------------
SWING = ("plan", "swing-up", "--length", "0.25", "--mass", "0.0139", "--theta-d", "115deg", "--theta0", "0.1")


@pytest.mark.parametrize(
    "extra, option",
    [
        (("--push", "1e6"), "--push"),
        (("--push", "nan"), "--push"),
        (("--dt", "1e-9"), "--dt"),
        (("--dt", "nan"), "--dt"),
        (("--duration", "1e9"), "--duration"),
        (("--duration", "-1"), "--duration"),
        (("--ke", "inf"), "--ke"),
        (("--workers", "0"), "--workers"),
        (("--margin", "nan"), "--margin"),
    ],
)
def test_swing_up_numeric_options_are_validated(capsys, tmp_path, no_planning, extra, option):
    code, _, err = run(capsys, *SWING, *extra, "-o", tmp_path / "s.csv")
    line = one_line(err)
    assert code == 2 and option in line and "must be" in line


def test_swing_up_length_nan(capsys, tmp_path):
    argv = list(SWING)
    argv[argv.index("--length") + 1] = "nan"
    code, _, err = run(capsys, *argv, "-o", tmp_path / "s.csv")
    assert code == 2 and "--length must be in [0.01, 5] m, got nan" in one_line(err)


@pytest.mark.parametrize("argv", [("--step", "nan"), ("--step", "0"), ("--step", "1e-9"), ("--margin", "-0.1")])
def test_retime_numeric_options(capsys, joint_csv, tmp_path, argv):
    code, _, err = run(capsys, "retime", joint_csv, "-o", tmp_path / "r.csv", *argv)
    assert code == 2 and argv[0] in one_line(err)


def test_headerless_dt_must_be_finite(capsys, tmp_path):
    p = tmp_path / "h.csv"
    p.write_text("0.1,0.2,0.3,-1.0,0.5,0.6,0.7\n" * 3)
    for bad in ("nan", "inf", "0"):
        code, _, err = run(capsys, "fk", p, "-o", tmp_path / "t.csv", "--dt", bad)
        assert code == 2 and "--dt" in one_line(err)


# -- retime: never a file outside the limits -----------------------------------------------------------------------
def test_retime_output_passes_central_and_forward_difference_checks(capsys, tmp_path, limits):
    from trajectories.check import check_trajectory, step_ratios
    from trajectories.csvio import read_joint_csv

    rng = np.random.default_rng(0)  # sharp corners: the samples of toppra's spline overshoot at the first attempt
    q = Q_START + np.cumsum(rng.normal(scale=0.3, size=(10, 7)), axis=0)
    q = np.clip(q, -0.9 * limits.position, 0.9 * limits.position)
    src = tmp_path / "corners.csv"
    write_joint_csv(src, JointTrajectory.from_samples(q, 0.01))
    out = tmp_path / "r.csv"
    code, stdout, err = run(capsys, "retime", src, "-o", out, "--step", "0.005", "--margin", "0", "--json")
    assert code == 0, err
    figures = json.loads(stdout)
    traj = read_joint_csv(out)
    assert check_trajectory(traj, limits).ok
    assert max(step_ratios(traj, limits).values()) <= 1.0
    assert figures["ratios"]["acceleration"] <= 1.0 and figures["attempts"] >= 1


def test_retime_refuses_a_path_outside_the_position_limits_and_writes_nothing(capsys, tmp_path, limits):
    q = np.tile(Q_START, (5, 1))
    q[:, 0] = np.linspace(0, limits.position[0] + 0.1, 5)
    src = tmp_path / "far.csv"
    write_joint_csv(src, JointTrajectory.from_samples(q, 0.01))
    code, _, err = run(capsys, "retime", src, "-o", tmp_path / "r.csv")
    line = one_line(err)
    assert code == 1 and "position limit of A1" in line and "nothing written" in line
    assert not (tmp_path / "r.csv").exists()


# -- exit 1 when nothing was done ----------------------------------------------------------------------------------
@pytest.mark.heavy
def test_listen_with_no_broker_exits_1_and_records_nothing(capsys, tmp_path):
    rec = tmp_path / "rec.jsonl"
    code, out, err = run(capsys, "listen", "mqtt://127.0.0.1:9/lbr", "--connect-timeout", "0.5", "-o", rec, "--json")
    assert code == 1 and "could not reach the MQTT broker 127.0.0.1:9" in err
    assert json.loads(out)["connected"] is False
    assert list(tmp_path.iterdir()) == []


@pytest.mark.heavy
def test_listen_with_nothing_published_exits_1(capsys, broker):
    url = f"mqtt://{broker.host}:{broker.port}/{broker.topic}"
    code, out, err = run(capsys, "listen", url, "--duration", "1", "--json")
    assert code == 1 and "nothing received" in err
    assert json.loads(out)["connected"] is True


@pytest.mark.parametrize("argv", [("--duration", "nan"), ("--count", "0"), ("--connect-timeout", "-1")])
def test_listen_numeric_options(capsys, argv):
    code, _, err = run(capsys, "listen", "mqtt://127.0.0.1:9/x", *argv)
    assert code == 2 and argv[0] in one_line(err)


# -- Ctrl-C --------------------------------------------------------------------------------------------------------
@pytest.mark.heavy
def test_ctrl_c_ends_the_fast_swing_up_and_its_workers_within_a_second(tmp_path):
    """SIGINT to the whole process group, as a terminal sends it: exit 130, one line, no worker tracebacks."""
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "lbrcli",
            "plan",
            "swing-up",
            "--method",
            "fast",
            "--length",
            "0.25",
            "--mass",
            "0.0139",
            "--theta-d",
            "115deg",
            "-o",
            str(tmp_path / "s.csv"),
            "--json",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    time.sleep(2.5)  # inside the differential evolution (≈ 3 s with 2 workers)
    t0 = time.monotonic()
    os.killpg(proc.pid, signal.SIGINT)
    out, err = proc.communicate(timeout=20)
    elapsed = time.monotonic() - t0
    if proc.returncode == 0 or "wrote" in err:  # done and written: the interrupt hit the interpreter's exit
        pytest.skip("the plan finished before the interrupt (very fast machine)")
    assert proc.returncode == 130 and elapsed < 5.0, (elapsed, err)  # goal 1 s: 0.5–0.6 s measured at load 13
    assert err.strip().splitlines() == ["lbr: interrupted"]
    assert json.loads(out) == {"ok": False, "exit_code": 130, "error": "interrupted"}
    assert not (tmp_path / "s.csv").exists()
    time.sleep(0.2)
    with pytest.raises(ProcessLookupError):
        os.killpg(proc.pid, 0)  # no worker left in the group


def _mapped(pid: int, name: str) -> bool:
    try:
        with open(f"/proc/{pid}/maps") as f:
            return name in f.read()
    except OSError:
        return False


@pytest.mark.heavy
@pytest.mark.parametrize("library", ["_multiarray_umath", "pinocchio_pywrap"])
def test_ctrl_c_while_python_imports_the_app_is_one_line_and_130(tmp_path, library):
    """A Ctrl-C that lands while the interpreter still imports numpy (the app's import) or pinocchio (inside the
    command) ends like any other: exit 130, one line, no traceback, the --json object."""
    if not os.path.exists("/proc/self/maps"):
        pytest.skip("needs /proc to see which libraries the process has loaded")
    proc = subprocess.Popen(
        [sys.executable, "-m", "lbrcli", "check", str(tmp_path / "missing.csv"), "--json"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    deadline = time.monotonic() + 60
    while not _mapped(proc.pid, library) and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.002)
    os.killpg(proc.pid, signal.SIGINT)
    out, err = proc.communicate(timeout=20)
    if proc.returncode == 2 and "missing.csv" in err:
        pytest.skip(f"the command ended before the interrupt ({library} loaded after the check)")
    assert proc.returncode == 130, err
    assert err.strip().splitlines() == ["lbr: interrupted"]
    assert json.loads(out) == {"ok": False, "exit_code": 130, "error": "interrupted"}
