"""The demo's output folder: built in a hidden sibling, swapped in when complete, never mixed with an old run."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

SUMMARY_TITLE = "# lbr demo"


def prepare_out(out: Path) -> str | None:
    """Check that ``out`` may receive the demo; return a description of the previous demo it replaces (or None).

    Raises SettingError ``demo.out`` (exit 2) when ``out`` is a file, or a non-empty folder that is not a previous
    demo.
    """
    from trajectories.errors import SettingError

    if out.exists() and not out.is_dir():
        raise SettingError("demo", "out", f"{out} exists and is not a folder")
    if not out.exists() or not any(out.iterdir()):
        try:
            out.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise SettingError("demo", "out", f"cannot create the folder {out.parent} ({exc.strerror})") from None
        return None
    summary = out / "summary.md"
    try:
        previous = summary.read_text().startswith(SUMMARY_TITLE)
    except OSError:
        previous = False
    if not previous:
        raise SettingError(
            "demo", "out", f"{out} is not empty and holds no previous demo (no summary.md): choose a new folder"
        )
    n = sum(1 for p in out.iterdir() if p.is_file())
    return f"{n} files"


def staging_folder(out: Path) -> Path:
    """A fresh hidden folder next to ``out`` for this run."""
    staging = out.parent / f".{out.name}.partial-{os.getpid()}"
    discard(staging)
    staging.mkdir(parents=True)
    return staging


def publish(staging: Path, out: Path) -> None:
    """Replace ``out`` by ``staging`` (the old folder moved aside first, then deleted)."""
    old = None
    if out.exists():
        old = out.parent / f".{out.name}.old-{os.getpid()}"
        discard(old)
        os.replace(out, old)
    os.replace(staging, out)
    if old is not None:
        discard(old)


def discard(folder: Path) -> None:
    shutil.rmtree(folder, ignore_errors=True)
