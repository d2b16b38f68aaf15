"""Atomic output: a file appears under its name only complete; a failed or interrupted write leaves the old one."""

import os

import numpy as np
import pytest

from trajectories.atomic import atomic_open, atomic_path, temporary_name
from trajectories.csvio import read_table, write_table


def test_complete_write_is_renamed_and_leaves_no_temporary(tmp_path):
    target = tmp_path / "a.csv"
    write_table(target, ("t", "x"), np.array([[0.0, 1.0], [0.1, 2.0]]))
    assert read_table(target, ("t", "x")).data[1, 1] == 2.0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv"]


@pytest.mark.parametrize("error", [RuntimeError, KeyboardInterrupt])
def test_interrupted_write_keeps_the_old_file(tmp_path, error):
    target = tmp_path / "log.jsonl"
    target.write_text("old\n")
    with pytest.raises(error):
        with atomic_open(target) as fh:
            fh.write("half a line")
            raise error()
    assert target.read_text() == "old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["log.jsonl"]


def test_temporary_keeps_the_suffix_for_format_sniffing_writers(tmp_path):
    tmp = temporary_name(tmp_path / "plot.png")
    assert tmp.suffix == ".png" and tmp.parent == tmp_path and tmp.name.startswith(".plot.")
    assert str(os.getpid()) in tmp.name


def test_errors_name_the_target_not_the_temporary(tmp_path):
    with pytest.raises(FileNotFoundError) as exc:
        with atomic_path(tmp_path / "no" / "such" / "x.csv"):
            pass
    assert exc.value.filename == str(tmp_path / "no" / "such" / "x.csv")
    (tmp_path / "d.csv").mkdir()
    with pytest.raises(IsADirectoryError) as exc:
        with atomic_path(tmp_path / "d.csv"):
            pass
    assert exc.value.filename == str(tmp_path / "d.csv")
