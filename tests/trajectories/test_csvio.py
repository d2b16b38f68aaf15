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
        (HEADER + "0,1,2,3,4,5,6,7\n0.005,1,2,3,4,5,6,7\n0.011,1,2,3,4,5,6,7\n0.015,1,2,3,4,5,6,7\n", 4, 1, "not uniform"),
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
    with pytest.raises(CsvFormatError, match="--dt"):
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
