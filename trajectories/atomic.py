"""Atomic file output: write under a temporary name in the target's folder, rename over the target when complete.

An interrupted or failed write never leaves a half-written file under the final name (``os.replace`` is atomic on
POSIX within one file system). The temporary name keeps the target's suffix so that writers choosing the format
from the name (matplotlib, ``np.savetxt`` with ``.gz``, OpenCV) behave as for the target; it is created exclusively
(``mkstemp``), so a file or link planted under a guessable name is never written through.

Only regular files are replaced: a target that is a symbolic link, a device (``/dev/null``), a FIFO or a socket is
refused (:class:`OutputRefused`, exit 2) — renaming over it would destroy it. A write that fails for lack of space,
quota or an I/O error raises :class:`OutputError` (exit 1) naming the target; other file-system errors name the
target too (never the temporary name).
"""

from __future__ import annotations

import contextlib
import errno
import os
import stat
import tempfile
from pathlib import Path
from typing import Iterator

PART_MARK = ".part"  # temporary files are named .<stem>.<random>.part<suffix>
# errors of the medium, not of the path the user gave: the job failed (exit 1)
FAILED_WRITE_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO})


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


_FILE_MODE = 0o666 & ~_umask()  # what open() would give a new file


def temporary_name(path: str | Path) -> Path:
    """A fresh, exclusively created temporary sibling of ``path`` (hidden, same suffix); the caller owns it."""
    p = Path(path)
    fd, name = tempfile.mkstemp(prefix=f".{p.stem}.", suffix=f"{PART_MARK}{p.suffix}", dir=p.parent)
    try:
        os.fchmod(fd, _FILE_MODE)
    finally:
        os.close(fd)
    return Path(name)


def _kind(mode: int) -> str | None:
    """What a non-regular file is, in words (None for a regular file or a directory)."""
    for test, what in ((stat.S_ISLNK, "a symbolic link"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                       (stat.S_ISSOCK, "a socket")):  # fmt: skip
        if test(mode):
            return what
    return None


def refuse_special(path: str | Path, option: str | None = None) -> None:
    """OutputRefused (exit 2) when ``path`` exists and is not a regular file or a folder: lbr never replaces a
    symbolic link, a device, a FIFO or a socket with an output."""
    from .errors import OutputRefused

    try:
        mode = os.lstat(path).st_mode
    except OSError:
        return  # absent (or unreadable: the write itself will say)
    what = _kind(mode)
    if what is None:
        return
    if stat.S_ISLNK(mode):
        with contextlib.suppress(OSError):
            what += f" (to {os.readlink(path)})"
    name = f"{option} {path}" if option else str(path)
    raise OutputRefused(f"{name} is {what}: lbr replaces only regular files with its outputs (remove it or choose "
                        "another name)", file=path)  # fmt: skip


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path to write; on normal exit rename it to ``path``, on any exception delete it.

    Refuses (before anything is written) a target that is a link, a device, a FIFO or a socket. File-system errors
    name ``path`` (not the temporary name): a missing folder, a directory in the way, no permission; a full disk,
    an exceeded quota or file-size limit and I/O errors are :class:`OutputError`.
    """
    target = Path(path)
    refuse_special(target)
    if target.is_dir():
        raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(target))
    if not target.parent.is_dir():
        raise FileNotFoundError(errno.ENOENT, f"{os.strerror(errno.ENOENT)} (no folder {target.parent})", str(target))
    try:
        tmp = temporary_name(target)
    except OSError as exc:
        raise _about_target(exc, target, None) from None
    try:
        yield tmp
        refuse_special(target)  # still not a link or device (it may have appeared while the output was written)
        os.replace(tmp, target)
    except OSError as exc:
        _discard(tmp)
        raise _about_target(exc, target, tmp) from None
    except BaseException:
        _discard(tmp)
        raise


def _about_target(exc: OSError, target: Path, tmp: Path | None) -> BaseException:
    """The error to raise for ``exc`` met while writing ``target``: OutputError for a failed medium, else the same
    OSError naming the target when it named the temporary file or nothing."""
    from .errors import OutputError

    if exc.errno in FAILED_WRITE_ERRNOS:
        return OutputError(f"cannot write: {os.strerror(exc.errno)}; nothing was written under this name",
                           file=target)  # fmt: skip
    if exc.filename is None or (tmp is not None and exc.filename in (str(tmp), tmp)):
        return type(exc)(exc.errno, exc.strerror or str(exc), str(target))
    return exc


@contextlib.contextmanager
def atomic_open(path: str | Path, mode: str = "w", **kwargs) -> Iterator:
    """``open`` for writing through :func:`atomic_path`: the file appears under ``path`` only once closed."""
    with atomic_path(path) as tmp:
        with open(tmp, mode, **kwargs) as fh:
            yield fh


def _discard(tmp: Path) -> None:
    with contextlib.suppress(OSError):
        tmp.unlink()
