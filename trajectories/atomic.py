"""Atomic file output: write under a temporary name in the target's folder, rename over the target when complete.

An interrupted or failed write never leaves a half-written file under the final name (``os.replace`` is atomic on
POSIX within one file system). The temporary name keeps the target's suffix so that writers choosing the format
from the name (matplotlib, ``np.savetxt`` with ``.gz``, OpenCV) behave as for the target.
"""

from __future__ import annotations

import contextlib
import errno
import os
from pathlib import Path
from typing import Iterator

PART_MARK = ".part"  # temporary files are named .<stem>.<pid>.part<suffix>


def temporary_name(path: str | Path) -> Path:
    """The temporary sibling of ``path`` used while it is written (hidden, per process, same suffix)."""
    p = Path(path)
    return p.with_name(f".{p.stem}.{os.getpid()}{PART_MARK}{p.suffix}")


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path to write; on normal exit rename it to ``path``, on any exception delete it.

    File-system errors name ``path`` (not the temporary name): a missing folder, a directory in the way, no
    permission.
    """
    target = Path(path)
    if target.is_dir():
        raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(target))
    if not target.parent.is_dir():
        raise FileNotFoundError(errno.ENOENT, f"{os.strerror(errno.ENOENT)} (no folder {target.parent})", str(target))
    tmp = temporary_name(target)
    try:
        yield tmp
        os.replace(tmp, target)
    except OSError as exc:
        _discard(tmp)
        if exc.filename in (str(tmp), tmp):
            raise type(exc)(exc.errno, exc.strerror, str(target)) from None
        raise
    except BaseException:
        _discard(tmp)
        raise


@contextlib.contextmanager
def atomic_open(path: str | Path, mode: str = "w", **kwargs) -> Iterator:
    """``open`` for writing through :func:`atomic_path`: the file appears under ``path`` only once closed."""
    with atomic_path(path) as tmp:
        with open(tmp, mode, **kwargs) as fh:
            yield fh


def _discard(tmp: Path) -> None:
    with contextlib.suppress(OSError):
        tmp.unlink()
