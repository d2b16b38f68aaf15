"""Strict CSV reading and writing for every lbr file, in one place.

Every malformed input raises :class:`CsvFormatError` naming file, row (1-based line number) and column.
"""

from __future__ import annotations

import csv
import io
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Literal, Sequence

import numpy as np

from .atomic import atomic_path
from .errors import CsvFormatError
from .inputs import MAX_CSV_BYTES, read_input
from .numbers import DECIMAL, NAN_WORDS, NotANumber, plain_float
from .trajectory import N_JOINTS, JointTrajectory, TaskTrajectory

JOINT_COLUMNS = ("t",) + tuple(f"q{i}" for i in range(1, N_JOINTS + 1))
TASK_COLUMNS = ("t", "x", "y", "z", "qw", "qx", "qy", "qz")
PREDICTION_COLUMNS = ("t", "theta")

_NOT_BLANK = re.compile(rb"[^\s,]")  # a line or text holding more than separators and white space

TimeRule = Literal["uniform", "increasing", "none"]

# A uniform grid written with a few decimals (e.g. 0.005) reads back exactly; allow float noise only.
_UNIFORM_ABS_TOL = 1e-6  # [s]
_UNIFORM_REL_TOL = 1e-4


@dataclass(frozen=True)
class Table:
    """A parsed numeric CSV: column names and an (n, m) float array."""

    path: str
    names: tuple[str, ...]
    data: np.ndarray

    def column(self, name: str) -> np.ndarray:
        return self.data[:, self.names.index(name)]

    def has(self, name: str) -> bool:
        return name in self.names


def _parse_float(cell: str, *, path: str, row: int, col: int, name: str, allow_nan: bool) -> float:
    text = cell.strip()
    if text == "":
        if allow_nan:
            return math.nan
        raise CsvFormatError("empty cell", file=path, row=row, column=col, column_name=name)
    if allow_nan and text.lower() in NAN_WORDS:
        return math.nan
    try:
        return plain_float(text)
    except NotANumber as exc:
        raise CsvFormatError(str(exc), file=path, row=row, column=col, column_name=name) from None


def _looks_numeric(cells: Sequence[str]) -> bool:
    try:
        [float(c) for c in cells]
    except ValueError:
        return False
    return True


def _check_time(t: np.ndarray, path: str, rule: TimeRule, first_row: int) -> None:
    if rule == "none" or len(t) == 0:
        return
    if abs(t[0]) > _UNIFORM_ABS_TOL:
        raise CsvFormatError(
            f"time must start at 0, got {t[0]:g} s", file=path, row=first_row, column=1, column_name="t"
        )
    if len(t) < 2:
        return
    dt = np.diff(t)
    bad = np.flatnonzero(dt <= 0.0)
    if bad.size:
        k = int(bad[0]) + 1
        raise CsvFormatError(
            f"time not increasing ({t[k - 1]:g} s then {t[k]:g} s)",
            file=path,
            row=first_row + k,
            column=1,
            column_name="t",
        )
    if rule == "uniform":
        h = (t[-1] - t[0]) / (len(t) - 1)
        tol = _UNIFORM_ABS_TOL + _UNIFORM_REL_TOL * h
        off = np.abs(dt - h)
        bad = np.flatnonzero(off > tol)
        if bad.size:
            k = int(bad[0]) + 1
            raise CsvFormatError(
                f"time step not uniform: {dt[k - 1]:g} s here, {h:g} s on average",
                file=path,
                row=first_row + k,
                column=1,
                column_name="t",
            )


def _read_bytes(path: str | Path, spath: str) -> bytes:
    """The whole file, bounded (:func:`trajectories.inputs.read_input`), a leading UTF-8 byte-order mark dropped."""
    raw = read_input(path, MAX_CSV_BYTES, error=CsvFormatError)
    return raw[3:] if raw.startswith(b"\xef\xbb\xbf") else raw


def _decode(raw: bytes, start: int, end: int, spath: str) -> str:
    """UTF-8 text of raw[start:end]; a byte that is not UTF-8 is named by its row."""
    try:
        return raw[start:end].decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw[: start + exc.start].count(b"\n") + 1
        raise CsvFormatError(
            f"not a readable CSV file (not UTF-8 text: byte {raw[start + exc.start]:#04x})", file=spath, row=line
        ) from None


def _first_line(raw: bytes) -> tuple[int, int, int, int]:
    """(1-based line number, offset, end, offset of the next line) of the first line that is not blank."""
    pos, line_no = 0, 1
    while pos < len(raw):
        end = raw.find(b"\n", pos)
        end = len(raw) if end < 0 else end
        if _NOT_BLANK.search(raw, pos, end):
            return line_no, pos, end, end + 1
        pos, line_no = end + 1, line_no + 1
    return 0, len(raw), len(raw), len(raw)


ARROW_MIN_BYTES = 1 << 20  # [bytes] bodies this large are parsed by Arrow's CSV reader (≈ 4× numpy's; its import
# costs ≈ 0.1 s, more than numpy takes for a small file)


def _arrow_body(raw: bytes, start: int, end: int, width: int) -> np.ndarray | None:
    """raw[start:end] parsed by Arrow's C++ CSV reader as ``width`` float64 columns, nothing read as missing (an
    empty cell is a fault here, as for numpy); None when Arrow refuses anything (the strict reader names it)."""
    import pyarrow as pa
    import pyarrow.csv as pacsv

    names = [f"c{j}" for j in range(width)]
    try:
        table = pacsv.read_csv(
            pa.py_buffer(memoryview(raw)[start:end]),
            read_options=pacsv.ReadOptions(column_names=names, use_threads=True),
            parse_options=pacsv.ParseOptions(delimiter=",", quote_char=False, double_quote=False,
                                             ignore_empty_lines=False),
            convert_options=pacsv.ConvertOptions(column_types={n: pa.float64() for n in names}, null_values=[],
                                                 strings_can_be_null=False, quoted_strings_can_be_null=False,
                                                 check_utf8=True),
        )  # fmt: skip
    except (pa.ArrowInvalid, pa.ArrowNotImplementedError, ValueError):
        return None
    data = np.empty((table.num_rows, width), dtype=float)
    for j, column in enumerate(table.columns):
        data[:, j] = column.to_numpy()
    return data


def _fast_body(raw: bytes, start: int, width: int, nan_ok: set[int]) -> np.ndarray | None:
    """Parse the data rows (raw[start:]) with numpy's C reader; None when anything is unusual (blank lines, quotes, empty or malformed cells, a wrong
    number of cells, a non-finite value outside ``nan_ok``, not UTF-8): the strict per-cell reader then finds and
    names the fault."""
    import warnings

    end = len(raw)
    while end > start and raw[end - 1 : end] in (b"\n", b"\r", b" ", b"\t"):
        end -= 1  # trailing blank lines do not shift any row number
    if end == start or raw.find(b'"', start, end) >= 0:
        return None
    lines = raw.count(b"\n", start, end) + 1
    if end - start >= ARROW_MIN_BYTES:
        data = _arrow_body(raw, start, end, width)
    else:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error")  # e.g. "input contained no data"
                data = np.loadtxt(
                    io.BytesIO(raw[start:end]), delimiter=",", comments=None, dtype=float, ndmin=2, encoding="utf-8"
                )
        except (ValueError, UserWarning):  # UnicodeDecodeError is a ValueError
            return None
    if data is None:
        return None
    if data.shape != (lines, width):  # blank lines were skipped, or the column count differs
        return None
    finite = np.isfinite(data)
    if not finite.all():
        bad_cols = set(np.flatnonzero(~finite.all(axis=0)).tolist())
        if not bad_cols <= nan_ok or np.isinf(data[:, sorted(bad_cols)]).any():
            return None
    return data


def _parse_rows(
    rows: list[tuple[int, list[str]]], width: int, names: Sequence[str], nan_ok: set[int], spath: str, block: int = 2048
) -> np.ndarray:
    """The strict reader: blocks of rows converted at once, a block with any fault cell by cell, so that the first
    fault in the file is named by file, row and column."""
    data = np.empty((len(rows), width), dtype=float)
    allowed = np.zeros(width, dtype=bool)
    allowed[sorted(nan_ok)] = True
    for b0 in range(0, len(rows), block):
        chunk = rows[b0 : b0 + block]
        cells = [r for _, r in chunk]
        if all(len(r) == width for r in cells):
            try:
                values = np.array(cells, dtype=float)
            except ValueError:
                values = None
            if values is not None and not all(DECIMAL.match(c.strip()) or c.strip().lower() in NAN_WORDS
                                              for r in cells for c in r):  # fmt: skip
                values = None  # e.g. '1_0', which numpy reads as 10: the cell-by-cell reader names it
            if values is not None:
                finite = np.isfinite(values)
                if finite.all() or not (~finite & ~allowed).any() and not np.isinf(values).any():
                    data[b0 : b0 + len(chunk)] = values
                    continue
        for i, (line, row_cells) in enumerate(chunk, start=b0):
            if len(row_cells) != width:
                what = "missing" if len(row_cells) < width else "extra"
                col = min(len(row_cells), width) + 1 if len(row_cells) < width else width + 1
                raise CsvFormatError(
                    f"{what} columns: {len(row_cells)} cells, expected {width}", file=spath, row=line, column=col
                )
            for j, cell in enumerate(row_cells):
                data[i, j] = _parse_float(cell, path=spath, row=line, col=j + 1, name=names[j], allow_nan=j in nan_ok)
    return data


def _csv_rows(text: str, spath: str, first_line: int = 1) -> list[tuple[int, list[str]]]:
    """Non-blank CSV rows with their 1-based line numbers."""
    try:
        rows = list(csv.reader(io.StringIO(text, newline="")))
    except csv.Error as exc:
        raise CsvFormatError(f"not a readable CSV file ({exc})", file=spath) from None
    return [(first_line + i, r) for i, r in enumerate(rows) if any(c.strip() for c in r)]


_DT = "read_table.headerless_dt"  # the setting a headerless file's step comes from (the commands' sample-step option)


def read_table(
    path: str | Path,
    columns: Sequence[str],
    *,
    time: TimeRule = "uniform",
    nan_columns: Sequence[str] = (),
    headerless_dt: float | None = None,
    headerless_width: int | None = None,
) -> Table:
    """Read a numeric CSV whose header starts with ``columns`` (extra named columns may follow).

    A headerless file of exactly ``headerless_width`` numeric columns is accepted when ``headerless_dt`` [s]
    is given; it gets the column names ``columns[1:]`` and a time column t = k·dt.
    Cells of ``nan_columns`` and of every extra column after ``columns`` may be empty or 'nan' (a missing value,
    e.g. the ball position of a frame where it was not found); the required columns must hold numbers.
    UTF-8 with or without a byte-order mark. Well-formed files are parsed by a C reader (numpy's; Arrow's for bodies
    of ≥ 1 MiB); any fault sends the file through the strict per-cell reader, which names it.
    """
    spath = str(path)
    raw = _read_bytes(path, spath)
    first_line, first_start, first_end, body_start = _first_line(raw)
    if first_line == 0:
        raise CsvFormatError("empty file", file=spath)
    first = _csv_rows(_decode(raw, first_start, first_end, spath), spath, first_line)[0][1]

    headerless = False
    if _looks_numeric(first):
        if headerless_width is None or len(first) != headerless_width:
            expected = ",".join(columns)
            raise CsvFormatError(f"missing header; expected '{expected}'", file=spath, row=first_line)
        if headerless_dt is None:
            raise CsvFormatError(f"headerless {headerless_width}-column file: give the sample step with {_DT}",
                                 file=spath, row=first_line)  # fmt: skip
        if not (headerless_dt > 0 and math.isfinite(headerless_dt)):
            raise CsvFormatError(f"{_DT} must be a positive number of seconds, got {headerless_dt:g}", file=spath)
        names = tuple(columns[1:])
        headerless = True
        body_start, body_line = first_start, first_line
    else:
        names = tuple(c.strip() for c in first)
        for j, want in enumerate(columns):
            if j >= len(names):
                raise CsvFormatError(f"missing column '{want}'", file=spath, row=first_line, column=j + 1)
            if names[j] != want:
                raise CsvFormatError(
                    f"wrong header: expected '{want}', found '{names[j]}'",
                    file=spath,
                    row=first_line,
                    column=j + 1,
                )
        for j, name in enumerate(names):
            if name == "":
                raise CsvFormatError("empty column name", file=spath, row=first_line, column=j + 1)
        if len(set(names)) != len(names):
            dup = next(n for n in names if names.count(n) > 1)
            raise CsvFormatError(f"duplicate column '{dup}'", file=spath, row=first_line, column=names.index(dup) + 1)
        body_line = first_line + 1
        if not _NOT_BLANK.search(raw, body_start):
            raise CsvFormatError("no data rows after the header", file=spath, row=first_line)

    width = len(names)
    # a missing value (empty cell or nan) is allowed in the named columns and in every column after the required ones
    nan_ok = {names.index(c) for c in nan_columns if c in names} | set(range(len(columns) if not headerless else width,
                                                                             width))  # fmt: skip
    data = _fast_body(raw, body_start, width, nan_ok)
    if data is None:
        rows = _csv_rows(_decode(raw, body_start, len(raw), spath), spath, body_line)
        if not rows:
            raise CsvFormatError("no data rows after the header", file=spath, row=first_line)
        data = _parse_rows(rows, width, names, nan_ok, spath)
        body_line = rows[0][0]

    if headerless:
        t = np.arange(len(data)) * float(headerless_dt)
        data = np.column_stack([t, data])
        names = tuple(columns[:1]) + names
    else:
        _check_time(data[:, 0], spath, time, body_line)
    return Table(path=spath, names=names, data=data)


def float_first_row(fmt: str) -> str:
    """The format of a file's first data row: a ``%…g`` field in its alternate form (``%#…g``: always a decimal
    point), so that readers which type columns from their first rows (polars, DuckDB) take them as floats even where
    later rows hold whole numbers (``0``)."""
    return re.sub(r"%(\.\d+)?g", lambda m: "%#" + (m.group(1) or "") + "g", fmt)


def write_table(path: str | Path, names: Sequence[str], data: np.ndarray, fmt: str | Sequence[str] = "%.10g") -> None:
    """Write an (n, m) array with a header line, atomically (a temporary name renamed when complete). Float columns
    read as floats everywhere (:func:`float_first_row`); NaN is written as ``nan`` (a missing value)."""
    data = np.asarray(data, dtype=float)
    if data.ndim == 1:
        data = data[:, None]
    fmts = [fmt] * data.shape[1] if isinstance(fmt, str) else list(fmt)
    row = ",".join(fmts)
    first = ",".join(float_first_row(f) for f in fmts)
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="utf-8", newline="\n") as fh:
            fh.write(",".join(names) + "\n")
            lines = [(first if i == 0 else row) % tuple(r) for i, r in enumerate(data.reshape(len(data), -1).tolist())]
            fh.write("\n".join(lines) + ("\n" if lines else ""))


# What a joint or task file can plausibly hold; beyond it the file is wrong (units, a corrupted cell), and the
# arithmetic downstream would overflow.
MAX_JOINT_ANGLE = 2 * math.pi  # [rad] every iiwa joint stays within ±175°
MAX_TASK_POSITION = 10.0  # [m] the arm reaches 0.8 m; millimetres read as metres land here
STEP_RANGE = (1e-5, 60.0)  # [s] sample step of a trajectory file


def _check_plausible(table: Table, first: int, width: int, bound: float, what: str) -> None:
    """CsvFormatError naming row and column of the first |value| > bound in columns first..first+width-1."""
    block = table.data[:, first : first + width]
    bad = np.argwhere(np.abs(block) > bound)
    if bad.size:
        k, j = (int(v) for v in bad[0])
        raise CsvFormatError(f"{what} {block[k, j]:g} is beyond ±{bound:g}", file=table.path, row=k + 2,
                             column=first + j + 1, column_name=table.names[first + j])  # fmt: skip
    t = table.data[:, 0]
    if len(t) > 1:
        step = (t[-1] - t[0]) / (len(t) - 1)
        if not STEP_RANGE[0] <= step <= STEP_RANGE[1]:
            raise CsvFormatError(f"time step {step:g} s is outside {STEP_RANGE[0]:g}..{STEP_RANGE[1]:g} s",
                                 file=table.path, row=3, column=1, column_name="t")  # fmt: skip


def read_joint_csv(path: str | Path, dt: float | None = None) -> JointTrajectory:
    """Read a joint trajectory (``t,q1..q7`` [s, rad]); a headerless 7-column file needs ``dt`` [s]."""
    table = read_table(path, JOINT_COLUMNS, headerless_dt=dt, headerless_width=N_JOINTS)
    if len(table.data) < 1:
        raise CsvFormatError("no samples", file=table.path)
    _check_plausible(table, 1, N_JOINTS, MAX_JOINT_ANGLE, "joint angle [rad]")
    return JointTrajectory(t=table.data[:, 0].copy(), q=np.ascontiguousarray(table.data[:, 1 : 1 + N_JOINTS]))


def write_joint_csv(path: str | Path, traj: JointTrajectory) -> None:
    """Write ``t,q1..q7`` with 1e-9 s and 1e-12 rad resolution."""
    write_table(path, JOINT_COLUMNS, np.column_stack([traj.t, traj.q]), fmt=["%.9f"] + ["%.12f"] * N_JOINTS)


def read_task_csv(path: str | Path) -> TaskTrajectory:
    """Read a task trajectory (``t,x,y,z,qw,qx,qy,qz`` [s, m]); quaternions must be unit (within 1e-3)."""
    table = read_table(path, TASK_COLUMNS)
    _check_plausible(table, 1, 3, MAX_TASK_POSITION, "position [m]")
    quat = table.data[:, 4:8]
    norms = np.linalg.norm(quat, axis=1)
    bad = np.flatnonzero(np.abs(norms - 1.0) > 1e-3)
    if bad.size:
        k = int(bad[0])
        raise CsvFormatError(
            f"quaternion not unit (norm {norms[k]:.6g})", file=table.path, row=k + 2, column=5, column_name="qw"
        )
    return TaskTrajectory(
        t=table.data[:, 0].copy(),
        position=np.ascontiguousarray(table.data[:, 1:4]),
        quaternion=np.ascontiguousarray(quat / norms[:, None]),
    )


def write_task_csv(path: str | Path, traj: TaskTrajectory) -> None:
    """Write ``t,x,y,z,qw,qx,qy,qz`` with 1e-12 m resolution."""
    write_table(
        path, TASK_COLUMNS, np.column_stack([traj.t, traj.position, traj.quaternion]), fmt=["%.9f"] + ["%.12f"] * 7
    )
