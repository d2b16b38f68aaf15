"""`lbr control damp --sensor camera`: the whole loop without hardware — the simulator's ball rendered by its camera
(MJPEG over HTTP on loopback), tracked live, the tilt from the camera's geometry and the robot's pivot, the damper
correcting the FRI commands of the simulated robot. Judged on the simulator's own ball (the log's ball_theta), the
open loop from the project's pendulum model run offline on the same path."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.helpers.cli import run_lbr
from tests.helpers.damp import read_log, sway_after, write_moves


@pytest.fixture(scope="module")
def crane(tmp_path_factory):
    """The default crane move (`lbr plan anti-sway --length 0.25 --a-max 2`, 5 ms) and when its motion ends [s]."""
    path = tmp_path_factory.mktemp("crane") / "crane.csv"
    p = run_lbr("plan", "anti-sway", "-o", path, "--length", "0.25", "--a-max", "2", "--json", timeout=300)
    assert p.returncode == 0, p.stderr[-1000:]
    return path, float(json.loads(p.stdout)["motion_s"])


def _open_loop_sway(path, move_end: float, true_length: float) -> float:
    """The largest tilt [deg] two swing periods after the move of the plan alone (planners.feedback.damping's
    simulation of the ball on the TCP path, no FRI)."""
    from planners.feedback.damping import simulate_damping
    from planners.pendulum import natural_period
    from trajectories.csvio import read_joint_csv
    from trajectories.robot import Flange, Robot, RobotConfig

    traj = read_joint_csv(path, None)
    tcp, _ = Robot(RobotConfig(flange=Flange("touch-electric"))).fk_path(traj.q)
    run = simulate_damping(tcp, traj.dt, true_length, 0.25, damping=False, after_s=3.0)
    return float(np.degrees(run.theta[run.t >= move_end + 2 * natural_period(true_length)].max()))


def _damp(crane_path, log, true_length: float, *camera: str):
    p = run_lbr("control", "damp", crane_path, "--length", "0.25", "--sim-length", true_length, "--sensor", "camera",
                "--log", log, "--port", "0", "--sim-lenient", "--json", *camera, timeout=240)  # fmt: skip
    return p, (json.loads(p.stdout) if p.stdout.strip().startswith("{") else {})


JUDGES = (
    # the default camera (320x240, 120 fps, 15 ms latency, 4 ms exposure, posed to see both axes, frames stamped), the
    # string 20 % long: measured 0.03–0.10° (open loop 0.80°)
    (0.30, (), 0.3),
    # a second judge: from the other side of the move and higher (a 1° tilt moves the ball only 0.5–0.8 px), 90 fps,
    # 6 ms exposure, 30 ms latency, the string 20 % short: measured 0.15–0.17° (open loop 0.67°)
    (
        0.20,
        (
            "--sim-camera-position",
            "0.9,-0.9,1.0",
            "--sim-camera-look-at",
            "0.5,0,0.2",
            "--sim-camera-fov",
            "60",
            "--sim-camera-fps",
            "90",
            "--sim-camera-exposure",
            "6",
            "--sim-camera-latency",
            "30",
        ),
        0.45,
    ),
)


@pytest.mark.slow  # real time by nature (the camera renders and streams at its frame rate; no lock-step): beside two
# busy processes it drops frames and its health check ends the correction; bench_camera_damp measures the band
def test_the_camera_damps_the_sway_a_wrong_string_length_leaves(crane, tmp_path):
    """Both judges one after the other (each runs four processes in real time: simulator, camera, tracker, client)."""
    path, move_end = crane
    for i, (true_length, camera, share) in enumerate(JUDGES):
        log = tmp_path / f"run{i}.csv"
        p, fig = _damp(path, log, true_length, *camera)
        assert p.returncode == 0, p.stderr[-2000:]
        assert fig["outcome"] == "completed" and fig["sensor_fault"] is None
        sway_open = _open_loop_sway(path, move_end, true_length)
        sway_closed = sway_after(read_log(log), move_end, 2, true_length)
        assert sway_open > 0.5  # the plan alone leaves the ball swinging (string 20 % off)
        assert sway_closed < share * sway_open, (true_length, sway_closed, sway_open)
        # the camera measured the string from the hanging ball and saw most frames
        assert fig["camera_string_source"] == "camera" and abs(fig["camera_string_m"] - true_length) < 0.005
        assert fig["camera_found_percent"] > 90 and fig["camera_readings"] > 300
        assert 0.0 < fig["max_offset_m"] < 0.08


@pytest.mark.heavy
def test_a_camera_that_cannot_see_the_sway_is_refused(crane):
    """Level with the ball and looking along base x, a tilt toward x only moves the ball toward the camera; the crane
    move sways the ball along x and y."""
    p = run_lbr("control", "damp", crane[0], "--length", "0.25", "--sensor", "camera", "--port", "0",
                "--sim-camera-position", "1.6,0,0.2", "--sim-camera-look-at", "0.5,0,0.2")  # fmt: skip
    assert p.returncode == 1, p.stderr  # a check of the setup against the move that failed, as the module's axis
    assert "cannot see the sway along base x" in p.stderr and "--sim-camera-position" in p.stderr
    assert "Traceback" not in p.stderr and len(p.stderr.strip().splitlines()) == 1  # refused before anything started


@pytest.mark.heavy
def test_a_camera_that_cannot_be_reached_fails_before_anything_is_sent(tmp_path):
    traj = tmp_path / "moves.csv"
    write_moves(traj)
    p = run_lbr("control", "damp", traj, "--length", "0.25", "--sensor", "camera", "--camera",
                "http://127.0.0.1:9/stream.mjpg", "--camera-position", "1.0,0.8,0.9", "--camera-look-at", "0.5,0,0.2",
                "--port", "0", timeout=120)  # fmt: skip
    assert p.returncode == 1, p.stderr
    assert "cannot be opened" in p.stderr and "127.0.0.1:9" in p.stderr and "Traceback" not in p.stderr
    assert "simulator on" not in p.stderr


@pytest.mark.heavy
def test_a_camera_stream_that_stops_ends_the_correction_and_the_rows_finish(tmp_path):
    """The simulated camera stops streaming 1.5 s after the simulator started: the damper stops correcting, the rows
    are streamed as planned, the session ends as failed with the reason."""
    traj = tmp_path / "moves.csv"
    write_moves(traj)
    p = run_lbr("control", "damp", traj, "--length", "0.25", "--sim-length", "0.3", "--sensor", "camera",
                "--sim-camera-stop", "1.5", "--port", "0", "--sim-lenient", "--json",
                timeout=180)  # fmt: skip
    assert p.returncode == 1, p.stderr[-2000:]
    fig = json.loads(p.stdout)
    assert "stream ended" in fig["sensor_fault"] and "stream ended" in p.stderr.strip().splitlines()[-1]
    assert fig["damping_active"] is False and fig["trajectory_rows"] == fig["rows"]
