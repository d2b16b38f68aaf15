"""Film a simulated execution: render the simulated ball of an execution log as a lab camera would see it.

The camera stands in front of the robot (on +x, looking toward −x) perpendicular to the base y–z plane, so the
image u axis is base +y and v points down; a green marker is drawn on the pivot (TCP) for `--pivot-color`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np


@dataclass(frozen=True)
class Camera:
    """A metric orthographic camera of the y–z plane: pixels per metre, and where the start pivot appears."""

    px_per_m: float = 1300.0  # [px/m]
    pivot0_uv: tuple[float, float] = (640.0, 260.0)  # [px], pivot at the first frame
    size: tuple[int, int] = (1280, 720)
    fps: float = 60.0  # [1/s]
    ball_radius_m: float = 0.005  # [m] (a 1 cm ball: 13 px)


@dataclass(frozen=True)
class Footage:
    """What was filmed: the video, its time offset in the log [s], and the ground truth of every frame."""

    path: str
    t0_log: float  # [s] log time of the first frame
    truth: object  # tracking.synthetic.GroundTruth


FILM_COLUMNS = ("ball_theta_y",) + tuple(f"msr_q{i}" for i in range(1, 8))  # what a film needs from a log


def read_film_log(log_csv: str | Path):
    """The execution log as a table; CsvFormatError (exit 2) when it lacks the simulated ball or the joints."""
    from trajectories.csvio import read_table
    from trajectories.errors import CsvFormatError

    from lbrcli.fri.log import LOG_COLUMNS, NAN_COLUMNS

    table = read_table(log_csv, LOG_COLUMNS, time="increasing", nan_columns=NAN_COLUMNS)
    missing = [c for c in FILM_COLUMNS if not table.has(c)]
    if missing:
        raise CsvFormatError(f"no column '{missing[0]}': not a log of the simulator with its ball (`lbr execute` "
                             "on the built-in simulator with a string length > 0)", file=table.path, row=1)  # fmt: skip
    if len(table.column("t")) < 2:
        raise CsvFormatError("need at least 2 rows to film", file=table.path)
    return table


def film_execution_log(
    log_csv,
    video: str | Path,
    length: float,
    camera: Camera = Camera(),
    lead_s: float = 0.3,
    flange: str = "touch-electric",
    tool=(0.0, 0.0, 0.0),
    progress=None,
    cup=None,
    target: str | Path | None = None,
) -> Footage:
    """Render ``video`` from an execution log (a path, or the table of :func:`read_film_log`) with the simulator's
    ``ball_theta_y`` [rad] and ``msr_q1..7``.

    Starts ``lead_s`` before the first commanded trajectory row and ends with the log. The ball is drawn where the
    log's ``ball_y``, ``ball_z`` [m] put it when it has them (flying on a slack string too, the string sagging),
    else on a taut string at ``ball_theta_y``. With ``cup`` (a ``planners.string_model.StringModel``) the ball has
    that model's radius and the cup is drawn on the pivot (a clear cup: its outline and a light tint, so that the
    camera still sees the ball inside). ``target``: the name errors report when ``video`` is a temporary one.
    """
    from tracking.synthetic import render_pendulum_video
    from trajectories.robot import Flange, Robot, RobotConfig

    from lbrcli.fri.log import PHASE_TRAJECTORY

    table = read_film_log(log_csv) if isinstance(log_csv, (str, Path)) else log_csv
    t = table.column("t")
    phase = table.column("phase")
    moving = np.flatnonzero(phase == PHASE_TRAJECTORY)
    start = t[moving[0]] - lead_s if moving.size else t[0]
    keep = t >= start
    t = t[keep]
    theta = table.column("ball_theta_y")[keep]
    q = np.column_stack([table.column(f"msr_q{i}") for i in range(1, 8)])[keep]
    robot = Robot(RobotConfig(flange=Flange(flange), tool=tuple(tool)))
    pos, rot = robot.fk_path(q)
    k = camera.px_per_m

    def image(y, z):
        return np.column_stack([camera.pivot0_uv[0] + k * (y - pos[0, 1]), camera.pivot0_uv[1] - k * (z - pos[0, 2])])

    pivot_uv = image(pos[:, 1], pos[:, 2])
    ball_path, foreground, radius = None, (), camera.ball_radius_m
    if table.has("ball_y") and table.has("ball_z"):  # the string model's ball: drawn where it flew on a slack string
        ball_path = image(table.column("ball_y")[keep], table.column("ball_z")[keep])
    if cup is not None and ball_path is not None:
        axes = rot @ np.asarray(cup.axis_flange)
        foreground = (cup_drawer(t - t[0], pivot_uv, np.column_stack([axes[:, 1], -axes[:, 2]]), cup.cup, k),)
        radius = cup.ball.radius
    truth = render_pendulum_video(
        video,
        t - t[0],
        theta,
        pivot_uv,
        string_px=k * length,
        ball_radius_px=k * radius,
        size=camera.size,
        fps=camera.fps,
        pivot_marker="green",
        progress=progress,
        ball_path=ball_path,
        foreground=foreground,
        target=target,
    )
    return Footage(path=str(video), t0_log=float(t[0]), truth=truth)


def cup_drawer(t: np.ndarray, pivot_uv: np.ndarray, axis_uv: np.ndarray, cup, px_per_m: float):
    """A ``tracking.synthetic`` foreground drawer of the cup on the pivot: its side view (the U-shaped section through
    the axis) as a clear cup — a light blue-grey tint and a dark outline — at the pivot and axis of each time t [s]."""
    import cv2

    ri, ro, rim, zb = (px_per_m * v for v in (cup.inner_radius, cup.outer_radius, cup.rim_height, cup.bottom_height))
    section = np.array([(-ro, 0.0), (ro, 0.0), (ro, rim), (ri, rim), (ri, zb), (-ri, zb), (-ri, rim), (-ro, rim)])

    def draw(frame: np.ndarray, tf: float, ball: np.ndarray) -> None:
        p = np.array([np.interp(tf, t, pivot_uv[:, 0]), np.interp(tf, t, pivot_uv[:, 1])])
        a = np.array([np.interp(tf, t, axis_uv[:, 0]), np.interp(tf, t, axis_uv[:, 1])])
        a /= np.linalg.norm(a)
        across = np.array([-a[1], a[0]])
        pts = p[None, :] + section[:, :1] * across[None, :] + section[:, 1:] * a[None, :]
        poly = np.round(pts * 16).astype(np.int32).reshape(-1, 1, 2)
        tint = frame.copy()
        cv2.fillPoly(tint, [poly], (150, 135, 120), cv2.LINE_AA, 4)
        cv2.addWeighted(tint, 0.35, frame, 0.65, 0.0, dst=frame)
        cv2.polylines(frame, [poly], True, (70, 60, 55), 2, cv2.LINE_AA, 4)

    return draw
