"""Every example in examples/ runs against the simulator and does what it says — in lock-step (--sim-fast, or
--sim-lockstep where a source runs in real time beside it), so that what they judge does not depend on this machine's
load; the timing rules have their own tests and benchmarks."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from tests.helpers.cli import Q_START

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
sys.path.insert(0, str(EXAMPLES))


def test_every_example_is_short():
    for path in EXAMPLES.glob("*.py"):
        assert len(path.read_text().splitlines()) <= 60, path.name


@pytest.mark.heavy
@pytest.mark.parametrize("version", ["1.15", "2.7"])
def test_joint_sine_overlay_moves_the_measured_position_by_the_sine(version):
    import joint_sine_overlay

    result, client = joint_sine_overlay.main(["--duration", "2", "--fri-version", version, "--sim-fast"])
    assert result.ok, result.detail
    measured = np.array([m for m, _ in client.history])
    commanded = np.array([c for _, c in client.history])
    # the robot stands where the previous cycle's command put it (ipo + offset, never the offset re-added); for a
    # reply that reached the simulator late (a loaded machine) it bridged at the commands' velocity, off by < a step
    prev = np.abs(measured[1:] - commanded[:-1]).max(axis=1)
    step = np.abs(np.diff(commanded, axis=0)).max()
    assert np.mean(prev < 1e-6) > 0.9 and prev.max() < 2 * step
    assert np.abs(measured - measured[0]).max() < 0.04 + 1e-9  # bounded by the amplitude: nothing accumulates
    assert 1e-4 < np.ptp(commanded[:, 3]) <= 2 * 0.04 + 1e-9  # the filtered sine on A4 only, within ± its amplitude
    assert np.ptp(commanded[:, 0]) == 0.0
    assert result.prepared_replies > 0.9 * len(client.history)  # reply first (prepare_command)


@pytest.mark.heavy
def test_torque_sine_moves_the_joint_and_wrench_sine_moves_the_flange():
    import torque_sine_overlay
    import wrench_sine_overlay

    result, client = torque_sine_overlay.main(["--duration", "2", "--sim-fast"])
    assert result.ok, result.detail
    q = np.array(client.measured)
    assert np.ptp(q[:, 3]) > 1e-4 and np.ptp(q[:, 0]) < np.ptp(q[:, 3]) / 10  # 5 Nm on A4 against 1000 Nm/rad
    assert result.prepared_replies > 0.9 * len(client.measured)  # reply first (prepare_command + prepare_overlay)
    result, client = wrench_sine_overlay.main(["--duration", "2", "--sim-fast"])
    assert result.ok, result.detail
    assert np.ptp(np.array(client.measured), axis=0).max() > 1e-5
    assert result.prepared_replies > 0.9 * len(client.measured)


@pytest.mark.heavy
def test_stream_csv_and_monitor_write_logs_the_project_reads(tmp_path):
    import monitor_to_file
    import stream_csv

    from lbrcli.fri.log import LOG_COLUMNS
    from trajectories.csvio import read_table

    t = np.arange(0, 1.0 + 1e-9, 0.005)
    s = 10 * (t / t[-1]) ** 3 - 15 * (t / t[-1]) ** 4 + 6 * (t / t[-1]) ** 5
    q = Q_START + 0.1 * s[:, None]
    csv = tmp_path / "move.csv"
    np.savetxt(csv, np.column_stack([t, q]), delimiter=",", header="t,q1,q2,q3,q4,q5,q6,q7", comments="", fmt="%.12g")
    result, player = stream_csv.main([str(csv), "--log", str(tmp_path / "run.csv"), "--sim-fast"])
    assert result.ok, result.detail
    assert player.trajectory_rows == len(t)
    assert result.prepared_replies > 0.5 * len(t)  # over UDP with the simulator: the rows go out prepared
    assert len(read_table(tmp_path / "run.csv", LOG_COLUMNS, time="increasing").data) == result.cycles
    result, rows = monitor_to_file.main(["--log", str(tmp_path / "mon.csv"), "--duration", "0.5", "--sim-fast"])
    assert result.ok and rows == len(read_table(tmp_path / "mon.csv", LOG_COLUMNS, time="increasing").data) > 50


@pytest.mark.heavy
def test_damp_ball_feedback_removes_the_sway_open_loop_keeps():
    import damp_ball

    late = {}
    for gain in (0.9, 0.0):
        # in lock-step, as fast as it answers: the same closed loop however loaded this machine is
        result, client = damp_ball.main(["--gain", str(gain), "--duration", "4", "--sim-fast"])
        assert result.ok, result.detail
        late[gain] = max(abs(th) for t, th in client.sway if t > client.t - 1.5)  # its last 1.5 s of commanding
        assert client.t > 4.0  # it commanded long enough to damp
    assert late[0.0] > math.radians(0.5)  # the excited ball keeps swinging without feedback
    assert late[0.9] < late[0.0] / 4


@pytest.mark.heavy
def test_io_access_writes_the_clock_and_reads_it_back():
    import io_access

    result, client = io_access.main(["--duration", "1", "--sim-fast"])
    assert result.ok, result.detail
    assert len(client.written) > 50
    # what the controller reports in the next message is what was written in the cycle before
    digital, analog = zip(*client.written)
    assert all(0 <= d < 64 for d in digital) and all(0.0 <= a <= 0.9 + 1e-9 for a in analog)
    later = client.read_back[-len(client.written) + 1 :]
    hits = sum(1 for w, r in zip(client.written, later) if w[0] == r[0] and abs(w[1] - r[1]) < 1e-12)
    assert hits >= 0.5 * len(later)  # a reply that reached the controller late is read back a cycle later
    assert set(later) <= set(client.written) | {(0, 0.0)}  # never anything that was not written


@pytest.mark.heavy
def test_bridge_pose_source_draws_the_circle_and_ends_the_session():
    import bridge_pose_source

    from trajectories.robot import Robot

    result, follower, sent = bridge_pose_source.main(["--sim-lockstep"])
    assert result.ok, result.detail
    assert "ended" in result.detail and follower.pose_targets > 300 and follower.poses_unreached == 0
    circle, tcp_back = np.array(sent[:-1]), sent[-1]
    assert np.ptp(circle[:, 1]) > 0.09  # the source drew the 5 cm circle
    # the state that came back: the commanded TCP is where the last targets (the circle's end) put it
    assert tcp_back is not None and np.linalg.norm(tcp_back - circle[-1]) < 1e-4
    end = Robot().fk(np.array(follower._q)).translation
    assert np.linalg.norm(end - circle[-1]) < 1e-4
