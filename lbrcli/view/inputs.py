"""Every file `lbr` writes, read for the 3D view: recognised by its header, turned into arm, ball, state and path
series (each on its own file's clock; :mod:`lbrcli.view.timeline` puts them on one time line).

Ball directions are unit string directions s in the base frame (the ball at pivot + length·s):
- a prediction with ``phi`` (anti-sway) or an execution log's ``ball_theta``/``ball_phi`` (the simulator):
  s = (sin θ cos φ, sin θ sin φ, −cos θ);
- a prediction with ``theta`` only (swing-up) and a track's ``theta``: the planar angle in the base y–z plane,
  positive toward +y (the swing-up's plane; the film's camera sees image right = base +y), s = (0, sin θ, −cos θ).
A file whose columns carry the ball's position (``ball_x,ball_y,ball_z`` [m], base frame) is drawn there.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from trajectories.errors import CsvFormatError

JOINT = "joint trajectory"
TASK = "task trajectory"
LOG = "execution log"
PREDICTION = "prediction"
TRACK = "track"
OBSTACLES = "obstacles"
BALL_POSITION_COLUMNS = ("ball_x", "ball_y", "ball_z")  # [m], base frame


@dataclass(frozen=True)
class ArmSeries:
    """Joint positions of one arm over the file's time: role planned, commanded, measured or ipo."""

    source: str
    role: str
    t: np.ndarray  # (n,) [s], file time
    q: np.ndarray  # (n, 7) [rad]


@dataclass(frozen=True)
class BallSeries:
    """A ball over the file's time: kind predicted, simulated or tracked."""

    source: str
    kind: str
    t: np.ndarray  # (n,) [s], file time
    direction: np.ndarray  # (n, 3) unit string direction in the base frame (NaN rows: not known)
    planar: np.ndarray  # (n,) swing angle in the base y–z plane [rad], toward +y (for aligning clocks)
    position: np.ndarray | None = None  # (n, 3) [m] when the file carries the ball's position


@dataclass(frozen=True)
class StateSeries:
    """An execution log's session state, command phase and plan row per FRI message."""

    t: np.ndarray  # (n,) [s]
    state: np.ndarray  # (n,) SessionState
    phase: np.ndarray  # (n,) Phase
    row: np.ndarray  # (n,) commanded plan row (−1: none)


@dataclass(frozen=True)
class InputFile:
    """One file and what the view draws from it."""

    path: str
    kind: str
    arms: tuple[ArmSeries, ...] = ()
    balls: tuple[BallSeries, ...] = ()
    state: StateSeries | None = None
    pivot_path: np.ndarray | None = None  # (n, 3) [m] of a task trajectory, with pivot_t
    pivot_t: np.ndarray | None = None
    obstacles: tuple = ()  # planners.obstacles.Obstacle

    @property
    def name(self) -> str:
        return Path(self.path).name

    @property
    def plan_clock(self) -> bool:
        """True for files on a plan's clock (t = 0 at its first row): joint, task trajectories and predictions."""
        return self.kind in (JOINT, TASK, PREDICTION)


def spherical_direction(theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """(n, 3) string directions from the tilt θ and its azimuth φ [rad]."""
    st = np.sin(theta)
    return np.column_stack([st * np.cos(phi), st * np.sin(phi), -np.cos(theta)])


def planar_direction(theta: np.ndarray) -> np.ndarray:
    """(n, 3) string directions for a swing angle θ [rad] in the base y–z plane, positive toward +y."""
    return np.column_stack([np.zeros_like(theta), np.sin(theta), -np.cos(theta)])


def _header(path: str) -> list[str]:
    """The first line that is not blank or a comment, as cells (a missing file is named in one line)."""
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            for row in csv.reader(fh):
                if row and any(c.strip() for c in row) and not row[0].lstrip().startswith("#"):
                    return [c.strip() for c in row]
    except FileNotFoundError:
        raise CsvFormatError("file not found", file=path) from None
    except IsADirectoryError:
        raise CsvFormatError("is a directory, not a file lbr writes", file=path) from None
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise CsvFormatError(f"not a readable CSV file ({exc})", file=path) from None
    raise CsvFormatError("empty file", file=path)


def file_kind(path: str | Path) -> str:
    """Which lbr file ``path`` is, from its header (CsvFormatError naming the file when none)."""
    spath = str(path)
    head = _header(spath)
    if head[:2] == ["name", "x_min"]:
        return OBSTACLES
    if head[:1] != ["t"] or len(head) < 2:
        raise CsvFormatError(
            f"not a file lbr writes (header starts {','.join(head[:3])!r}): expected a joint or task trajectory, "
            "an execution log, a prediction, a track or an obstacle file",
            file=spath,
            row=1,
            column=1,
        )
    second = head[1]
    kinds = {"q1": JOINT, "x": TASK, "state": LOG, "theta": PREDICTION, "frame": TRACK}
    if second not in kinds:
        raise CsvFormatError(
            f"not a file lbr writes (second column {second!r}): expected q1 (joint trajectory), x (task), "
            "state (execution log), theta (prediction) or frame (track)",
            file=spath,
            row=1,
            column=2,
        )
    return kinds[second]


def _ball_position(table) -> np.ndarray | None:
    if all(table.has(c) for c in BALL_POSITION_COLUMNS):
        return np.column_stack([table.column(c) for c in BALL_POSITION_COLUMNS])
    return None


def read_input(path: str | Path) -> InputFile:
    """Read one file for the view (strict readers of trajectories.csvio; errors name file, row and column)."""
    from trajectories.csvio import PREDICTION_COLUMNS, read_joint_csv, read_table, read_task_csv

    from ..fri.log import LOG_COLUMNS, NAN_COLUMNS

    spath = str(path)
    kind = file_kind(spath)
    if kind == OBSTACLES:
        from ..obstacle_file import read_obstacles

        return InputFile(spath, kind, obstacles=read_obstacles(spath))
    if kind == JOINT:
        traj = read_joint_csv(spath)
        return InputFile(spath, kind, arms=(ArmSeries(spath, "planned", traj.t, traj.q),))
    if kind == TASK:
        task = read_task_csv(spath)
        return InputFile(spath, kind, pivot_path=task.position, pivot_t=task.t)
    if kind == LOG:
        table = read_table(spath, LOG_COLUMNS, time="increasing", nan_columns=NAN_COLUMNS + BALL_POSITION_COLUMNS)
        t = table.column("t")
        arms = tuple(
            ArmSeries(spath, role, t, np.column_stack([table.column(f"{prefix}_q{i}") for i in range(1, 8)]))
            for role, prefix in (("commanded", "cmd"), ("measured", "msr"))
        )
        balls: tuple[BallSeries, ...] = ()
        if table.has("ball_theta") and table.has("ball_phi"):
            theta, phi = table.column("ball_theta"), table.column("ball_phi")
            planar = table.column("ball_theta_y") if table.has("ball_theta_y") else theta
            balls = (BallSeries(spath, "simulated", t, spherical_direction(theta, phi), planar, _ball_position(table)),)
        cols = [table.column(c) if table.has(c) else np.full(len(t), -1.0) for c in ("state", "phase", "row")]
        state = StateSeries(t, *(c.astype(int) for c in cols))
        return InputFile(spath, kind, arms=arms, balls=balls, state=state)
    if kind == PREDICTION:
        table = read_table(
            spath,
            PREDICTION_COLUMNS,
            time="increasing",
            nan_columns=("theta", "phi", "theta_x", "theta_y") + BALL_POSITION_COLUMNS,
        )
        t, theta = table.column("t"), table.column("theta")
        if table.has("phi"):
            direction = spherical_direction(theta, table.column("phi"))
            planar = table.column("theta_y") if table.has("theta_y") else np.arctan2(direction[:, 1], -direction[:, 2])
        else:
            direction, planar = planar_direction(theta), theta
        return InputFile(
            spath, kind, balls=(BallSeries(spath, "predicted", t, direction, planar, _ball_position(table)),)
        )
    from tracking.trackfile import read_track_csv

    track = read_track_csv(spath)
    if track.theta is None:
        raise CsvFormatError(
            "no 'theta' column: track the video giving the pivot (its position or colour) to draw its ball",
            file=spath,
            row=1,
        )
    return InputFile(
        spath, kind, balls=(BallSeries(spath, "tracked", track.t, planar_direction(track.theta), track.theta),)
    )


__all__ = [
    "InputFile",
    "ArmSeries",
    "BallSeries",
    "StateSeries",
    "read_input",
    "file_kind",
    "JOINT",
    "TASK",
    "LOG",
    "PREDICTION",
    "TRACK",
    "OBSTACLES",
]
