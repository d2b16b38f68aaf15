"""Files of one real run, made once per test session and shared by the xdist workers: a joint CSV executed by
`lbr execute` on the lock-step simulator with its ball (the log), and a track of that ball as a camera would give it
(60 fps, a known delay, noise, lost frames) — what `lbr view` and `lbr export` read."""

from __future__ import annotations

import fcntl
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tests.helpers.cli import Q_START, run_lbr

Q0 = Q_START  # [rad], thesis start pose
AXES = np.array([0.35, 0.2, -0.15, 0.3, 0.1, -0.25, 0.4])  # [rad] amplitude of the move per joint
TRACK_LAG = 0.37  # [s] track time − log time of the synthetic camera
LENGTH = 0.25  # [m] the simulated string


@dataclass(frozen=True)
class RunFiles:
    folder: Path
    plan: Path
    log: Path
    track: Path
    obstacles: Path


def _make(folder: Path) -> None:
    from trajectories.csvio import read_table, write_joint_csv, write_table
    from trajectories.trajectory import JointTrajectory

    from lbrcli.fri.log import LOG_COLUMNS

    t = np.arange(0.0, 1.6 + 1e-12, 0.01)
    s = (1 - np.cos(2 * np.pi * t / 1.6)) / 2
    write_joint_csv(folder / "plan.csv", JointTrajectory(t=t, q=Q0 + s[:, None] * AXES))
    # in this process (the `lbr` script's code path) and in lock-step as fast as the client answers (--sim-fast):
    # the session the paced simulator runs, stamp for stamp, without waiting for its clock
    proc = run_lbr("execute", folder / "plan.csv", "--port", "0", "--log", folder / "log.csv", "--length", str(LENGTH),
                   "--settle", "0.6", "--sim-lenient", "--sim-fast", "--json")  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    log = read_table(folder / "log.csv", LOG_COLUMNS, time="increasing")
    rng = np.random.default_rng(7)
    t_track = np.arange(0.0, log.column("t")[-1] - 0.5, 1 / 60)
    theta = np.interp(t_track - TRACK_LAG, log.column("t"), log.column("ball_theta_y"))
    theta = theta + rng.normal(0.0, np.radians(0.05), len(theta))
    found = rng.random(len(theta)) > 0.05
    theta[~found] = np.nan
    uv = np.where(found[:, None], np.column_stack([640 + 300 * np.sin(theta), 260 + 300 * np.cos(theta)]), np.nan)
    write_table(
        folder / "track.csv",
        ("t", "frame", "u", "v", "found", "theta"),
        np.column_stack([t_track, np.arange(len(t_track)), uv, found.astype(float), theta]),
        fmt=["%.6f", "%d", "%.3f", "%.3f", "%d", "%.6f"],
    )
    (folder / "boxes.csv").write_text("name,x_min,y_min,z_min,x_max,y_max,z_max\npost,0.5,-0.4,0.0,0.56,-0.34,0.3\n")
    (folder / "done.json").write_text(json.dumps({"ok": True}))


def run_files(tmp_path_factory) -> RunFiles:
    """The shared files (made by the first worker that asks; the others wait on a lock)."""
    root = tmp_path_factory.getbasetemp()
    shared = root.parent if root.name.startswith("popen-gw") else root
    folder = shared / "lbr-view-run"
    folder.mkdir(exist_ok=True)
    with open(shared / "lbr-view-run.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (folder / "done.json").exists():
            _make(folder)
    return RunFiles(folder, folder / "plan.csv", folder / "log.csv", folder / "track.csv", folder / "boxes.csv")
