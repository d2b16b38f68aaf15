"""The demo's folder: built aside, swapped in complete, an old demo replaced only as a whole."""

import pytest

from lbrcli.demo.folder import discard, prepare_out, publish, staging_folder
from trajectories.errors import OptionError


def test_fresh_and_empty_folders_are_accepted(tmp_path):
    assert prepare_out(tmp_path / "new" / "demo") is None
    (tmp_path / "empty").mkdir()
    assert prepare_out(tmp_path / "empty") is None


def test_a_previous_demo_is_replaced_whole(tmp_path):
    out = tmp_path / "lbr-demo"
    out.mkdir()
    (out / "summary.md").write_text("# lbr demo\n\nold\n")
    (out / "old_only.csv").write_text("1\n")
    assert prepare_out(out) == "2 files"
    staging = staging_folder(out)
    (staging / "summary.md").write_text("# lbr demo\n\nnew\n")
    publish(staging, out)
    assert sorted(p.name for p in out.iterdir()) == ["summary.md"]  # nothing of the old run mixed in
    assert "new" in (out / "summary.md").read_text()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lbr-demo"]  # no staging or old folder left


def test_an_interrupted_run_leaves_the_old_demo_as_it_was(tmp_path):
    out = tmp_path / "lbr-demo"
    out.mkdir()
    (out / "summary.md").write_text("# lbr demo\nold\n")
    staging = staging_folder(out)
    (staging / "half.csv").write_text("t,q1\n0,")
    discard(staging)  # what `lbr demo` does on Ctrl-C
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lbr-demo"]
    assert (out / "summary.md").read_text() == "# lbr demo\nold\n"


def test_other_work_is_never_replaced(tmp_path):
    (tmp_path / "data.csv").write_text("x")
    with pytest.raises(OptionError, match="holds no previous demo"):
        prepare_out(tmp_path)
    (tmp_path / "summary.md").write_text("# my summary\n")
    with pytest.raises(OptionError, match="holds no previous demo"):
        prepare_out(tmp_path)
