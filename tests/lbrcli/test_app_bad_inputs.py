"""The bad-input campaign (issue #34): every command, fed what users and adversaries feed it.

Bad option values (generated from each option's own parser, so no option escapes), bad CSV, TOML, JSON, obstacle,
video and image files, devices, FIFOs, outputs onto links, devices and FIFOs, and full disks (RLIMIT_FSIZE, and a
tiny tmpfs when this process may mount one). For each case: no traceback and no "internal error", the expected exit
code (2 bad input, 1 a job that could not be done; never a silent 0), one "lbr:" line on stderr naming the option,
file, row and column where they apply, no output left in the case's folder, no input touched, links/FIFOs/devices
left as they were. Runs `lbrcli.app.main` in-process (the code path of the `lbr` script without a Python start-up
per case): ≈ 800 cases.
"""

from __future__ import annotations

import contextlib
import os
import resource
import stat
import subprocess
import typing
from pathlib import Path

import numpy as np
import pytest

from tests.helpers.cli import Q_START, run_in_process

# ---------------------------------------------------------------- running a command in-process


run = run_in_process  # `lbr ARGV` in this process: (exit code, stdout, stderr)


def error_line(code: int, err: str, expected: int) -> str:
    """The one "lbr:" line of a failed command (warnings before it allowed), after the contract's checks."""
    assert "Traceback" not in err and "internal error" not in err, err
    assert code == expected, (code, err)
    lines = [line for line in err.splitlines() if line.strip()]
    lbr_lines = [line for line in lines if line.startswith("lbr:")]
    others = [line for line in lines if not line.startswith(("lbr:", "warning:"))]
    assert len(lbr_lines) == 1 and lines[-1] == lbr_lines[0] and not others, err
    return lbr_lines[0]


def snapshot(folder: Path) -> dict[str, tuple]:
    """Every entry under ``folder`` (links not followed): what it is, its size, content time and inode."""
    out = {}
    for root, dirs, files in os.walk(folder):
        for name in dirs + files:
            p = Path(root) / name
            st = os.lstat(p)
            out[str(p.relative_to(folder))] = (stat.S_IFMT(st.st_mode), st.st_size, st.st_mtime_ns, st.st_ino)
    return out


# ---------------------------------------------------------------- the workspace of good inputs


def _joint(h=0.005, duration=1.0):
    from trajectories.trajectory import JointTrajectory

    t = np.arange(0, duration + h / 2, h)
    s = 0.5 - 0.5 * np.cos(np.pi * t / duration)
    return JointTrajectory(t=t, q=Q_START + np.outer(s, [0.05, 0.04, 0.03, 0.05, 0.04, 0.04, 0.05]))


def _log(path: Path, complete: bool = True, ball: bool = True) -> None:
    """A small execution log as `lbr execute` writes it (columns of lbrcli.fri.log, file_rows, the ball)."""
    from lbrcli.fri.log import CONTROL_COLUMNS, LOG_COLUMNS, PHASE_SETTLE, PHASE_TRAJECTORY
    from trajectories.csvio import write_table

    n_wait, n_rows, n_settle = 10, 100, 10
    rows = n_rows if complete else 40
    n = n_wait + rows + (n_settle if complete else 0)
    names = list(LOG_COLUMNS + CONTROL_COLUMNS) + ["file_rows"] + (["ball_theta_y"] if ball else [])
    data = np.zeros((n, len(names)))
    col = {name: k for k, name in enumerate(names)}
    data[:, col["t"]] = np.arange(n) * 0.005
    data[:, col["state"]] = 4
    for i in range(7):
        data[:, col[f"msr_q{i + 1}"]] = Q_START[i]
        data[:, col[f"cmd_q{i + 1}"]] = Q_START[i]
    data[:, col["row"]] = -1
    data[n_wait : n_wait + rows, col["phase"]] = PHASE_TRAJECTORY
    data[n_wait : n_wait + rows, col["row"]] = np.arange(rows)
    data[n_wait + rows :, col["phase"]] = PHASE_SETTLE
    data[:, col["file_rows"]] = n_rows
    if ball:
        data[:, col["ball_theta_y"]] = 0.1 * np.sin(2 * np.pi * data[:, col["t"]])
    write_table(path, names, data)


@pytest.fixture(scope="module")
def ws(tmp_path_factory):
    """Good inputs every case starts from (never modified: checked after each case)."""
    from trajectories.csvio import write_joint_csv, write_table, write_task_csv
    from trajectories.poses import quaternions_from_matrices
    from trajectories.robot import Robot
    from trajectories.trajectory import TaskTrajectory
    from tracking.synthetic import render_pendulum_video

    d = tmp_path_factory.mktemp("ws")
    traj = _joint()
    write_joint_csv(d / "joint.csv", traj)
    pos, rot = Robot().fk_path(traj.q)
    write_task_csv(d / "task.csv", TaskTrajectory(t=traj.t, position=pos, quaternion=quaternions_from_matrices(rot)))
    t = np.arange(0, 4.0, 0.01)
    write_table(d / "pred.csv", ("t", "theta"), np.column_stack([t, 0.2 * np.sin(2 * np.pi * t)]))
    tt = np.arange(0, 4.0, 1 / 60)
    th = 0.2 * np.sin(2 * np.pi * tt)
    write_table(
        d / "track.csv",
        ("t", "frame", "u", "v", "found", "theta"),
        np.column_stack([tt, np.arange(len(tt)), 100 + 50 * th, 200 + 0 * tt, 1 + 0 * tt, th]),
    )
    _log(d / "log.csv")
    _log(d / "stopped.csv", complete=False)
    _log(d / "noball.csv", ball=False)
    (d / "limits.toml").write_text("velocity_deg_s = [98, 98, 100, 130, 140, 180, 180]\n")
    (d / "obstacles.csv").write_text("name,x_min,y_min,z_min,x_max,y_max,z_max\npost,0.5,-0.2,0,0.55,-0.15,0.25\n")
    (d / "secret.txt").write_text("0123456789abcdef0123\n")
    (d / "study.toml").write_text('[study]\nkind = "probe"\n[vary]\nvalue = [1]\n')
    tv = np.arange(0, 2.0, 1 / 60)
    render_pendulum_video(d / "video.mp4", tv, 0.3 * np.sin(2 * np.pi * tv), (160, 40), 120, 8, size=(320, 240),
                          fps=60, pivot_marker="green")  # fmt: skip
    import cv2

    cv2.imwrite(str(d / "noise.png"), np.random.default_rng(0).integers(0, 255, (120, 160, 3), dtype=np.uint8))
    return d


@pytest.fixture
def guarded_ws(ws):
    """The workspace, checked to be unchanged after the case."""
    before = snapshot(ws)
    yield ws
    assert snapshot(ws) == before, "an input of the workspace was changed"


# ---------------------------------------------------------------- every command, with valid required arguments

BASE = {
    "fk": ["fk", "{ws}/joint.csv", "-o", "{out}/t.csv"],
    "ik": ["ik", "{ws}/task.csv", "-o", "{out}/j.csv"],
    "check": ["check", "{ws}/joint.csv"],
    "retime": ["retime", "{ws}/joint.csv", "-o", "{out}/r.csv"],
    "compare": ["compare", "{ws}/pred.csv", "{ws}/track.csv"],
    "plan anti-sway": ["plan", "anti-sway", "-o", "{out}/a.csv", "--length", "0.25", "--a-max", "2"],
    "plan swing-up": [
        "plan",
        "swing-up",
        "-o",
        "{out}/s.csv",
        "--length",
        "0.25",
        "--mass",
        "0.0139",
        "--theta-d",
        "115deg",
    ],
    "plan cup-and-ball": ["plan", "cup-and-ball", "-o", "{out}/c.csv", "--length", "0.25"],
    "execute": ["execute", "{ws}/joint.csv"],
    "monitor": ["monitor", "--duration", "1"],
    "ptp": ["ptp", ",".join(map(str, Q_START)), "--time", "1"],
    "sim": ["sim"],
    "serve": ["serve"],
    "listen": ["listen", "mqtt://127.0.0.1:1/x"],
    "track video": ["track", "video", "{ws}/video.mp4", "-o", "{out}/tr.csv"],
    "track calibrate": ["track", "calibrate", "{ws}/noise.png", "-o", "{out}/cal.json"],
    "track film": ["track", "film", "{ws}/log.csv", "-o", "{out}/f.mp4"],
    "track live": ["track", "live", "{ws}/video.mp4", "--duration", "1"],
    "demo": ["demo", "--out", "{out}/demo"],
    "control upright": ["control", "upright"],
    "control damp": ["control", "damp", "{ws}/joint.csv"],
    "view": ["view", "{ws}/joint.csv", "-o", "{out}/v.html"],
    "export": ["export", "{ws}/log.csv", "-o", "{out}/r.mcap"],
    "sweep": ["sweep", "{ws}/study.toml", "-o", "{out}/res", "--scheduler", "inline"],
}


def argv_of(command: str, ws: Path, out: Path, *extra) -> list[str]:
    return [a.format(ws=ws, out=out) for a in BASE[command]] + [str(e) for e in extra]


def _commands():
    """(name, function) of every command of the app."""
    from lbrcli.app import app, groups

    found = []
    for prefix, typer_app in [("", app)] + [(f"{g} ", t) for g, t in groups.items()]:
        for cmd in typer_app.registered_commands:
            found.append((prefix + (cmd.name or cmd.callback.__name__), cmd.callback))
    return found


def _value_options(fn):
    """(option name, ParameterInfo, base type) of every option and argument of a command function."""
    import typer.models

    hints = typing.get_type_hints(fn, include_extras=True)
    for name, hint in hints.items():
        if typing.get_origin(hint) is not typing.Annotated:
            continue
        base, *meta = typing.get_args(hint)
        inner = [a for a in typing.get_args(base) if a is not type(None)] or [base]
        for m in meta:
            if isinstance(m, typer.models.ParameterInfo):
                first = (m.default,) if isinstance(m.default, str) else ()  # typer.Option("--x", ...) in Annotated
                decls = [d for d in (*first, *(m.param_decls or ())) if d.startswith("-")]
                shown = max(decls, key=len) if decls else None
                yield shown, m, inner[0]


def test_the_campaign_covers_every_command():
    assert sorted(name for name, _ in _commands()) == sorted(BASE)


@pytest.mark.heavy
def test_every_numeric_option_is_validated_by_the_shared_parsers():
    """No int or float option of any command escapes lbrcli.options (one mechanism, at parse time), and every
    option's help shows a metavar a user can read (no '<list[str]>')."""
    from lbrcli.options import Angle, Number

    missing = []
    for command, fn in _commands():
        for shown, info, base in _value_options(fn):
            if base in (int, float) and not isinstance(info.parser, (Number, Angle)):
                missing.append(f"{command} {shown}")
    assert not missing, missing
    for command, _ in _commands():
        code, out, err = run([*command.split(), "--help"])
        assert code == 0 and "list[str]" not in out and "<tuple>" not in out and "ndarray" not in out, (command, out)


# ---------------------------------------------------------------- bad option values, from each option's parser


def _bad_values(parser) -> list[str]:
    """Values the parser must refuse: syntax, non-finite, out of range, wrong shape."""
    from lbrcli.fri_options import parse_ip
    from lbrcli.options import Angle, Choice, Floats, Grid, Joints, Number, Points

    if isinstance(parser, Number):
        vals = ["nan", "inf", "-inf", "", "abc", "1_0", "0x10", "1e400", "１"]
        if parser.integer:
            vals += ["1.5", "1e3"]
        if parser.low is not None:
            below = (
                parser.low / 2 if getattr(parser, "zero_is_none", False) else parser.low - max(1e-6, abs(parser.low))
            )
            vals.append(f"{parser.low:.17g}" if parser.low_open else f"{below:.17g}")  # (0: "no ball" where it is)
        if parser.high is not None:
            vals.append(
                f"{parser.high:.17g}" if parser.high_open else f"{parser.high + max(1e-6, abs(parser.high)):.17g}"
            )
        return vals
    if isinstance(parser, Angle):
        lo, hi = parser.range.low, parser.range.high
        return ["nan", "abc", "1_0deg", "inf", f"{(lo if parser.range.low_open else lo - 1):g}deg",
                f"{(hi if parser.range.high_open else hi + 1):g}deg"]  # fmt: skip
    if isinstance(parser, Joints):
        return ["1,2,3", "nan,0,0,0,0,0,0", "a,b,c,d,e,f,g", "400deg,0,0,0,0,0,0", "0,0,0,0,0,0,1_0", ""]
    if isinstance(parser, Floats):
        good = ",".join(["0"] * parser.count)
        return [",".join(["0"] * (parser.count + 1)), good.replace("0", "nan", 1), good.replace("0", "1e300", 1),
                good.replace("0", "x", 1), ""]  # fmt: skip
    if isinstance(parser, Grid):
        return ["10", "axb", "1x1", "1e3x100", "99999x99999"]
    if isinstance(parser, Points):
        return ["x", "0.4,nan;1,1", "0.4;1,1", "100,0;1,1"]
    if isinstance(parser, Choice):
        return ["bogus", "", parser.choices[0] + "x"]
    if parser is parse_ip:
        return ["not-an-ip", "a b", "300.1.1.1", ""]
    return ["a b,,", "not-an-ip"]  # other parsers (--source, --client, ...)


SYNTAX_ONLY = frozenset({"inf", "-inf", "", "abc", "0x10", "1e400", "１", "1.5", "1e3"})  # Number's syntax cases


def _option_cases():
    """Every value option with its parser's bad values. The syntax cases of a plain number (inf, '', abc, 0x10, …)
    are the shared Number parser's, the same for every option (test_every_numeric_option_is_validated_by_the_
    shared_parsers checks each option has it): they run on the first numeric option of each command; every numeric
    option gets 'nan', '1_0' and its own range's ends."""
    from lbrcli.options import Number

    cases = []
    for command, fn in _commands():
        syntax_done = False
        for shown, info, _ in _value_options(fn):
            if info.parser is None:
                continue
            values = _bad_values(info.parser)
            if isinstance(info.parser, Number):
                if syntax_done:
                    values = [v for v in values if v not in SYNTAX_ONLY]
                syntax_done = True
            for value in values:
                cases.append(pytest.param(command, shown, value, id=f"{command}|{shown or 'ARG'}|{value}"))
    return cases


OPTION_CASES = _option_cases()


@pytest.mark.parametrize("command, option, value", OPTION_CASES)
def test_bad_option_values_are_refused_at_parse_time(guarded_ws, tmp_path, command, option, value):
    ws = guarded_ws
    argv = argv_of(command, ws, tmp_path)
    if option is None:  # the positional joint vector of `lbr ptp`
        argv[1] = value
    else:
        argv += [option, value]
    code, out, err = run(argv)
    line = error_line(code, err, 2)
    assert (option or "Q") in line and f"lbr {command}:" in line and "--help" in line, line
    assert not any(tmp_path.iterdir()), "a refused command left a file"


# ---------------------------------------------------------------- values that parse but the command must refuse

BEYOND = "3," + ",".join(map(str, Q_START[1:]))  # A1 3 rad: outside ±170°


@pytest.mark.parametrize(
    "command, extra, words",
    [
        ("ik", ("--q0", BEYOND), "--q0: A1 = 3.0000 rad"),
        ("plan anti-sway", ("--q0", BEYOND), "--q0: A1"),
        ("plan swing-up", ("--q-start", BEYOND), "--q-start: A1"),
        ("sim", ("--q0", BEYOND), "--q0: A1"),
        ("control upright", ("--q-start", BEYOND), "--q-start: A1"),
        ("execute", ("--sim-start", BEYOND), "--sim-start: A1"),
        ("ptp", ("--sim-start", BEYOND), "--sim-start: A1"),
        ("serve", ("--sim-start", BEYOND), "--sim-start: A1"),
        ("control damp", ("--sim-start", BEYOND), "--sim-start: A1"),
        ("ik", ("--q0", BEYOND, "--limits", "{ws}/limits.toml"), "--q0: A1"),
        ("track film", ("--size", "64x5000"), "--size"),
        ("serve", ("--listen", "off"), "--listen off needs --mqtt"),
        ("serve", ("--secret", "{ws}/joint.csv", "--listen", "nonsense"), "--listen"),
        ("compare", ("--column", "nope"), "no column 'nope'"),
        ("execute", ("--robot", "192.0.2.1", "--damping", "0.5"), "apply to the simulator only"),
        ("control upright", ("--robot", "192.0.2.1"), "--pendulum PORT is needed"),
        ("track video", ("--pivot", "1000,10"), "is outside the 320x240 px image"),
        ("track video", ("--pivot", "10,10", "--pivot-color", "green"), "either --pivot or --pivot-color"),
        ("track video", ("--color", "plaid"), "--color"),
        ("track live", ("--pivot", "10,10", "--pivot-color", "green"), "either --pivot or --pivot-color"),
        ("plan cup-and-ball", ("--q-start", BEYOND), "--q-start: A1"),
        ("view", ("--offset", "nofile.csv=1"), "--offset: nofile.csv is none of the files given"),
        ("export", ("{ws}/stopped.csv",), "at most one execution log"),
        ("sweep", ("--runs", "5"), "--runs: 5 is outside the study's runs 0-0"),
        ("plan cup-and-ball", ("--length", "0.05"), "exceed the cup's extent"),
        ("sim", ("--cup", "default"), "--cup needs the simulated ball"),
        ("execute", ("--cup", "default", "--length", "0"), "--cup needs the simulated ball"),
        ("track film", ("--cup", "radius=0.03,depth=0.3,rim=0.31", "--length", "0.2"), "--cup"),
        ("track live", ("--mqtt", "http://127.0.0.1:1/x"), "--mqtt"),
        ("monitor", ("--robot", "192.0.2.1", "--length", "0.3"), "apply to the simulator only"),
    ],
)
def test_values_that_parse_but_do_not_fit_are_refused(guarded_ws, tmp_path, command, extra, words):
    code, out, err = run(argv_of(command, guarded_ws, tmp_path, *(e.format(ws=guarded_ws) for e in extra)))
    assert words in error_line(code, err, 2)
    assert not any(tmp_path.iterdir())


# ---------------------------------------------------------------- bad files

HEADER = "t,q1,q2,q3,q4,q5,q6,q7\n"
ROW0 = "0,0,0.1,0,-1.3,0,0.1,0\n"


def _csv(body: str) -> bytes:
    return (HEADER + ROW0 + body).encode()


# (name, content or a special kind, expected words, expected row, expected column); row/column None: not named
BAD_JOINT_FILES = [
    ("empty", b"", "empty file", None, None),
    ("blank", b"\n \n,,\n", "empty file", None, None),
    ("header_only", HEADER.encode(), "no data rows", 1, None),
    ("wrong_header", b"t,a1,q2,q3,q4,q5,q6,q7\n" + ROW0.encode(), "wrong header", 1, 2),
    ("missing_column", b"t,q1,q2,q3,q4,q5,q6\n0,0,0,0,0,0,0\n", "missing column 'q7'", 1, 8),
    ("duplicate_column", b"t,q1,q2,q3,q4,q5,q6,q7,q7\n0,0,0,0,0,0,0,0,0\n", "duplicate column", 1, 8),
    ("empty_name", b"t,q1,q2,q3,q4,q5,q6,q7,\n0,0,0,0,0,0,0,0,0\n", "empty column name", 1, 9),
    ("text_cell", _csv("0.005,0,0.1,zero,-1.3,0,0.1,0\n"), "not a number: 'zero'", 3, 4),
    ("underscore", _csv("0.005,0,0.1,1_0,-1.3,0,0.1,0\n"), "not a number: '1_0'", 3, 4),
    ("nan_cell", _csv("0.005,0,0.1,nan,-1.3,0,0.1,0\n"), "not a finite number", 3, 4),
    ("inf_cell", _csv("0.005,0,0.1,0,-inf,0,0.1,0\n"), "not a finite number", 3, 5),
    ("overflow", _csv("0.005,0,0.1,0,-1.3,1e400,0.1,0\n"), "not a finite number", 3, 6),
    ("huge_angle", _csv("0.005,0,0.1,0,-1.3,0,1e300,0\n"), "joint angle [rad] 1e+300", 3, 7),
    ("arabic_digit", _csv("0.005,0,0.1,0,-1.3,0,0.1,\u0661\n"), "not a number", 3, 8),
    ("empty_cell", _csv("0.005,0,0.1,,-1.3,0,0.1,0\n"), "empty cell", 3, 4),
    ("short_row", _csv("0.005,0,0.1,0,-1.3,0,0.1\n"), "missing columns", 3, 8),
    ("long_row", _csv("0.005,0,0.1,0,-1.3,0,0.1,0,9\n"), "extra columns", 3, 9),
    ("t_not_zero", (HEADER + "1,0,0.1,0,-1.3,0,0.1,0\n").encode(), "time must start at 0", 2, 1),
    ("t_backwards", _csv("0.005,0,0.1,0,-1.3,0,0.1,0\n0.001,0,0.1,0,-1.3,0,0.1,0\n"), "time not increasing", 4, 1),
    ("t_repeated", _csv("0,0,0.1,0,-1.3,0,0.1,0\n"), "time not increasing", 3, 1),
    ("t_uneven", _csv("0.005,0,0.1,0,-1.3,0,0.1,0\n0.02,0,0.1,0,-1.3,0,0.1,0\n"), "not uniform", 3, 1),
    ("t_huge_step", _csv("1e9,0,0.1,0,-1.3,0,0.1,0\n"), "time step 1e+09 s", 3, 1),
    ("latin1", _csv("0.005,0,0.1,0,-1.3,0,0.1,0\n")[:-12] + b"\xb5-1.3,0,0.1,0\n", "not UTF-8", 3, None),
    ("binary", bytes(range(256)) * 8, "NUL byte", None, None),
    ("quote_garbage", _csv('0.005,"0,0.1,0,-1.3,0,0.1,0\n'), "", None, None),
    ("headerless", b"0,0.1,0,-1.3,0,0.1,0\n" * 3, "give the sample step with --dt", 1, None),
    ("headerless_8", b"0,0,0.1,0,-1.3,0,0.1,0\n" * 3, "missing header", 1, None),
    ("dev_zero", "/dev/zero", "NUL byte at offset 0", None, None),
    ("directory", "DIR", "is a directory", None, None),
    ("missing", "MISSING", "not found", None, None),
    ("fifo", "FIFO", "empty file", None, None),
]
JOINT_READERS = [
    ("fk", lambda f: ["fk", f, "-o", "{out}/t.csv"]),
    ("check", lambda f: ["check", f]),
    ("retime", lambda f: ["retime", f, "-o", "{out}/r.csv"]),
    ("execute", lambda f: ["execute", f]),
    ("control damp", lambda f: ["control", "damp", f]),
]


def _materialise(tmp_path: Path, name: str, content) -> Path:
    if content == "/dev/zero":
        return Path(content)
    p = tmp_path.parent / f"in-{tmp_path.name}" / f"{name}.csv"
    p.parent.mkdir(exist_ok=True)
    if content == "DIR":
        p.mkdir()
    elif content == "FIFO":
        os.mkfifo(p)
    elif content != "MISSING":
        p.write_bytes(content)
    return p


def _check_names(line: str, path: Path, words: str, row, column) -> None:
    assert str(path) in line and words in line, line
    if row is not None:
        assert f"row {row}" in line, line
    if column is not None:
        assert f"column {column}" in line, line


@pytest.mark.parametrize("reader", [r for r, _ in JOINT_READERS])
@pytest.mark.parametrize("name, content, words, row, column", BAD_JOINT_FILES, ids=[c[0] for c in BAD_JOINT_FILES])
def test_bad_joint_files(guarded_ws, tmp_path, reader, name, content, words, row, column):
    path = _materialise(tmp_path, name, content)
    argv = [a.format(out=tmp_path) for a in dict(JOINT_READERS)[reader](str(path))]
    code, out, err = run(argv)
    _check_names(error_line(code, err, 2), path, words, row, column)
    assert not any(tmp_path.iterdir())


TASK_HEADER = "t,x,y,z,qw,qx,qy,qz\n"
BAD_TASK_FILES = [
    ("not_unit", TASK_HEADER + "0,0.5,0,0.5,1,0,0,0\n0.005,0.5,0,0.5,0.5,0,0,0\n", "quaternion not unit", 3, 5),
    ("huge_position", TASK_HEADER + "0,0.5,0,0.5,1,0,0,0\n0.005,1e300,0,0.5,1,0,0,0\n", "position [m] 1e+300", 3, 2),
    ("millimetres", TASK_HEADER + "0,500,0,500,1,0,0,0\n0.005,500,0,500,1,0,0,0\n", "beyond ±10", 2, 2),
    ("joint_file", HEADER + ROW0, "wrong header", 1, 2),
    ("nan_quat", TASK_HEADER + "0,0.5,0,0.5,nan,0,0,0\n", "not a finite number", 2, 5),
    ("underscore", TASK_HEADER + "0,0.5,0,0.5,1,0,0,0\n0.005,0.5,0,0.5,1,0,0,0_0\n", "not a number: '0_0'", 3, 8),
]


@pytest.mark.parametrize("name, content, words, row, column", BAD_TASK_FILES, ids=[c[0] for c in BAD_TASK_FILES])
def test_bad_task_files(guarded_ws, tmp_path, name, content, words, row, column):
    path = _materialise(tmp_path, name, content.encode())
    code, out, err = run(["ik", path, "-o", tmp_path / "j.csv"])
    _check_names(error_line(code, err, 2), path, words, row, column)
    assert not any(tmp_path.iterdir())


HOSTILE_TOML = [
    ("random", bytes(np.random.default_rng(1).integers(0, 256, 3000, dtype=np.uint8)), "limits.toml"),
    ("not_utf8", b"velocity_deg_s = [\xff]", "not UTF-8"),
    ("deep", b"a = " + b"[" * 5000 + b"]" * 5000, "nested deeper"),
    ("bigint", b"velocity_deg_s = [" + b",".join([b"9" * 400] * 7) + b"]", "list of 7 numbers"),
    ("tiny", b"velocity_deg_s = [1e-300, 98, 100, 130, 140, 180, 180]", "outside the plausible range"),
    ("negative", b"acceleration_rad_s2 = [-1, 1, 1, 1, 1, 1, 1]", "outside the plausible range"),
    ("huge", b"jerk_rad_s3 = [1e30, 1, 1, 1, 1, 1, 1]", "outside the plausible range"),
    ("bool", b"torque_nm = [true, 1, 1, 1, 1, 1, 1]", "list of 7 numbers"),
    ("short", b"position_deg = [170, 120]", "list of 7 numbers"),
    ("unknown", b"speed = 3", "unknown limit table"),
    ("syntax", b"velocity_deg_s = [1, 2", "not a valid TOML"),
    ("table", b"[velocity_deg_s]\na = 1", "list of 7 numbers"),
    ("dev_zero", "/dev/zero", "NUL byte"),
    ("missing", "MISSING", "limits file not found"),
    ("directory", "DIR", "is a directory"),
]
LIMITS_READERS = ["check", "retime", "ik", "plan anti-sway", "plan swing-up", "plan cup-and-ball", "execute", "ptp",
                  "sim", "serve", "control upright", "control damp", "export"]  # fmt: skip


@pytest.mark.parametrize("command", LIMITS_READERS)
@pytest.mark.parametrize("name, content, words", HOSTILE_TOML, ids=[c[0] for c in HOSTILE_TOML])
def test_hostile_limits_files(guarded_ws, tmp_path, command, name, content, words):
    path = _materialise(tmp_path, name, content)
    code, out, err = run(argv_of(command, guarded_ws, tmp_path, "--limits", path))
    line = error_line(code, err, 2)
    assert str(path) in line and (words in line or words == "limits.toml"), line
    assert not any(tmp_path.iterdir())


OBSTACLE_HEADER = "name,x_min,y_min,z_min,x_max,y_max,z_max\n"
BAD_OBSTACLES = [
    ("empty", "", "empty", None, None),
    ("header", "name,x,y\n", "header must start with", 1, 2),
    ("nan", OBSTACLE_HEADER + "a,nan,0,0,1,1,1\n", "not a finite number", 2, 2),
    ("underscore", OBSTACLE_HEADER + "a,0,0,0,1_0,1,1\n", "not a number: '1_0'", 2, 5),
    ("inverted", OBSTACLE_HEADER + "a,1,0,0,0.5,1,1\n", "must exceed", 2, 5),
    ("short", OBSTACLE_HEADER + "a,0,0,0\n", "expected 7 columns", 2, 5),
    ("duplicate", OBSTACLE_HEADER + "a,0,0,0,1,1,1\na,0,0,0,1,1,1\n", "duplicate obstacle name", 3, 1),
    ("noname", OBSTACLE_HEADER + ",0,0,0,1,1,1\n", "empty obstacle name", 2, 1),
    ("binary", "\x00\x01", "NUL byte", None, None),
]


@pytest.mark.parametrize("name, content, words, row, column", BAD_OBSTACLES, ids=[c[0] for c in BAD_OBSTACLES])
def test_bad_obstacle_files(guarded_ws, tmp_path, name, content, words, row, column):
    path = _materialise(tmp_path, name, content.encode())
    code, out, err = run(argv_of("plan anti-sway", guarded_ws, tmp_path, "--obstacles", path))
    _check_names(error_line(code, err, 2), path, words, row, column)
    assert not any(tmp_path.iterdir())


def test_an_obstacle_file_with_a_byte_order_mark_is_read(tmp_path):
    from lbrcli.obstacle_file import read_obstacles

    p = tmp_path / "o.csv"
    p.write_bytes(b"\xef\xbb\xbf" + (OBSTACLE_HEADER + "post,0.5,-0.2,0,0.55,-0.15,0.25\n").encode())
    (obstacle,) = read_obstacles(p)
    assert obstacle.name == "post" and obstacle.upper == (0.55, -0.15, 0.25)


BAD_CALIBRATIONS = [
    ("not_json", "{", "not JSON"),
    ("list", "[1, 2]", "not a calibration object"),
    ("missing", '{"dist_coeffs": [0,0,0,0,0], "image_size": [320, 240]}', "missing field 'camera_matrix'"),
    (
        "nan",
        '{"camera_matrix": [[NaN,0,0],[0,1,0],[0,0,1]], "dist_coeffs": [0,0,0,0,0], "image_size": [320, 240]}',
        "non-finite",
    ),
    ("shape", '{"camera_matrix": [1,2,3], "dist_coeffs": [0,0,0,0,0], "image_size": [320, 240]}', "shape"),
    (
        "size",
        '{"camera_matrix": [[1,0,0],[0,1,0],[0,0,1]], "dist_coeffs": [0,0,0,0,0], "image_size": [-1, 1e30]}',
        "image_size",
    ),
    (
        "rms",
        '{"camera_matrix": [[1,0,0],[0,1,0],[0,0,1]], "dist_coeffs": [0,0,0,0,0], "image_size": [320, 240], '
        '"rms_px": "low"}',
        "rms_px",
    ),
    ("deep", "[" * 100000 + "]" * 100000, "nested too deeply"),
]


@pytest.mark.parametrize("name, content, words", BAD_CALIBRATIONS, ids=[c[0] for c in BAD_CALIBRATIONS])
def test_bad_calibration_files(guarded_ws, tmp_path, name, content, words):
    path = _materialise(tmp_path, name, content.encode())
    code, out, err = run(argv_of("track video", guarded_ws, tmp_path, "--calibration", path))
    line = error_line(code, err, 2)
    assert str(path) in line and words in line, line
    assert not any(tmp_path.iterdir())


BAD_MEDIA = [
    ("text", b"this is not a video\n", "not a readable video"),
    ("empty", b"", "not a readable video"),
    ("random", bytes(np.random.default_rng(2).integers(0, 256, 5000, dtype=np.uint8)), "not a readable video"),
    ("dev_zero", "/dev/zero", "not a regular file"),
    ("fifo", "FIFO", "not a regular file"),
    ("missing", "MISSING", "not found"),
]


@pytest.mark.parametrize("name, content, words", BAD_MEDIA, ids=[c[0] for c in BAD_MEDIA])
def test_bad_videos(guarded_ws, tmp_path, name, content, words):
    path = _materialise(tmp_path, name, content)
    code, out, err = run(["track", "video", path, "-o", tmp_path / "tr.csv"])
    line = error_line(code, err, 2)
    assert str(path) in line and words in line, line
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize(
    "name, content, words", BAD_MEDIA[:3] + BAD_MEDIA[5:], ids=[c[0] for c in BAD_MEDIA[:3] + BAD_MEDIA[5:]]
)
def test_bad_calibration_images(guarded_ws, tmp_path, name, content, words):
    path = _materialise(tmp_path, name, content)
    code, out, err = run(["track", "calibrate", path, "-o", tmp_path / "cal.json"])
    line = error_line(code, err, 2)
    assert str(path) in line or "board was found in 0" in line, line
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize(
    "argv, words",
    [
        (
            ["track", "film", "{ws}/stopped.csv", "-o", "{out}/f.mp4"],
            "did not complete (it stopped at row 40 of the 100",
        ),
        (["track", "film", "{ws}/noball.csv", "-o", "{out}/f.mp4"], "no column 'ball_theta_y'"),
        (["track", "film", "{ws}/joint.csv", "-o", "{out}/f.mp4"], "wrong header"),
        (["compare", "{ws}/stopped.csv", "{ws}/track.csv", "--column", "ball_theta_y"], "did not complete"),
        (["compare", "{ws}/pred.csv", "{ws}/joint.csv"], "wrong header"),
        (["compare", "{ws}/joint.csv", "{ws}/track.csv"], "wrong header"),
        (["serve", "--secret", "{ws}/nope.txt"], "not found"),
        (["serve", "--secret", "/dev/zero"], "is larger than lbr reads"),
        (["check", "/dev/zero", "--limits", "{ws}/limits.toml"], "NUL byte"),
        (["sweep", "/dev/zero", "-o", "{out}/res"], "NUL byte"),
        (["sweep", "{ws}/joint.csv", "-o", "{out}/res"], "not valid TOML"),
    ],
)
def test_bad_logs_and_other_inputs(guarded_ws, tmp_path, argv, words):
    code, out, err = run([a.format(ws=guarded_ws, out=tmp_path) for a in argv])
    assert words in error_line(code, err, 2)
    assert not any(tmp_path.iterdir())


def test_a_partial_log_is_used_when_asked(guarded_ws, tmp_path):
    code, out, err = run(["track", "film", guarded_ws / "stopped.csv", "-o", tmp_path / "f.mp4", "--partial",
                          "--size", "320x240", "--fps", "10"])  # fmt: skip
    assert code == 0 and "did not complete" in err and (tmp_path / "f.mp4").stat().st_size > 0, err


def test_a_track_covering_a_small_part_of_the_prediction_is_refused(guarded_ws, tmp_path):
    from trajectories.csvio import write_table

    t = np.arange(0, 0.4, 1 / 60)
    short = tmp_path.parent / f"short-{tmp_path.name}.csv"
    write_table(
        short,
        ("t", "frame", "u", "v", "found", "theta"),
        np.column_stack([t, np.arange(len(t)), 0 * t, 0 * t, 1 + 0 * t, 0.2 * np.sin(2 * np.pi * t)]),
    )
    code, out, err = run(["compare", guarded_ws / "pred.csv", short, "--lag", "0"])
    assert "covers only 10 % of the prediction" in error_line(code, err, 1)
    code, out, err = run(["compare", guarded_ws / "pred.csv", short, "--lag", "0", "--partial"])
    assert code == 0, err


# ---------------------------------------------------------------- outputs onto links, devices, FIFOs

OUTPUTS = [
    ("fk", "-o"), ("ik", "-o"), ("retime", "-o"), ("check", "--plot"), ("compare", "--plot"),
    ("plan anti-sway", "-o"), ("plan anti-sway", "--task-out"), ("plan anti-sway", "--prediction"),
    ("plan anti-sway", "--plot"), ("plan swing-up", "-o"), ("plan swing-up", "--prediction"),
    ("plan swing-up", "--plot"), ("plan swing-up", "--task-out"), ("plan cup-and-ball", "-o"),
    ("plan cup-and-ball", "--prediction"), ("plan cup-and-ball", "--plot"), ("execute", "--log"), ("execute", "--plot"),
    ("monitor", "--log"), ("ptp", "--log"), ("serve", "--log"), ("listen", "-o"), ("track video", "-o"),
    ("track video", "--plot"), ("track video", "--preview"), ("track video", "--candidates"),
    ("track calibrate", "-o"), ("track film", "-o"), ("track film", "--truth"), ("track live", "-o"),
    ("track live", "--plot"), ("demo", "--out"),
    ("control upright", "--log"), ("control upright", "--plot"), ("control damp", "--log"),
    ("control damp", "--plot"), ("view", "-o"), ("export", "-o"), ("sweep", "-o"),
]  # fmt: skip


@pytest.mark.parametrize("target", ["symlink", "dangling", "fifo", "dev_null"])
@pytest.mark.parametrize("command, option", OUTPUTS, ids=[f"{c}|{o}" for c, o in OUTPUTS])
def test_outputs_never_replace_links_devices_or_fifos(guarded_ws, tmp_path, command, option, target):
    precious = tmp_path / "precious.csv"
    precious.write_text("keep me\n")
    path = {"dev_null": Path("/dev/null")}.get(target, tmp_path / "target.out")
    if target == "symlink":
        path.symlink_to(precious)
    elif target == "dangling":
        path.symlink_to(tmp_path / "nowhere")
    elif target == "fifo":
        os.mkfifo(path)
    before = snapshot(tmp_path)
    null = os.stat("/dev/null")
    argv = argv_of(command, guarded_ws, tmp_path)
    if option in argv:  # the base's own output: replace its value
        argv[argv.index(option) + 1] = str(path)
    else:
        argv += [option, path]
    code, out, err = run(argv)
    line = error_line(code, err, 2)
    assert "replaces only regular files" in line and str(path) in line, line
    assert snapshot(tmp_path) == before and precious.read_text() == "keep me\n"
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode) and os.stat("/dev/null").st_rdev == null.st_rdev


# ---------------------------------------------------------------- full disks


@contextlib.contextmanager
def file_size_limit(nbytes: int):
    """RLIMIT_FSIZE for this process: writes beyond ``nbytes`` fail with EFBIG (Python ignores SIGXFSZ)."""
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    resource.setrlimit(resource.RLIMIT_FSIZE, (nbytes, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))


@pytest.fixture(scope="module")
def tiny_disk(tmp_path_factory):
    """A 256 KiB tmpfs (ENOSPC when full), or None when this process may not mount one (not root)."""
    d = tmp_path_factory.mktemp("tiny")
    if os.geteuid() != 0:
        yield None
        return
    ok = (
        subprocess.run(["mount", "-t", "tmpfs", "-o", "size=256k", "tmpfs", str(d)], capture_output=True).returncode
        == 0
    )
    yield d if ok else None
    if ok:
        subprocess.run(["umount", "-l", str(d)], capture_output=True)


BOTH = ("file_size_limit", "full_tmpfs")
TMPFS = ("full_tmpfs",)  # another output of the command is written first: a process-wide file-size limit hits it
WRITERS = [
    ("fk -o", BOTH, ["fk", "{ws}/joint.csv", "-o", "{full}/t.csv"]),
    ("ik -o", BOTH, ["ik", "{ws}/task.csv", "-o", "{full}/j.csv", "--q0", ",".join(map(str, Q_START))]),
    ("retime -o", BOTH, ["retime", "{ws}/joint.csv", "-o", "{full}/r.csv", "--step", "0.001"]),
    ("check --plot", BOTH, ["check", "{ws}/joint.csv", "--plot", "{full}/c.png"]),
    ("compare --plot", BOTH, ["compare", "{ws}/pred.csv", "{ws}/track.csv", "--plot", "{full}/c.png"]),
    ("track film -o", BOTH, ["track", "film", "{ws}/log.csv", "-o", "{full}/f.mp4", "--size", "640x480", "--fps",
                             "30"]),
    ("track film --truth", TMPFS, ["track", "film", "{ws}/log.csv", "-o", "{out}/f.mp4", "--truth",
                                   "{full}/truth.csv", "--size", "320x240", "--fps", "500"]),
    ("track video -o", BOTH, ["track", "video", "{ws}/video.mp4", "-o", "{full}/tr.csv", "--min-found", "0"]),
    ("track video --plot", TMPFS, ["track", "video", "{ws}/video.mp4", "-o", "{out}/tr.csv", "--plot",
                                  "{full}/p.png", "--min-found", "0"]),
    ("track video --preview", BOTH, ["track", "video", "{ws}/video.mp4", "-o", "{out}/tr.csv", "--preview",
                                     "{full}/p.mp4", "--min-found", "0"]),
    ("track video --candidates", BOTH, ["track", "video", "{ws}/video.mp4", "-o", "{out}/tr.csv", "--candidates",
                                        "{full}/c.png", "--min-found", "0"]),
    ("plan anti-sway -o", BOTH, ["plan", "anti-sway", "-o", "{full}/a.csv", "--length", "0.25", "--a-max", "1",
                                 "--points", "0.45,-0.1;0.55,-0.1", "--shaper", "zv", "--length-tolerance", "0",
                                 "--no-tune", "--dt", "0.001"]),
    ("view -o", BOTH, ["view", "{ws}/joint.csv", "-o", "{full}/v.html"]),
    ("export -o", BOTH, ["export", "{ws}/log.csv", "-o", "{full}/r.mcap"]),
    ("execute --plot", TMPFS, ["execute", "{ws}/joint.csv", "--log", "{out}/log.csv", "--plot", "{full}/p.png",
                               "--sim-lenient"]),
]  # fmt: skip


def _padding(folder: Path) -> None:
    """Fill a tmpfs: not one more page can be written (empty files can still be created)."""
    with open(folder / "padding", "wb", buffering=0) as fh:
        with contextlib.suppress(OSError):
            while True:
                fh.write(b"\0" * 4096)


@pytest.mark.heavy
@pytest.mark.parametrize("disk", BOTH)
@pytest.mark.parametrize("name, disks, argv", WRITERS, ids=[w[0] for w in WRITERS])
def test_a_full_disk_leaves_nothing_and_exits_1(guarded_ws, tmp_path, tiny_disk, disk, name, disks, argv):
    if disk not in disks:
        pytest.skip("this output is written after another one, which a file-size limit would stop first")
    out = tmp_path / "out"
    out.mkdir()
    if disk == "full_tmpfs":
        if tiny_disk is None:
            pytest.skip("cannot mount a tmpfs here (not root)")
        full = tiny_disk / tmp_path.name
        full.mkdir()
        _padding(tiny_disk)
        limit = contextlib.nullcontext()
    else:
        full = tmp_path / "full"
        full.mkdir()
        limit = file_size_limit(2048)
    argv = [a.format(ws=guarded_ws, full=full, out=out) for a in argv]
    try:
        with limit:
            code, _, err = run(argv)
    finally:
        if disk == "full_tmpfs":
            (tiny_disk / "padding").unlink()
    line = error_line(code, err, 1)
    assert str(full) in line and any(w in line for w in ("No space left", "too large", "could not be written",
                                                          "cannot start writing"))  # fmt: skip
    assert not any(full.iterdir()), "a failed write left a file"
