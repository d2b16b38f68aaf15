"""The track CSV: ``t,frame,u,v,found`` [s, -, px, px, 0/1], then ``theta`` [rad] when a pivot is known,
``pivot_u,pivot_v`` [px] when the pivot is tracked, ``x_m,y_m`` [m] with a plane calibration, and
``confidence,unsure`` [0–1, 0/1]: how sure the tracker was of the frame's fix; a frame it was unsure of (a
candidate seen but not trusted) has found = 0, empty positions and unsure = 1.

Lost frames keep their row with found = 0 and NaN positions and angles; times strictly increase
(variable-frame-rate videos exist). Reading is strict (trajectories.csvio) and names file, row and column.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from trajectories.csvio import read_table, write_table
from trajectories.errors import CsvFormatError

from .pipeline import Track

TRACK_COLUMNS = ("t", "frame", "u", "v", "found")
_NAN_COLUMNS = ("u", "v", "theta", "pivot_u", "pivot_v", "x_m", "y_m", "theta_x", "theta_y", "t_source")


@dataclass(frozen=True)
class TrackTable:
    """A track read back from CSV (optional parts None when their columns are absent)."""

    path: str
    t: np.ndarray  # (n,) [s]
    frame: np.ndarray  # (n,) int
    uv: np.ndarray  # (n, 2) [px], NaN where not found
    found: np.ndarray  # (n,) bool
    theta: np.ndarray | None  # (n,) [rad]
    pivot_uv: np.ndarray | None  # (n, 2) [px]
    xy_m: np.ndarray | None  # (n, 2) [m]
    confidence: np.ndarray | None = None  # (n,) 0–1
    unsure: np.ndarray | None = None  # (n,) bool


def track_columns(track: Track) -> tuple[tuple[str, ...], np.ndarray, list[str]]:
    """Column names, (n, m) data and printf formats of a track."""
    names = list(TRACK_COLUMNS)
    cols = [track.t, track.frame, track.uv[:, 0], track.uv[:, 1], track.found.astype(float)]
    fmt = ["%.6f", "%d", "%.3f", "%.3f", "%d"]
    if track.theta is not None:
        names.append("theta")
        cols.append(track.theta)
        fmt.append("%.6f")
    if track.pivot_uv is not None:
        names += ["pivot_u", "pivot_v"]
        cols += [track.pivot_uv[:, 0], track.pivot_uv[:, 1]]
        fmt += ["%.3f", "%.3f"]
    if track.xy_m is not None:
        names += ["x_m", "y_m"]
        cols += [track.xy_m[:, 0], track.xy_m[:, 1]]
        fmt += ["%.6f", "%.6f"]
    if track.confidence is not None:
        names += ["confidence", "unsure"]
        cols += [track.confidence, track.unsure.astype(float)]
        fmt += ["%.3f", "%d"]
    for name, values in track.extra:
        names.append(name)
        cols.append(np.asarray(values, float))
        fmt.append("%.6g")
    return tuple(names), np.column_stack(cols), fmt


def write_track_csv(path: str | Path, track: Track) -> None:
    """Write the track CSV (NaN cells as 'nan')."""
    names, data, fmt = track_columns(track)
    write_table(path, names, data, fmt)


def read_track_csv(path: str | Path) -> TrackTable:
    """Read a track CSV strictly: header starting t,frame,u,v,found; found ∈ {0, 1} with u, v finite when 1."""
    table = read_table(path, TRACK_COLUMNS, time="increasing", nan_columns=_NAN_COLUMNS)
    found = table.column("found")
    bad = np.flatnonzero((found != 0) & (found != 1))
    if bad.size:
        k = int(bad[0])
        raise CsvFormatError(
            f"found must be 0 or 1, got {found[k]:g}", file=table.path, row=k + 2, column=5, column_name="found"
        )
    uv = table.data[:, 2:4]
    bad = np.flatnonzero((found == 1) & ~np.all(np.isfinite(uv), axis=1))
    if bad.size:
        k = int(bad[0])
        raise CsvFormatError(
            "found = 1 but the position is empty", file=table.path, row=k + 2, column=3, column_name="u"
        )

    def opt(*names: str) -> np.ndarray | None:
        if not all(table.has(n) for n in names):
            return None
        a = np.column_stack([table.column(n) for n in names])
        return a[:, 0] if len(names) == 1 else a

    return TrackTable(
        path=table.path,
        t=table.column("t").copy(),
        frame=table.column("frame").astype(int),
        uv=np.ascontiguousarray(uv),
        found=found == 1,
        theta=opt("theta"),
        pivot_uv=opt("pivot_u", "pivot_v"),
        xy_m=opt("x_m", "y_m"),
        confidence=opt("confidence"),
        unsure=(opt("unsure") == 1) if table.has("unsure") else None,
    )
