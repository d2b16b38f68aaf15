import os
import re

import numpy as np
import pytest

from trajectories.csvio import read_joint_csv, read_table, read_task_csv, write_joint_csv
from trajectories.errors import CsvFormatError
from trajectories.trajectory import JointTrajectory

HEADER = "t,q1,q2,q3,q4,q5,q6,q7\n"
ROW = ",0.1,0.2,0.3,-1.0,0.5,0.6,0.7\n"


def write(tmp_path, text, name="j.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def good(n=5, h=0.005):
    return HEADER + "".join(f"{k * h:.3f}{ROW}" for k in range(n))


def test_round_trip(tmp_path):
    traj = JointTrajectory.from_samples(np.random.default_rng(0).normal(size=(50, 7)), 0.001)
    p = tmp_path / "a.csv"
    write_joint_csv(p, traj)
    back = read_joint_csv(p)
    assert np.allclose(back.q, traj.q, atol=1e-12) and np.allclose(back.t, traj.t)
    assert back.dt == pytest.approx(0.001)


def test_extra_named_columns_after_the_fixed_ones_are_allowed(tmp_path):
    text = "t,q1,q2,q3,q4,q5,q6,q7,note\n" + "".join(f"{k * 0.005:.3f}{ROW.strip()},{k}\n" for k in range(3))
    assert len(read_joint_csv(write(tmp_path, text))) == 3


@pytest.mark.parametrize(
    "text, row, column, words",
    [
        ("t,q1,q2,q3,q4,q5,q6\n0,1,2,3,4,5,6\n", 1, 8, "missing column 'q7'"),
        ("t,q1,q2,q3,q4,q5,q6,q8\n0,1,2,3,4,5,6,7\n", 1, 8, "expected 'q7', found 'q8'"),
        ("time,q1,q2,q3,q4,q5,q6,q7\n0,1,2,3,4,5,6,7\n", 1, 1, "expected 't'"),
        (HEADER + "0,1,2,3,4,5,6\n", 2, 8, "missing columns"),
        (HEADER + "0,1,2,3,4,5,6,7,8\n", 2, 9, "extra columns"),
        (HEADER + "0,1,2,3,nan,5,6,7\n", 2, 5, "not a finite number"),
        (HEADER + "0,1,2,3,inf,5,6,7\n", 2, 5, "not a finite number"),
        (HEADER + "0,1,2,abc,4,5,6,7\n", 2, 4, "not a number: 'abc'"),
        (HEADER + "0,1,2,,4,5,6,7\n", 2, 4, "empty cell"),
        (HEADER + "0.1,1,2,3,4,5,6,7\n", 2, 1, "time must start at 0"),
        (HEADER + "0,1,2,3,4,5,6,7\n0.005,1,2,3,4,5,6,7\n0.005,1,2,3,4,5,6,7\n", 4, 1, "time not increasing"),
        (
            HEADER + "0,1,2,3,4,5,6,7\n0.005,1,2,3,4,5,6,7\n0.011,1,2,3,4,5,6,7\n0.015,1,2,3,4,5,6,7\n",
            4,
            1,
            "not uniform",
        ),
    ],
)
def test_bad_joint_files_name_row_and_column(tmp_path, text, row, column, words):
    with pytest.raises(CsvFormatError) as exc:
        read_joint_csv(write(tmp_path, text))
    err = exc.value
    assert err.row == row and err.column == column
    assert words in str(err)
    assert str(tmp_path / "j.csv") in str(err)
    assert "\n" not in str(err)


def test_empty_file(tmp_path):
    with pytest.raises(CsvFormatError, match="empty file"):
        read_joint_csv(write(tmp_path, ""))
    with pytest.raises(CsvFormatError, match="no data rows"):
        read_joint_csv(write(tmp_path, HEADER))


def test_missing_file(tmp_path):
    with pytest.raises(CsvFormatError, match="file not found"):
        read_joint_csv(tmp_path / "nope.csv")


def test_headerless_needs_dt(tmp_path):
    p = write(tmp_path, "0.1,0.2,0.3,-1.0,0.5,0.6,0.7\n" * 4)
    with pytest.raises(CsvFormatError, match="read_table.headerless_dt"):
        read_joint_csv(p)
    traj = read_joint_csv(p, dt=0.005)
    assert len(traj) == 4 and traj.t[-1] == pytest.approx(0.015)
    assert traj.q[0, 3] == -1.0


def test_headerless_wrong_width_is_a_missing_header(tmp_path):
    with pytest.raises(CsvFormatError, match="missing header"):
        read_joint_csv(write(tmp_path, "0,1,2,3\n"), dt=0.005)


def test_uniform_tolerates_rounding_only(tmp_path):
    # 0.001 s steps written with 3 decimals read back as uniform
    assert len(read_joint_csv(write(tmp_path, good(100, 0.001)))) == 100


def test_task_quaternion_must_be_unit(tmp_path):
    p = write(tmp_path, "t,x,y,z,qw,qx,qy,qz\n0,0.5,0,0.8,1,0,0,0\n0.01,0.5,0,0.8,0.9,0,0,0\n", "task.csv")
    with pytest.raises(CsvFormatError) as exc:
        read_task_csv(p)
    assert exc.value.row == 3 and "quaternion not unit" in str(exc.value)


def test_nan_columns_and_increasing_time(tmp_path):
    p = write(tmp_path, "t,frame,u,v,found\n0,0,1.5,2.5,1\n0.017,1,,,0\n0.033,2,1.6,2.4,1\n", "track.csv")
    table = read_table(p, ("t", "frame", "u", "v", "found"), time="increasing", nan_columns=("u", "v"))
    assert np.isnan(table.column("u")[1]) and table.column("v")[2] == 2.4


# -- encodings, line endings, blank lines; the fast reader agrees with the strict one ------------------------------
def test_utf8_bom_is_read(tmp_path):
    p = tmp_path / "bom.csv"
    p.write_bytes(b"\xef\xbb\xbf" + good(4).encode())
    traj = read_joint_csv(p)
    assert len(traj) == 4 and traj.q[0, 0] == 0.1
    p.write_bytes(b"\xef\xbb\xbf" + "0.1,0.2,0.3,-1.0,0.5,0.6,0.7\n".encode() * 3)  # headerless with a BOM
    assert read_joint_csv(p, dt=0.01).q.shape == (3, 7)


def test_crlf_trailing_and_inner_blank_lines_keep_row_numbers(tmp_path):
    rows = good(6).splitlines()
    text = "\r\n".join(rows[:3] + ["", " , ,"] + rows[3:]) + "\r\n\r\n\r\n"
    traj = read_joint_csv(write(tmp_path, text))
    assert len(traj) == 6 and np.allclose(np.diff(traj.t), 0.005)
    bad = rows[:3] + ["", ""] + rows[3:4] + [rows[4].replace("0.5", "oops", 1)] + rows[5:]
    with pytest.raises(CsvFormatError) as exc:
        read_joint_csv(write(tmp_path, "\n".join(bad) + "\n"))
    assert exc.value.row == 7 and exc.value.column == 6 and "'oops'" in str(exc.value)


def test_quoted_cells_read_like_csv(tmp_path):
    text = HEADER + '"0",1,2,3,4,5,6,0.7\n0.005,"1",2,3,4,5,6,0.7\n'
    assert read_joint_csv(write(tmp_path, text)).q[1, 0] == 1.0


@pytest.mark.parametrize(
    "cell, words",
    [
        ("1_0", "not a number: '1_0'"),
        ("١", "not a number"),
        ("0x1", "not a number"),
        ("1e400", "not a finite number"),
        ("inf", "not a finite number"),
        ("1e300", "joint angle [rad] 1e+300 is beyond"),
    ],
)
def test_cells_must_be_plain_finite_plausible_numbers(tmp_path, cell, words):
    text = HEADER + "0,0,0,0,0,0,0,0\n0.005,0,0,%s,0,0,0,0\n" % cell
    with pytest.raises(CsvFormatError) as exc:
        read_joint_csv(write(tmp_path, text))
    assert words in str(exc.value) and (exc.value.row, exc.value.column) == (3, 4)


def test_bounded_reads(tmp_path):
    with pytest.raises(CsvFormatError, match="NUL byte at offset 0"):
        read_joint_csv("/dev/zero")
    fifo = tmp_path / "f.csv"
    os.mkfifo(fifo)
    with pytest.raises(CsvFormatError, match="empty file"):  # no writer: read as empty, never blocks
        read_joint_csv(fifo)


def test_not_utf8_names_the_row(tmp_path):
    p = tmp_path / "latin1.csv"
    p.write_bytes(good(3).encode() + "0.015,1,2,3,4,5,6,\xb57\n".encode("latin-1"))
    with pytest.raises(CsvFormatError) as exc:
        read_joint_csv(p)
    assert exc.value.row == 5 and "not UTF-8" in str(exc.value)


@pytest.mark.heavy
@pytest.mark.parametrize("rows", [10, 3000, 5001])
def test_large_files_read_exactly_and_name_the_first_fault(tmp_path, rows):
    rng = np.random.default_rng(rows)
    traj = JointTrajectory.from_samples(rng.normal(size=(rows, 7)), 0.001)
    p = tmp_path / "big.csv"
    write_joint_csv(p, traj)
    back = read_joint_csv(p)
    assert np.array_equal(back.q, np.loadtxt(p, delimiter=",", skiprows=1)[:, 1:])
    lines = p.read_text().splitlines()
    k = rows // 2 + 1  # a data line in the middle of the file (1-based line k + 1)
    cells = lines[k].split(",")
    cells[3] = "inf"
    lines[k] = ",".join(cells)
    later = lines[-1].split(",")
    later[2] = "x"  # a second fault further down must not be the one reported
    lines[-1] = ",".join(later)
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(CsvFormatError) as exc:
        read_joint_csv(p)
    assert (exc.value.row, exc.value.column) == (k + 1, 4) and "not a finite number" in str(exc.value)


def test_nan_columns_allow_nan_text_but_not_inf(tmp_path):
    head = "t,frame,u,v,found\n"
    ok = write(tmp_path, head + "0,0,1.5,2.5,1\n0.017,1,nan,nan,0\n", "ok.csv")
    table = read_table(ok, ("t", "frame", "u", "v", "found"), time="increasing", nan_columns=("u", "v"))
    assert np.isnan(table.column("u")[1])
    bad = write(tmp_path, head + "0,0,1.5,2.5,1\n0.017,1,inf,2,0\n", "bad.csv")
    with pytest.raises(CsvFormatError) as exc:
        read_table(bad, ("t", "frame", "u", "v", "found"), time="increasing", nan_columns=("u", "v"))
    assert (exc.value.row, exc.value.column) == (3, 3)


ODD_CELLS = [
    "1_0",
    "١",
    "0x1",
    "1e400",
    "-1e400",
    "inf",
    "-inf",
    "Infinity",
    "nan",
    "NaN",
    "-nan",
    "",
    " ",
    " 0.5",
    "0.5 ",
    "+0.5",
    ".5",
    "5.",
    "1e-5",
    "1E+2",
    "0.5e",
    "e5",
    "--1",
    "1.2.3",
    "0.5\r",
    "1,5",
    "true",
    "null",
    "N/A",
    "#N/A",
    "1e-400",
    "0.1f",
    "٣.٥",
    "０.５",
    "1 000",
    "\t0.5",
    "0,",
    "'0.5'",
]


@pytest.mark.parametrize("cell", ODD_CELLS)
@pytest.mark.parametrize("nan_column", [False, True])
def test_the_large_file_reader_reads_exactly_what_the_small_file_reader_reads(tmp_path, monkeypatch, cell, nan_column):
    """Bodies of ≥ ARROW_MIN_BYTES go through Arrow's reader, smaller ones through numpy's; both fall back to the
    strict reader on anything unusual. The same odd cell must give the same data or the same one-line error."""
    from trajectories import csvio

    monkeypatch.setattr(csvio, "ARROW_MIN_BYTES", 4096)  # [bytes] (1 MiB by default: the same reader, a smaller file)
    arrow_calls = []
    arrow = csvio._arrow_body
    monkeypatch.setattr(csvio, "_arrow_body", lambda *a: arrow_calls.append(a[1:3]) or arrow(*a))
    names = ["t", "a", "b", "extra"]
    n_small, n_big = 20, 1 + csvio.ARROW_MIN_BYTES // len("0.123,0.25,-1.5,0.75\n")

    def body(n):
        rows = [f"{0.001 * k:.3f},0.25,-1.5,0.75" for k in range(n)]
        rows[n // 2] = rows[n // 2].replace("0.25", cell, 1)
        return "t,a,b,extra\n" + "\n".join(rows) + "\n"

    outcomes = []
    for n in (n_small, n_big):
        p = tmp_path / f"{n}.csv"
        p.write_text(body(n), newline="")
        try:
            table = read_table(p, names[:3], time="increasing", nan_columns=["a"] if nan_column else ())
            outcomes.append(("ok", table.data[n // 2, 1], table.data.shape[0] - n))
        except CsvFormatError as exc:
            outcomes.append(
                ("error", re.sub(r"row \d+", "row", str(exc).replace(str(p), "F")), exc.row - n // 2, exc.column)
            )
    small, big = outcomes
    assert len(arrow_calls) == 1  # the big file went to Arrow
    assert (small[0], small[2:]) == (big[0], big[2:])
    if small[0] == "ok":
        assert small[1] == big[1] or (np.isnan(small[1]) and np.isnan(big[1]))
    else:
        assert small[1] == big[1]


@pytest.mark.heavy
def test_the_large_file_reader_is_used_and_equals_numpys(tmp_path):
    from trajectories import csvio

    rng = np.random.default_rng(3)
    data = np.column_stack(
        [np.arange(60000) * 1e-3, rng.normal(size=(60000, 5)) * 10.0 ** rng.integers(-8, 8, (60000, 5))]
    )
    p = tmp_path / "big.csv"
    np.savetxt(p, data, delimiter=",", fmt="%.17g", header="t,a,b,c,d,e", comments="")
    assert p.stat().st_size - len("t,a,b,c,d,e\n") >= csvio.ARROW_MIN_BYTES
    table = read_table(p, ["t", "a", "b", "c", "d", "e"], time="increasing")
    assert np.array_equal(table.data, np.loadtxt(p, delimiter=",", skiprows=1))  # the same doubles, bit for bit
