"""The one number syntax lbr reads, in files and on the command line: plain ASCII decimals.

``1.5``, ``-2e-3``, ``+.5``, ``10`` are numbers; ``1_0`` (Python would read 10), ``0x10``, non-ASCII digits, ``nan``
and ``inf`` are not — a cell or an option must mean what it looks like to anyone reading it.
"""

from __future__ import annotations

import math
import re

DECIMAL = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?\Z", re.ASCII)
INTEGER = re.compile(r"[+-]?\d+\Z", re.ASCII)
NAN_WORDS = frozenset({"nan", "+nan", "-nan"})


class NotANumber(ValueError):
    """The text is not a plain finite decimal number; ``str()`` says why in a few words."""


def plain_float(text: str) -> float:
    """The finite float ``text`` spells (surrounding white space ignored); NotANumber otherwise."""
    s = str(text).strip()
    if not DECIMAL.match(s):
        if s.lower().lstrip("+-") in ("inf", "infinity", "nan"):
            raise NotANumber(f"not a finite number: {s!r}")
        raise NotANumber(f"not a number: {s!r}" if s else "empty")
    value = float(s)
    if not math.isfinite(value):
        raise NotANumber(f"not a finite number: {s!r} (beyond ±1.8e308)")
    return value


def plain_int(text: str) -> int:
    """The integer ``text`` spells in decimal digits (no '1_0', no '2.0', no '1e3'); NotANumber otherwise."""
    s = str(text).strip()
    if not INTEGER.match(s) or len(s) > 30:
        raise NotANumber(f"not a whole number: {s!r}" if s else "empty")
    return int(s)
