"""Reading an input file whole, bounded: a size limit with a clear message, never an endless read.

Every text input (CSV, TOML, JSON, a secret) goes through :func:`read_input`: a regular file larger than the
limit is refused from its size; a pipe or a device is read up to the limit (``/dev/zero`` is refused at its first
NUL byte, a FIFO nobody writes to reads as empty instead of blocking). Errors are :class:`InputError` (exit 2)
naming the file.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from .errors import InputError

MIB = 1 << 20
MAX_CSV_BYTES = 2048 * MIB  # a 1 kHz execution log grows ≈ 0.8 MB/s (45 min); plans and tracks are ≪ 100 MB
MAX_SMALL_BYTES = 4 * MIB  # TOML limits, JSON calibrations, obstacle lists, secrets
_CHUNK = 1 * MIB


def _size_text(n: int) -> str:
    return f"{n / MIB:g} MiB" if n >= MIB else f"{n} bytes"


def read_input(
    path: str | Path,
    limit: int = MAX_CSV_BYTES,
    *,
    text: bool = True,
    error: type[InputError] = InputError,
    what: str = "file",
) -> bytes:
    """The bytes of ``path`` (at most ``limit``); ``error`` (an InputError) naming the file when it is missing, a
    folder, unreadable, larger than ``limit``, or (``text``) holds a NUL byte."""
    spath = str(path)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)  # a FIFO without a writer must not block the open
    except FileNotFoundError:
        raise error(f"{what} not found", file=spath) from None
    except IsADirectoryError:
        raise error("is a directory, not a file", file=spath) from None
    except OSError as exc:
        raise error(f"cannot open: {exc.strerror}", file=spath) from None
    try:
        st = os.fstat(fd)
        if stat.S_ISDIR(st.st_mode):
            raise error("is a directory, not a file", file=spath)
        if stat.S_ISREG(st.st_mode) and st.st_size > limit:
            raise error(f"is {_size_text(st.st_size)}, more than lbr reads ({_size_text(limit)})", file=spath)
        os.set_blocking(fd, True)
        chunks: list[bytes] = []
        total = 0
        while True:
            try:
                chunk = os.read(fd, min(_CHUNK, limit + 1 - total))
            except OSError as exc:
                raise error(f"cannot read: {exc.strerror}", file=spath) from None
            if not chunk:
                break
            if text and b"\0" in chunk:
                at = total + chunk.index(b"\0")
                raise error(f"not a text file (a NUL byte at offset {at})", file=spath)
            chunks.append(chunk)
            total += len(chunk)
            if total > limit:
                raise error(f"is larger than lbr reads ({_size_text(limit)})", file=spath)
    finally:
        os.close(fd)
    return b"".join(chunks)


def read_text_input(path: str | Path, limit: int = MAX_SMALL_BYTES, what: str = "file") -> str:
    """:func:`read_input` decoded as UTF-8 (a leading byte-order mark dropped); InputError naming the line of a
    byte that is not UTF-8."""
    raw = read_input(path, limit, what=what)
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise InputError(f"not UTF-8 text (byte {raw[exc.start]:#04x})", file=str(path), row=line) from None


def require_regular(path: str | Path) -> None:
    """InputError unless ``path`` is an existing regular file (for readers that cannot bound their reads, e.g.
    video decoders: a device or a FIFO would block or never end)."""
    spath = str(path)
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise InputError("file not found", file=spath) from None
    except OSError as exc:
        raise InputError(f"cannot open: {exc.strerror}", file=spath) from None
    if stat.S_ISDIR(st.st_mode):
        raise InputError("is a directory, not a file", file=spath)
    if not stat.S_ISREG(st.st_mode):
        raise InputError("is not a regular file (a device, FIFO or socket)", file=spath)
