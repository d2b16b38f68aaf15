"""`lbr export`: every message of the MCAP file, read back by two independent readers (rosbags' own MCAP parser
and CDR deserialiser; the mcap library with mcap-ros2-support's decoder), equals the log it came from."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from tests.helpers.cli import run_lbr
from tests.helpers.run_files import LENGTH, run_files

from lbrcli.fri.log import LOG_COLUMNS
from trajectories.csvio import read_joint_csv, read_table
from trajectories.robot import Robot
from tests.helpers.rosbags import rosbags_messages

rosbags = pytest.importorskip("rosbags.highlevel", reason="rosbags is not installed (pip install -e .[test])")
mcap_reader = pytest.importorskip("mcap.reader", reason="mcap is not installed (pip install -e .[test])")
mcap_ros2 = pytest.importorskip("mcap_ros2.decoder", reason="mcap-ros2-support is not installed")


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    run = run_files(tmp_path_factory)
    out = tmp_path_factory.mktemp("export") / "run.mcap"
    proc = run_lbr("export", run.log, run.plan, "-o", out, "--json")
    assert proc.returncode == 0, proc.stderr
    return run, out, json.loads(proc.stdout)


def _mcap_messages(path: Path) -> dict[str, list]:
    out: dict[str, list] = {}
    with open(path, "rb") as fh:
        reader = mcap_reader.make_reader(fh, decoder_factories=[mcap_ros2.DecoderFactory()])
        for _, channel, message, decoded in reader.iter_decoded_messages():
            out.setdefault(channel.topic, []).append((message.log_time, decoded))
    return out


def _joints(table, prefix: str) -> np.ndarray:
    return np.column_stack([table.column(f"{prefix}{i}") for i in range(1, 8)])


@pytest.mark.heavy
@pytest.mark.parametrize("reader", [rosbags_messages, _mcap_messages], ids=["rosbags", "mcap"])
def test_every_message_read_back_equals_the_log(exported, reader):
    run, out, fig = exported
    log = read_table(run.log, LOG_COLUMNS, time="increasing")
    n = len(log.data)
    stamps = log.column("stamp_sec").astype(np.int64) * 1_000_000_000 + log.column("stamp_nsec").astype(np.int64)
    got = reader(out)
    assert fig["clock"] == "controller"
    expect = {
        "/lbr/joint_states": (_joints(log, "msr_q"), _joints(log, "msr_tau")),
        "/lbr/command/joint_states": (_joints(log, "cmd_q"), _joints(log, "cmd_tau")),
        "/lbr/ipo/joint_states": (_joints(log, "ipo_q"), None),
        "/lbr/external_torque": (None, _joints(log, "ext_tau")),
    }
    for topic, (position, effort) in expect.items():
        msgs = got[topic]
        assert len(msgs) == n, topic
        times = np.array([t for t, _ in msgs])
        np.testing.assert_array_equal(times, stamps)
        np.testing.assert_array_equal(
            [m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec for _, m in msgs], stamps
        )
        assert all(list(m.name) == [f"lbr_A{i}" for i in range(1, 8)] for _, m in msgs)
        for field, want in (("position", position), ("effort", effort)):
            values = np.array([list(getattr(m, field)) for _, m in msgs])
            if want is None:
                assert values.size == 0, (topic, field)
            else:
                np.testing.assert_array_equal(values, want, err_msg=f"{topic} {field}")
    # TF: the chain of the measured arm gives pinocchio's flange pose; the ball frame and topic the simulated ball
    robot = Robot()
    msr = _joints(log, "msr_q")
    theta, phi = log.column("ball_theta"), log.column("ball_phi")
    static = {tr.child_frame_id: tr.transform for _, m in got["/tf_static"] for tr in m.transforms}
    assert set(static) == {"lbr_flange", "lbr_tcp"}
    for k in range(0, n, max(1, n // 25)):
        _, tf = got["/tf"][k]
        pose = pin.SE3.Identity()
        chain = {tr.child_frame_id: tr for tr in tf.transforms}
        for i in range(1, 8):
            tr = chain[f"lbr_link_{i}"]
            assert tr.header.frame_id == f"lbr_link_{i - 1}"
            r = tr.transform.rotation
            pose = pose * pin.XYZQUATToSE3(
                np.array(
                    [
                        tr.transform.translation.x,
                        tr.transform.translation.y,
                        tr.transform.translation.z,
                        r.x,
                        r.y,
                        r.z,
                        r.w,
                    ]
                )
            )
        f = static["lbr_flange"]
        pose = pose * pin.SE3(np.eye(3), np.array([f.translation.x, f.translation.y, f.translation.z]))
        pin.framesForwardKinematics(robot.model, robot.data, msr[k])
        want = robot.data.oMf[robot.flange_id]
        np.testing.assert_allclose(pose.translation, want.translation, atol=1e-12)
        np.testing.assert_allclose(pose.rotation, want.rotation, atol=1e-12)
        tcp = robot.data.oMf[robot.tcp_id].translation
        ball = tcp + LENGTH * np.array(
            [np.sin(theta[k]) * np.cos(phi[k]), np.sin(theta[k]) * np.sin(phi[k]), -np.cos(theta[k])]
        )
        point = got["/lbr/ball"][k][1].point
        np.testing.assert_allclose([point.x, point.y, point.z], ball, atol=1e-12)
        b = chain["lbr_ball"].transform.translation
        np.testing.assert_allclose([b.x, b.y, b.z], ball, atol=1e-12)
    # the plan: one JointTrajectory with every row, placed where the log commanded its first row
    plan = read_joint_csv(run.plan)
    [(when, traj)] = got["/lbr/joint_trajectory_controller/joint_trajectory"]
    first = np.flatnonzero((log.column("phase") == 2) & (log.column("row") == 0))[0]
    assert when == stamps[first]
    assert list(traj.joint_names) == [f"lbr_A{i}" for i in range(1, 8)]
    np.testing.assert_array_equal([list(p.positions) for p in traj.points], plan.q)
    np.testing.assert_array_equal(
        [p.time_from_start.sec * 1_000_000_000 + p.time_from_start.nanosec for p in traj.points],
        np.round(plan.t * 1e9).astype(np.int64),
    )
    assert list(traj.points[0].velocities) == [0.0] * 7 and list(traj.points[-1].velocities) == [0.0] * 7
    [(_, description)] = got["/lbr/robot_description"]
    assert pin.buildModelFromXML(description.data).nq == 7


@pytest.mark.heavy  # the module's exported session: a simulator run and an export
def test_robot_description_is_attached_and_the_file_is_a_ros2_bag(exported):
    _, out, fig = exported
    with open(out, "rb") as fh:
        reader = mcap_reader.make_reader(fh)
        assert reader.get_header().profile == "ros2"
        [attachment] = list(reader.iter_attachments())
        summary = reader.get_summary()
    assert attachment.name == "robot_description.urdf" and attachment.media_type == "application/xml"
    model = pin.buildModelFromXML(attachment.data.decode())
    assert [model.names[i] for i in range(1, 8)] == [f"lbr_A{i}" for i in range(1, 8)]
    encodings = {(s.name, s.encoding) for s in summary.schemas.values()}
    assert ("sensor_msgs/msg/JointState", "ros2msg") in encodings
    assert {c.message_encoding for c in summary.channels.values()} == {"cdr"}
    latched = {
        c.topic for c in summary.channels.values() if "transient_local" in c.metadata.get("offered_qos_profiles", "")
    }
    assert latched == {"/tf_static", "/lbr/robot_description"}
    assert sum(fig["topics"].values()) == fig["messages"] == summary.statistics.message_count


@pytest.mark.heavy
def test_a_plan_alone_is_exported_from_zero_with_its_tf(tmp_path_factory, tmp_path):
    run = run_files(tmp_path_factory)
    out = tmp_path / "plan.mcap"
    proc = run_lbr("export", run.plan, "-o", out, "--prefix", "iiwa", "--tool", "0,0,0.05", "--json")
    assert proc.returncode == 0, proc.stderr
    got = rosbags_messages(out)
    plan = read_joint_csv(run.plan)
    rows = got["/iiwa/plan/joint_states"]
    assert [t for t, _ in rows] == list(np.round(plan.t * 1e9).astype(np.int64))
    np.testing.assert_array_equal([list(m.position) for _, m in rows], plan.q)
    assert len(got["/tf"]) == len(plan.t) and got["/tf"][0][1].transforms[0].header.frame_id == "iiwa_link_0"
    tcp = next(tr for _, m in got["/tf_static"] for tr in m.transforms if tr.child_frame_id == "iiwa_tcp")
    assert tcp.transform.translation.z == pytest.approx(0.05)


@pytest.mark.parametrize(
    "argv, message",
    [
        (["LOG", "-o", "x.txt"], "MCAP file"),
        (["LOG", "-o", "x.mcap", "--prefix", "1bad"], "--prefix"),
        (["LOG", "-o", "x.mcap", "--compression", "gzip"], "--compression"),
        (["TRACK", "-o", "x.mcap"], "execution logs and plans"),
        (["LOG", "LOG", "-o", "x.mcap"], "given twice"),
    ],
)
def test_bad_input_exits_2_with_one_line_and_writes_nothing(
    tmp_path_factory, tmp_path, monkeypatch, capsys, argv, message
):
    from lbrcli.app import main

    run = run_files(tmp_path_factory)
    monkeypatch.chdir(tmp_path)
    files = {"LOG": str(run.log), "TRACK": str(run.track)}
    with pytest.raises(SystemExit) as ended:
        main(["export", *(files.get(a, a) for a in argv)])
    err = capsys.readouterr().err
    assert ended.value.code == 2 and message in err and len(err.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []
