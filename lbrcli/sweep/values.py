"""Option values of a study: canonical form (for the cache key) and command-line text (for the run and its
equivalent `lbr` line)."""

from __future__ import annotations

import json
import math
from typing import Any

SIGNIFICANT = 12  # digits a float keeps: grids computed two ways (extended linspace) give the same run


def canonical(value: Any) -> Any:
    """A hashable canonical form of a TOML value: floats rounded to 12 significant digits, lists as tuples."""
    if isinstance(value, bool) or value is None or isinstance(value, (int, str)):
        return value
    if isinstance(value, float):
        return float(f"{value:.{SIGNIFICANT}g}") if math.isfinite(value) else value
    if hasattr(value, "tolist"):  # numpy scalars and arrays
        return canonical(value.tolist())
    if isinstance(value, (list, tuple)):
        return tuple(canonical(v) for v in value)
    if isinstance(value, dict):
        return Table(sorted((str(k), canonical(v)) for k, v in value.items()))
    raise TypeError(f"not a study value: {value!r}")


class Table(tuple):
    """An inline TOML table in canonical form: sorted (key, value) pairs (hashable, picklable)."""

    def as_dict(self) -> dict:
        return dict(self)


def plain(value: Any) -> Any:
    """A canonical value back as JSON-able: tuples → lists, tables → dicts."""
    if isinstance(value, Table):
        return {k: plain(v) for k, v in value}
    if isinstance(value, tuple):
        return [plain(v) for v in value]
    return value


def cli_text(value: Any) -> str:
    """How a value is typed on the command line: numbers as Python writes them (exact), a list of numbers
    'a,b,c', a list of lists 'a,b;c,d' (the --points form)."""
    if isinstance(value, (list, tuple)):
        if value and all(isinstance(v, (list, tuple)) for v in value):
            return ";".join(",".join(cli_text(x) for x in v) for v in value)
        return ",".join(cli_text(v) for v in value)
    if isinstance(value, float):
        return repr(value)
    return str(value)


def table_cell(value: Any) -> Any:
    """A value for one table cell: scalars as they are, anything else as JSON text."""
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    return json.dumps(plain(value) if isinstance(value, tuple) else value, separators=(",", ":"))
