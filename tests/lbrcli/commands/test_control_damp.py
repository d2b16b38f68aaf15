"""`lbr control damp` on the simulator: a joint file that leaves the ball swinging, streamed with active damping."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from tests.helpers.cli import run_lbr
from planners.pendulum import natural_period
from tests.helpers.damp import read_log, sway_after, write_moves, DT, THESIS


@pytest.mark.heavy
@pytest.mark.parametrize("sensor, true_length, delay", [("io", 0.30, 10.0), ("module", 0.20, 5.0)])
def test_damping_removes_the_sway_a_wrong_string_length_leaves(tmp_path, sensor, true_length, delay):
    traj = tmp_path / "moves.csv"
    if sensor == "io":
        move_end = write_moves(traj)
    else:  # a one-axis module, its bearing (the flange's axis) along base x — the thesis start pose — and a move
        # across it (A1 turns the TCP along base y), there and back
        a1 = np.array([0.12, 0, 0, 0, 0, 0, 0])
        move_end = write_moves(traj, ((a1, 0.8), (-a1, 0.7)), q0=THESIS)
    logs = {}
    for mode in ("closed", "open"):
        log = tmp_path / f"{mode}.csv"
        args = ["control", "damp", traj, "--length", "0.25", "--sim-length", true_length, "--sim-delay", delay,
                "--sensor", sensor, "--log", log, "--port", "0", "--sim-lenient", "--sim-fast", "--json"]  # fmt: skip
        if mode == "open":
            args.append("--open-loop")
        p = run_lbr(*args, timeout=180)
        assert p.returncode == 0, p.stderr[-2000:]
        fig = json.loads(p.stdout)
        assert fig["outcome"] == "completed"
        logs[mode] = (read_log(log), fig)
    closed, fig = logs["closed"]
    open_, fig_open = logs["open"]
    column = "ball_theta" if sensor == "io" else "ball_theta_y"  # the module swings along base y only
    sway_open = sway_after(open_, move_end, 2, true_length, column)
    sway_closed = sway_after(closed, move_end, 2, true_length, column)
    assert sway_open > 1.0  # the unshaped moves leave the ball swinging
    assert sway_closed <= 0.5
    assert sway_closed < 0.25 * sway_open
    # the correction is small, within its bounds, and the arm ends exactly on the file's last row
    assert 0.0005 < fig["max_offset_m"] < 0.08
    assert fig_open["max_offset_m"] == 0.0
    with open(traj, newline="") as f:
        last = [float(v) for v in list(csv.reader(f))[-1][1:]]
    active = closed["state"] == 4
    cmd = np.column_stack([closed[f"cmd_q{j}"] for j in range(1, 8)])[active]
    assert np.allclose(cmd[-1], last, atol=1e-9)
    # within the joint limits, as the guard would also have enforced
    from trajectories.limits import default_limits

    lim = default_limits()
    assert np.all(np.abs(np.diff(cmd, axis=0)) / DT <= lim.velocity * (1 + 1e-6))
    assert np.all(np.abs(np.diff(cmd, 2, axis=0)) / DT**2 <= lim.acceleration * (1 + 1e-6))
    # the log carries the damper's own view
    assert np.nanmax(np.abs(closed["damp_x"])) > 0 or np.nanmax(np.abs(closed["damp_y"])) > 0
    assert fig["controller_us_p50"] is not None and fig["measured_residual_deg"] is not None
    # at 5 ms the feedback runs in the cycle (reply first only up to REPLY_FIRST_MAX_PERIOD_S): nothing prepared
    assert fig["prepared_replies"] == 0


@pytest.mark.heavy
def test_at_1_ms_the_damper_replies_first_and_still_removes_the_sway(tmp_path):
    """At a 1 ms period each message's readings are read after its reply and the next command is prepared then:
    the replies go out as soon as the messages are checked, and the sway the moves leave (a string 20 % longer than
    the model, the readings 10 ms late) is still damped."""
    traj = tmp_path / "moves.csv"
    move_end = write_moves(traj, dt=1e-3)
    log = tmp_path / "closed.csv"
    p = run_lbr("control", "damp", traj, "--length", "0.25", "--sim-length", "0.30", "--sim-delay", "10", "--sensor",
                "io", "--log", log, "--port", "0", "--sim-lenient", "--sim-fast", "--json", timeout=240)  # fmt: skip
    assert p.returncode == 0, p.stderr[-2000:]
    fig = json.loads(p.stdout)
    assert fig["outcome"] == "completed"
    assert fig["prepared_replies"] > 0.9 * fig["trajectory_rows"]
    assert sway_after(read_log(log), move_end, 2, 0.30) <= 0.5  # (open loop these moves leave > 1°)


@pytest.mark.parametrize(
    "extra, needle",
    [
        (["--sensor", "camera", "--robot", "192.170.10.2", "--length", "0.25"], "--camera"),
        (["--camera", "0"], "--sensor camera"),
        (["--sensor", "camera", "--sim-delay", "10"], "--sim-camera-latency"),
        (["--io-names", "only_one"], "--io-names"),
        (["--module-axis", "z"], "--module-axis"),
        (["--sim-delay", "-1"], "--sim-delay"),
        (["--robot", "192.170.10.2", "--sim-length", "0.3"], "--length"),
    ],
)
def test_bad_options_are_one_line_errors(tmp_path, extra, needle):
    traj = tmp_path / "moves.csv"
    write_moves(traj)
    p = run_lbr("control", "damp", traj, *extra)
    assert p.returncode == 2, p.stderr
    assert needle in p.stderr and "Traceback" not in p.stderr
    assert len(p.stderr.strip().splitlines()) == 1


def test_a_file_off_the_fri_period_or_over_the_limits_is_refused_before_anything_is_sent(tmp_path):
    traj = tmp_path / "odd.csv"
    with open(traj, "w") as f:
        f.write("t,q1,q2,q3,q4,q5,q6,q7\n")
        for k in range(50):
            f.write(f"{k * 0.0025:.6f},0,0.6,0,-1.4,0,1.14,0\n")
    p = run_lbr("control", "damp", traj, "--port", "0")
    assert p.returncode == 2 and "odd.csv" in p.stderr and "2.5 ms" in p.stderr
    jump = tmp_path / "jump.csv"
    with open(jump, "w") as f:
        f.write("t,q1,q2,q3,q4,q5,q6,q7\n")
        for k in range(50):
            f.write(f"{k * 0.005:.6f},{0.5 if k > 25 else 0},0.6,0,-1.4,0,1.14,0\n")
    p = run_lbr("control", "damp", jump, "--port", "0")
    assert p.returncode == 1 and "refused" in p.stderr and "simulator on" not in p.stderr


@pytest.mark.heavy
def test_damping_rides_through_lost_and_malformed_messages(tmp_path):
    """3 % of the controller's messages lost and 1 % malformed: the controller extrapolates, the rows are rejoined
    within their share of the limits, the offsets keep the rest; the run completes and the sway is still damped."""
    from lbrcli.console import Reporter
    from lbrcli.control import DampingClient
    from lbrcli.control.damping import LOG_COLUMNS
    from lbrcli.fri_runner import run_client
    from lbrcli.plants.ball import BallSpec
    from lbrcli.session_settings import LogColumns, SessionSettings, SimulatorSettings
    from planners.feedback.correction import correction_plan
    from trajectories.csvio import read_joint_csv
    from trajectories.limits import default_limits
    from trajectories.robot import Flange, Robot, RobotConfig

    path = tmp_path / "moves.csv"  # moves that leave ≈ 5° of sway (the damper's bounds are not saturated)
    move_end = write_moves(
        path, ((np.array([0.12, 0, 0, 0, 0, 0, 0]), 1.2), (np.array([0, 0.05, 0, 0.06, 0, 0, 0]), 1.0))
    )
    lim, traj = default_limits(), read_joint_csv(path, None)
    plan = correction_plan(Robot(RobotConfig(flange=Flange("touch-electric"))), traj.q, lim, DT)  # the simulator's
    client = DampingClient(
        traj.q, lim, DT, 0.25, plan, damp_s=3 * natural_period(0.25), sensor_delay_s=0.015, reply_first=True
    )  # (the 1 ms default, here at 5 ms: with the faults)
    # the same closed loop on a busy machine, as fast as it computes
    sim = SimulatorSettings(period_ms=5, start=traj.q[0], ball=BallSpec(0.30, 0.0, io_delay_ms=10), max_runtime_s=60,
                            fast=True, loss=0.03, malformed=0.01, seed=6)  # fmt: skip
    log = tmp_path / "run.csv"
    result, _, _ = run_client(Reporter(True), client, SessionSettings(port=0, limits=lim, log=log), sim,
                              extra=LogColumns(LOG_COLUMNS, client.log_values))  # fmt: skip
    assert result.outcome.value == "completed", result.detail
    assert result.missed > 10 and client.skipped_rows > 10  # the faults happened and were bridged
    assert result.prepared_replies > 0.5 * client.trajectory_rows  # reply first between the faults
    assert sway_after(read_log(log), move_end, 2, 0.30) <= 0.5
    assert 0.0 < client.max_offset < plan.travel


def test_a_module_that_cannot_swing_with_the_sway_is_refused(tmp_path):
    """The flange pointing down keeps the module's bearing vertical: its rod cannot swing — refused, nothing sent."""
    traj = tmp_path / "down.csv"
    write_moves(traj, ((np.array([0.25, 0, 0, 0, 0, 0, 0]), 0.8),))
    p = run_lbr("control", "damp", traj, "--length", "0.25", "--sensor", "module", "--port", "0", timeout=120)
    assert p.returncode == 1 and "bearing axis" in p.stderr and "off base x" in p.stderr and "Traceback" not in p.stderr
    assert "simulator on" not in p.stderr  # refused before a session started
