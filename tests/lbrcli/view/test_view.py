"""`lbr view` without a browser: files recognised by their header, clocks put on one time line, the drawn poses
against pinocchio's forward kinematics, the plan's turning points against the points it was planned through."""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest
from tests.helpers.cli import run_lbr
from tests.helpers.run_files import LENGTH, TRACK_LAG, run_files

from lbrcli.fri.log import NAN_COLUMNS
from lbrcli.view.inputs import JOINT, LOG, OBSTACLES, PREDICTION, TASK, TRACK, file_kind, read_input
from lbrcli.view.scene import ViewSettings, build_scene, turning_points
from lbrcli.view.timeline import align
from trajectories.csvio import read_table
from trajectories.errors import CsvFormatError
from trajectories.robot import Robot, RobotConfig


@pytest.mark.heavy
def test_every_kind_is_recognised_and_a_foreign_file_is_named(tmp_path_factory, tmp_path):
    run = run_files(tmp_path_factory)
    assert [file_kind(p) for p in (run.plan, run.log, run.track, run.obstacles)] == [JOINT, LOG, TRACK, OBSTACLES]
    (tmp_path / "task.csv").write_text("t,x,y,z,qw,qx,qy,qz\n0,0.5,0,0.4,1,0,0,0\n")
    (tmp_path / "pred.csv").write_text("t,theta\n0,0\n0.01,0.001\n")
    assert file_kind(tmp_path / "task.csv") == TASK and file_kind(tmp_path / "pred.csv") == PREDICTION
    (tmp_path / "other.csv").write_text("time,a,b\n0,1,2\n")
    with pytest.raises(CsvFormatError) as exc:
        read_input(tmp_path / "other.csv")
    assert exc.value.file == str(tmp_path / "other.csv") and exc.value.row == 1 and exc.value.exit_code == 2


def test_the_track_is_placed_by_its_ball_and_the_plan_at_its_first_commanded_row(tmp_path_factory):
    run = run_files(tmp_path_factory)
    files = [read_input(p) for p in (run.plan, run.log, run.track)]
    al = align(files)
    off = {f.kind: al.offsets[f.path] for f in files}
    assert off[TRACK] - off[LOG] == pytest.approx(-TRACK_LAG, abs=1 / 60)  # within one video frame
    log = files[1].state
    first_row = log.t[np.flatnonzero((log.phase == 2) & (log.row == 0))[0]]
    assert off[JOINT] - off[LOG] == pytest.approx(first_row)
    assert min(al.offsets.values()) == 0.0
    given = align(files, {"track.csv": 1.5})
    assert given.offsets[str(run.track)] - given.offsets[str(run.log)] == pytest.approx(1.5)


@pytest.mark.parametrize(
    "lag, noise_deg, lost, fps", [(-0.8, 0.05, 0.05, 60), (0.15, 0.5, 0.2, 30), (1.3, 0.2, 0.1, 120)]
)
def test_tracks_are_placed_within_a_frame_across_lags_noise_and_lost_frames(
    tmp_path_factory, tmp_path, lag, noise_deg, lost, fps
):
    """Another camera each time: its own delay (before or after the log), noise, lost frames and frame rate; placed
    within one video frame or one log period, whichever is longer."""
    from trajectories.csvio import write_table

    run = run_files(tmp_path_factory)
    log = read_input(run.log)
    ball = log.balls[0]
    rng = np.random.default_rng(int(fps))
    t = np.arange(0.0, ball.t[-1] - 0.3, 1 / fps)
    theta = np.interp(t - lag, ball.t, ball.planar) + rng.normal(0.0, np.radians(noise_deg), len(t))
    found = rng.random(len(t)) > lost
    theta[~found] = np.nan
    write_table(
        tmp_path / "cam.csv",
        ("t", "frame", "u", "v", "found", "theta"),
        np.column_stack(
            [
                t,
                np.arange(len(t)),
                np.where(found, 1.0, np.nan),
                np.where(found, 1.0, np.nan),
                found.astype(float),
                theta,
            ]
        ),
    )
    al = align([log, read_input(tmp_path / "cam.csv")])
    placed = al.offsets[str(tmp_path / "cam.csv")] - al.offsets[log.path]
    period = float(np.median(np.diff(ball.t)))  # the log's 10 ms: the reference is sampled no finer
    assert placed == pytest.approx(-lag, abs=max(1 / fps, period))


@pytest.mark.parametrize("flange, tool", [("touch-electric", (0.0, 0.0, 0.0)), ("standard", (0.02, -0.01, 0.08))])
def test_drawn_bodies_and_balls_are_where_pinocchio_puts_the_logged_arm(tmp_path_factory, flange, tool):
    from trajectories.robot import Flange

    run = run_files(tmp_path_factory)
    files = [read_input(p) for p in (run.plan, run.log, run.track)]
    robot = Robot(RobotConfig(flange=Flange(flange), tool=tool))
    al = align(files)
    scene = build_scene(files, al, robot, ViewSettings(length=0.3, fps=40))
    arm = next(a for a in scene.arms if a.role == "measured")
    ball = next(b for b in scene.balls if b.kind == "simulated")
    state, log = files[1].state, files[1]
    logged = read_table(run.log, ("t",), nan_columns=NAN_COLUMNS)
    logged = logged if logged.has("ball_x") else None
    offset = al.offsets[log.path]
    q_log = log.arms[1].q
    for k in np.linspace(0, len(scene.t) - 1, 9).astype(int):
        tau = scene.t[k] - offset
        q = np.array([np.interp(tau, state.t, q_log[:, j]) for j in range(7)])
        pin.framesForwardKinematics(robot.model, robot.data, q)
        for b in range(7):
            np.testing.assert_allclose(arm.poses[k, b, :3], robot.data.oMi[b + 1].translation, atol=1e-12)
            r = pin.Quaternion(robot.data.oMi[b + 1].rotation)
            assert abs(np.dot(arm.poses[k, b, 3:], [r.w, r.x, r.y, r.z])) == pytest.approx(1.0, abs=1e-9)
        tcp = robot.data.oMf[robot.tcp_id].translation
        np.testing.assert_allclose(ball.pivot[k], tcp, atol=1e-12)
        if state.t[0] <= tau <= state.t[-1]:
            if logged is not None:  # the simulator's string model logs where the ball is: drawn there
                want = [np.interp(tau, logged.column("t"), logged.column(c)) for c in ("ball_x", "ball_y", "ball_z")]
                np.testing.assert_allclose(ball.ball[k], want, atol=1e-9)
            else:  # a ball given by angles: at the view's --length from the TCP
                assert np.linalg.norm(ball.ball[k] - tcp) == pytest.approx(0.3, abs=1e-9)
        else:
            assert np.all(np.isnan(ball.ball[k]))
    tracked = next(b for b in scene.balls if b.kind == "tracked")
    lost = np.isnan(tracked.ball[:, 0]).mean()
    assert 0.0 < lost < 0.4  # the track's lost frames and the time before it are not drawn


@pytest.mark.heavy
def test_turning_points_are_the_points_the_crane_move_was_planned_through(tmp_path):
    points = [(0.45, -0.15), (0.6, -0.15), (0.6, 0.1), (0.5, 0.1)]
    text = ";".join(f"{x},{y}" for x, y in points)
    proc = run_lbr(
        "plan",
        "anti-sway",
        "--points",
        text,
        "--length",
        LENGTH,
        "--a-max",
        "2",
        "--dt",
        "0.01",
        "--length-tolerance",
        "0",
        "--z",
        "0.4",
        "-o",
        tmp_path / "crane.csv",
        "--prediction",
        tmp_path / "pred.csv",
        "--json",
        cwd=tmp_path,
    )
    assert proc.returncode == 0, proc.stderr
    files = [read_input(tmp_path / "crane.csv"), read_input(tmp_path / "pred.csv")]
    scene = build_scene(files, align(files), Robot(), ViewSettings(length=LENGTH))
    want = np.array([[x, y, 0.4] for x, y in points])
    assert scene.turning_points.shape == want.shape
    np.testing.assert_allclose(scene.turning_points, want, atol=2e-3)
    predicted = next(b for b in scene.balls if b.kind == "predicted")
    theta = np.degrees(np.arccos(np.clip((predicted.pivot[:, 2] - predicted.ball[:, 2]) / LENGTH, -1, 1)))
    assert np.nanmax(theta) == pytest.approx(json.loads(proc.stdout)["peak_sway_deg"], abs=0.2)


def test_turning_points_of_a_reversing_and_a_resting_pivot():
    t = np.arange(0, 2.0, 0.01)
    y = 0.1 * np.sin(2 * np.pi * t)  # reverses at t = 0.25 s and 0.75 s, 1.25 s, 1.75 s
    p = np.column_stack([np.full_like(t, 0.5), y, np.full_like(t, 0.4)])
    found = turning_points(p, 0.01)
    np.testing.assert_allclose(np.sort(found[:, 1]), [-0.1, -0.1, 0.1, 0.1], atol=1e-3)
    assert turning_points(np.tile([0.5, 0.0, 0.4], (50, 1)), 0.01).shape == (1, 3)


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--fps", "0"], "--fps"),
        (["--cup", "0.04"], "--cup"),
        (["--offset", "nofile=1"], "--offset"),
        (["-o", "view.txt"], "HTML"),
        (["--port", "70000"], "--port"),
    ],
)
def test_bad_options_exit_2_with_one_line(tmp_path_factory, tmp_path, monkeypatch, capsys, argv, message):
    from lbrcli.app import main

    run = run_files(tmp_path_factory)
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as ended:
        main(["view", str(run.log), *argv])
    err = capsys.readouterr().err
    assert ended.value.code == 2 and message in err and len(err.strip().splitlines()) == 1


def test_the_server_starts_on_loopback_with_no_deprecated_viser_call():
    """viser's current API only (``configure_theme(control_layout=...)`` is deprecated since viser 1.1)."""
    import warnings

    from lbrcli.view.serve import start_server, stop_server

    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        server = start_server(port=0)
    try:
        assert server.get_host() == "127.0.0.1" and server.get_port() > 0
    finally:
        stop_server(server)
