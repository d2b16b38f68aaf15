"""Whether an execution log shows a session that completed what it was asked to do.

Downstream commands (`lbr track film`, `lbr compare --column ...`) refuse a log whose session stopped early — a
loaded machine, a safety stop, Ctrl-C, a killed process — unless given ``--partial``: a film or a comparison of
0.3 s of a 7 s move is not the experiment. The log tells from its rows (``lbrcli.fri.log``):

- ``file_rows`` (written by `lbr execute`): the number of rows the player streams; the session completed when
  the ``row`` column reached the last of them.
- otherwise, a log whose client played rows or a move (``phase`` TRAJECTORY or MOVE) completed when SETTLE rows
  follow the last of them (the player settles only after its last row);
- a log of a client that plays nothing (monitor, serve, control) cannot tell: it is taken as it is.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

FILE_ROWS_COLUMN = "file_rows"  # extra log column of `lbr execute`: rows the player streams


@dataclass(frozen=True)
class SessionEnd:
    """What the log says about the end of its session."""

    complete: bool
    reason: str  # why it is not complete (empty when complete)
    t_end: float  # [s] log time of the last row
    row: int  # 1-based file line of the last row


def session_end(table) -> SessionEnd:
    """Judge a log read by :func:`trajectories.csvio.read_table` (columns of ``lbrcli.fri.log``)."""
    from lbrcli.fri.log import PHASE_MOVE, PHASE_SETTLE, PHASE_TRAJECTORY

    t = table.column("t")
    n = len(t)
    t_end = float(t[-1]) if n else 0.0
    end = SessionEnd(True, "", t_end, n + 1)
    if n < 2:
        return SessionEnd(False, f"only {n} row", t_end, n + 1)
    if table.has(FILE_ROWS_COLUMN) and table.has("row"):
        rows = int(np.max(table.column(FILE_ROWS_COLUMN)))
        reached = int(np.max(table.column("row")))
        if rows > 0 and reached < rows - 1:
            return SessionEnd(False, f"it stopped at row {reached + 1} of the {rows} it streams", t_end, n + 1)
        return end
    if not table.has("phase"):
        return end
    phase = table.column("phase")
    played = np.flatnonzero((phase == PHASE_TRAJECTORY) | (phase == PHASE_MOVE))
    if played.size == 0:
        return end
    if not np.any(phase[played[-1] + 1 :] == PHASE_SETTLE):
        what = "its rows" if np.any(phase == PHASE_TRAJECTORY) else "its move"
        return SessionEnd(False, f"it stopped before the end of {what} (no settling after the last one at "
                                 f"t = {t[played[-1]]:.3f} s)", t_end, n + 1)  # fmt: skip
    return end


def require_complete(table, partial: bool, rep=None, *, option: str = "partial") -> SessionEnd:
    """:func:`session_end`, raising InputError (exit 2, naming the log) for an incomplete session unless
    ``partial``; with ``partial`` a warning on ``rep`` says what is used. ``option``: how the caller's user asks for
    a partial log (the command's flag)."""
    from trajectories.errors import InputError

    end = session_end(table)
    if not end.complete:
        if not partial:
            raise InputError(f"the session of this log did not complete ({end.reason}, log ends at {end.t_end:.3f} "
                             f"s); give {option} to use it anyway", file=table.path)  # fmt: skip
        if rep is not None:
            rep.warn(f"{table.path}: the session did not complete ({end.reason}); using the {end.t_end:.3f} s logged "
                     f"({option})")  # fmt: skip
    return end
