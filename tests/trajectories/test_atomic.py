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
    assert tmp.is_file() and temporary_name(tmp_path / "plot.png") != tmp  # created exclusively, fresh each time
    assert tmp.stat().st_mode & 0o777 == 0o666 & ~_umask()  # the permissions open() would give


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


@pytest.mark.parametrize("kind", ["symlink", "fifo", "device"])
def test_a_link_fifo_or_device_is_never_replaced(tmp_path, kind):
    from trajectories.errors import OutputRefused

    kept = tmp_path / "kept.csv"
    kept.write_text("precious\n")
    target = {"device": "/dev/null"}.get(kind, tmp_path / "out.csv")
    if kind == "symlink":
        target.symlink_to(kept)
    elif kind == "fifo":
        os.mkfifo(target)
    before = os.lstat(target)
    with pytest.raises(OutputRefused, match="replaces only regular files"):
        with atomic_path(target) as tmp:
            tmp.write_text("new\n")
    after = os.lstat(target)
    assert (after.st_mode, after.st_ino, after.st_rdev) == (before.st_mode, before.st_ino, before.st_rdev)
    assert kept.read_text() == "precious\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["kept.csv"] + (["out.csv"] if kind != "device" else [])
    )


def test_a_full_disk_is_an_output_error_and_leaves_nothing(tmp_path):
    """A write failing for lack of space (here the file-size limit, EFBIG) names the target, exit code 1, and leaves
    neither the target nor the temporary file; an older file under the name is kept."""
    import resource

    from trajectories.errors import OutputError

    target = tmp_path / "big.csv"
    target.write_text("old\n")
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    resource.setrlimit(resource.RLIMIT_FSIZE, (4096, hard))
    try:
        with pytest.raises(OutputError) as exc:
            write_table(target, ("t", "x"), np.zeros((10_000, 2)))
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
    assert exc.value.exit_code == 1 and exc.value.file == str(target) and "nothing was written" in str(exc.value)
    assert target.read_text() == "old\n" and sorted(p.name for p in tmp_path.iterdir()) == ["big.csv"]


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
