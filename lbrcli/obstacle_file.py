"""The obstacle file of `lbr plan anti-sway --obstacles`: boxes on the table, one per row.

Format (CSV, base frame, metres; blank lines and lines starting with '#' are ignored):

    name,x_min,y_min,z_min,x_max,y_max,z_max
    post_a,0.50,-0.20,0.00,0.55,-0.15,0.25

``name`` is any non-empty text (unique); each minimum must be below its maximum. UTF-8, with or without a
byte-order mark; at most 4 MiB.
"""

from __future__ import annotations

import csv
from pathlib import Path

from planners.obstacles import Obstacle
from trajectories.errors import CsvFormatError
from trajectories.numbers import NotANumber, plain_float

OBSTACLE_COLUMNS = ("name", "x_min", "y_min", "z_min", "x_max", "y_max", "z_max")


def read_obstacles(path: str | Path) -> tuple[Obstacle, ...]:
    """Parse the obstacle CSV; raise CsvFormatError (exit 2) naming file, row and column."""
    import io

    from trajectories.inputs import MAX_SMALL_BYTES, read_text_input

    spath = str(path)
    text = read_text_input(path, MAX_SMALL_BYTES)  # a UTF-8 byte-order mark is dropped
    try:
        rows = list(csv.reader(io.StringIO(text, newline="")))
    except csv.Error as exc:
        raise CsvFormatError(f"not a readable CSV file ({exc})", file=spath) from None
    lines = [
        (i + 1, r) for i, r in enumerate(rows) if r and any(c.strip() for c in r) and not r[0].lstrip().startswith("#")
    ]
    if not lines:
        raise CsvFormatError(f"empty; expected the header {','.join(OBSTACLE_COLUMNS)}", file=spath)
    row_no, header = lines[0]
    header = [c.strip() for c in header]
    if tuple(header[: len(OBSTACLE_COLUMNS)]) != OBSTACLE_COLUMNS:
        bad = next((i for i, (a, b) in enumerate(zip(header, OBSTACLE_COLUMNS)) if a != b), min(len(header), 6))
        raise CsvFormatError(
            f"header must start with {','.join(OBSTACLE_COLUMNS)}",
            file=spath,
            row=row_no,
            column=bad + 1,
            column_name=header[bad] if bad < len(header) else None,
        )
    out, names = [], set()
    for row_no, row in lines[1:]:
        if len(row) < len(OBSTACLE_COLUMNS):
            raise CsvFormatError(
                f"expected {len(OBSTACLE_COLUMNS)} columns, got {len(row)}",
                file=spath,
                row=row_no,
                column=len(row) + 1,
                column_name=OBSTACLE_COLUMNS[len(row)],
            )
        name = row[0].strip()
        if not name:
            raise CsvFormatError("empty obstacle name", file=spath, row=row_no, column=1, column_name="name")
        if name in names:
            raise CsvFormatError(
                f"duplicate obstacle name {name!r}", file=spath, row=row_no, column=1, column_name="name"
            )
        vals = []
        for j in range(1, len(OBSTACLE_COLUMNS)):
            try:
                vals.append(plain_float(row[j]))
            except NotANumber as exc:
                raise CsvFormatError(
                    f"{exc} [m]", file=spath, row=row_no, column=j + 1, column_name=OBSTACLE_COLUMNS[j]
                ) from None
        for j in range(3):
            if not vals[j] < vals[j + 3]:
                raise CsvFormatError(
                    f"{OBSTACLE_COLUMNS[j + 4]} = {vals[j + 3]:g} must exceed {OBSTACLE_COLUMNS[j + 1]} = {vals[j]:g}",
                    file=spath,
                    row=row_no,
                    column=j + 5,
                    column_name=OBSTACLE_COLUMNS[j + 4],
                )
        names.add(name)
        out.append(Obstacle(name, tuple(vals[:3]), tuple(vals[3:])))
    return tuple(out)


__all__ = ["read_obstacles", "OBSTACLE_COLUMNS"]
