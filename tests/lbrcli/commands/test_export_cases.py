"""`lbr export` on small random logs and plans — one row, odd row counts across chunk boundaries, optional columns
missing (controller timestamps, commanded torque, the simulated ball, phases), a plan with and without a log, every
compression — against a reference built message by message without lbr's code: rosbags' CDR serialiser for the
joint states (compared byte for byte with what the `mcap` reader returns) and pinocchio's forward kinematics per row
for /tf, /tf_static and the ball (decoded by rosbags)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from tests.helpers.cli import run_in_process
from tests.helpers.rosbags import rosbags_messages

from lbrcli.fri.log import LOG_COLUMNS
from lbrcli.ros import bulk
from trajectories.csvio import read_joint_csv, read_table, write_joint_csv, write_table
from trajectories.robot import Robot, RobotConfig, parse_tool
from trajectories.trajectory import JointTrajectory

pytest.importorskip("rosbags.highlevel", reason="rosbags is not installed (pip install -e .[test])")
mcap_reader = pytest.importorskip("mcap.reader", reason="mcap is not installed (pip install -e .[test])")
from rosbags.typesys import Stores, get_typestore  # noqa: E402
from tests.helpers.cli import Q_START

TYPES = get_typestore(Stores.ROS2_HUMBLE)
NAMES = [f"lbr_A{i}" for i in range(1, 8)]
Q0 = Q_START  # [rad]
LENGTH = 0.3  # [m]


def _log(path: Path, rng: np.random.Generator, n: int, stamps: bool, cmd_tau: bool, ball: bool, phases: bool) -> None:
    """A log of n rows at 1 ms with random joint values and torques (and the optional columns asked for)."""
    cols: dict[str, np.ndarray] = {"t": np.arange(n) * 0.001, "state": np.full(n, 4.0), "quality": np.full(n, 3.0)}
    for prefix, scale in (("cmd_q", 0.3), ("msr_q", 0.3), ("ipo_q", 0.3), ("msr_tau", 20.0), ("ext_tau", 2.0)):
        for i in range(1, 8):
            cols[f"{prefix}{i}"] = (Q0[i - 1] if prefix.endswith("q") else 0.0) + rng.normal(0, scale, n)
    cols["tracking"] = np.ones(n)
    if stamps:
        ns = 1_795_000_000_999_500_000 + np.cumsum(rng.integers(900_000, 1_100_000, n))
        cols["stamp_sec"], cols["stamp_nsec"] = ns // 1_000_000_000, ns % 1_000_000_000
    if phases:
        cols["phase"] = np.where(np.arange(n) < n // 3, 1.0, 2.0)
        cols["row"] = np.where(np.arange(n) < n // 3, 0.0, np.arange(n) - n // 3)
    if cmd_tau:
        for i in range(1, 8):
            cols[f"cmd_tau{i}"] = rng.normal(0, 20.0, n)
    if ball:
        cols["ball_theta"], cols["ball_phi"] = rng.uniform(-1.2, 1.2, n), rng.uniform(-np.pi, np.pi, n)
    fmt = [
        "%.17g" if not k.startswith(("stamp", "state", "quality", "phase", "row", "tracking")) else "%d" for k in cols
    ]
    write_table(path, tuple(cols), np.column_stack(list(cols.values())), fmt=fmt)


def _time(ns: int):
    return TYPES.types["builtin_interfaces/msg/Time"](sec=int(ns // 1_000_000_000), nanosec=int(ns % 1_000_000_000))


def _joint_state(ns: int, position=(), velocity=(), effort=()) -> bytes:
    types = TYPES.types
    msg = types["sensor_msgs/msg/JointState"](
        header=types["std_msgs/msg/Header"](stamp=_time(ns), frame_id=""),
        name=NAMES,
        position=np.asarray(position, dtype=float),
        velocity=np.asarray(velocity, dtype=float),
        effort=np.asarray(effort, dtype=float),
    )
    return bytes(TYPES.serialize_cdr(msg, "sensor_msgs/msg/JointState"))


def _raw(path: Path) -> dict[str, list]:
    with open(path, "rb") as fh:
        out: dict[str, list] = {}
        for _, channel, message in mcap_reader.make_reader(fh).iter_messages(log_time_order=True):
            out.setdefault(channel.topic, []).append((message.log_time, message.data))
    return out


def _pose(transform) -> pin.SE3:
    t, r = transform.translation, transform.rotation
    return pin.XYZQUATToSE3(np.array([t.x, t.y, t.z, r.x, r.y, r.z, r.w]))


def _robot(tool: str | None) -> Robot:
    return Robot(RobotConfig(tool=parse_tool(tool)))


def _check_tf(decoded: dict, times: np.ndarray, q: np.ndarray, ball: np.ndarray | None, tool: str | None) -> None:
    """/tf against pinocchio's joint placements row by row; /tf_static the flange and TCP; the ball's frame."""
    robot = _robot(tool)
    model, data = robot.model, robot.data
    assert [t for t, _ in decoded["/tf"]] == times.tolist()
    for k, (_, tf) in enumerate(decoded["/tf"]):
        pin.forwardKinematics(model, data, q[k])
        frames = [f"lbr_link_{i}" for i in range(8)]
        assert [(tr.header.frame_id, tr.child_frame_id) for tr in tf.transforms[:7]] == list(zip(frames, frames[1:]))
        for i, tr in enumerate(tf.transforms[:7]):
            assert tr.header.stamp.sec * 1_000_000_000 + tr.header.stamp.nanosec == times[k]
            np.testing.assert_allclose(
                _pose(tr.transform).homogeneous, data.liMi[i + 1].homogeneous, atol=1e-12, rtol=0
            )
        if ball is None:
            assert len(tf.transforms) == 7
        else:
            (tr,) = tf.transforms[7:]
            assert (tr.header.frame_id, tr.child_frame_id) == ("lbr_link_0", "lbr_ball")
            np.testing.assert_allclose(
                _pose(tr.transform).homogeneous[:3], np.column_stack([np.eye(3), ball[k]]), atol=1e-12, rtol=0
            )  # the ball's frame: at the ball, axes of lbr_link_0
    [(when, static)] = decoded["/tf_static"]
    assert when == times[0]
    pin.framesForwardKinematics(model, data, q[0])
    flange = data.oMi[7].inverse() * data.oMf[robot.flange_id]
    tcp = data.oMf[robot.flange_id].inverse() * data.oMf[robot.tcp_id]
    got = {tr.child_frame_id: (tr.header.frame_id, _pose(tr.transform)) for tr in static.transforms}
    assert got.keys() == {"lbr_flange", "lbr_tcp"}
    assert got["lbr_flange"][0] == "lbr_link_7" and got["lbr_tcp"][0] == "lbr_flange"
    np.testing.assert_allclose(got["lbr_flange"][1].homogeneous, flange.homogeneous, atol=1e-12, rtol=0)
    np.testing.assert_allclose(got["lbr_tcp"][1].homogeneous, tcp.homogeneous, atol=1e-12, rtol=0)


CASES = {  # rows, optional columns (stamps, cmd_tau, ball, phases), chunk size [bytes], compression, plan, --tool
    "one row": (1, (True, True, True, True), 1 << 20, "zstd", False, None),
    "two rows, nothing optional": (2, (False, False, False, False), 1 << 20, "lz4", False, None),
    "odd rows over small chunks": (301, (True, True, True, True), 3001, "zstd", False, "0.02,-0.01,0.08"),
    "rows wider than a chunk": (17, (True, False, True, False), 700, "none", False, "0,0.05,0"),
    "log and plan": (203, (True, True, True, True), 9000, "lz4", True, None),
    "log without stamps and a plan": (99, (False, True, False, True), 20_000, "none", True, "-0.03,0,0.1"),
}


@pytest.mark.heavy
@pytest.mark.parametrize("case", list(CASES))
def test_every_message_equals_a_reference_built_message_by_message(case, tmp_path, monkeypatch):
    n, (stamps, cmd_tau, ball, phases), chunk, compression, with_plan, tool = CASES[case]
    rng = np.random.default_rng(sorted(CASES).index(case))
    monkeypatch.setattr(bulk, "CHUNK_BYTES", chunk)
    _log(tmp_path / "log.csv", rng, n, stamps, cmd_tau, ball, phases)
    files = [tmp_path / "log.csv"]
    if with_plan:
        t = np.arange(0, 57) * 0.01
        write_joint_csv(tmp_path / "plan.csv", JointTrajectory(t=t, q=Q0 + np.sin(t)[:, None] * rng.normal(0, 0.3, 7)))
        files.append(tmp_path / "plan.csv")
    out = tmp_path / "run.mcap"
    code, _, err = run_in_process(
        [
            "export",
            *files,
            "-o",
            out,
            "--length",
            str(LENGTH),
            "--compression",
            compression,
            *(["--tool", tool] if tool else []),
        ]
    )
    assert code == 0, err
    log = read_table(tmp_path / "log.csv", LOG_COLUMNS, time="increasing")

    def joints(prefix):
        return np.column_stack([log.column(f"{prefix}{i}") for i in range(1, 8)])

    if stamps:
        times = log.column("stamp_sec").astype(np.int64) * 1_000_000_000 + log.column("stamp_nsec").astype(np.int64)
    else:
        times = np.round(log.column("t") * 1e9).astype(np.int64)
    want = {
        "/lbr/joint_states": [
            _joint_state(t, position=p, effort=e) for t, p, e in zip(times, joints("msr_q"), joints("msr_tau"))
        ],
        "/lbr/command/joint_states": [
            _joint_state(t, position=p, effort=e if cmd_tau else ())
            for t, p, e in zip(times, joints("cmd_q"), joints("cmd_tau") if cmd_tau else times)
        ],
        "/lbr/ipo/joint_states": [_joint_state(t, position=p) for t, p in zip(times, joints("ipo_q"))],
        "/lbr/external_torque": [_joint_state(t, effort=e) for t, e in zip(times, joints("ext_tau"))],
    }
    raw = _raw(out)
    for topic, messages in want.items():
        assert [t for t, _ in raw[topic]] == times.tolist(), topic
        assert [m for _, m in raw[topic]] == messages, topic
    decoded = rosbags_messages(out)
    expected_topics = set(want) | {"/tf", "/tf_static", "/lbr/robot_description"}
    ball_at = None
    if ball:
        robot = _robot(tool)
        theta, phi = log.column("ball_theta"), log.column("ball_phi")
        direction = np.column_stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), -np.cos(theta)])
        ball_at = np.array([robot.fk(q).translation for q in joints("msr_q")]) + LENGTH * direction
        points = decoded["/lbr/ball"]
        assert [t for t, _ in points] == times.tolist()
        assert all(m.header.frame_id == "lbr_link_0" for _, m in points)
        np.testing.assert_allclose([[m.point.x, m.point.y, m.point.z] for _, m in points], ball_at, atol=1e-12, rtol=0)
        expected_topics.add("/lbr/ball")
    _check_tf(decoded, times, joints("msr_q"), ball_at, tool)
    [(when, description)] = decoded["/lbr/robot_description"]
    assert when == times[0] and pin.buildModelFromXML(description.data).nq == 7
    if with_plan:
        plan = read_joint_csv(tmp_path / "plan.csv")
        start = times[np.flatnonzero((log.column("phase") == 2) & (log.column("row") == 0))[0]] if phases else times[0]
        plan_times = start + np.round(plan.t * 1e9).astype(np.int64)
        rows = decoded["/lbr/plan/joint_states"]
        assert [t for t, _ in rows] == plan_times.tolist()
        np.testing.assert_array_equal([m.position for _, m in rows], plan.q)
        velocity = np.gradient(plan.q, plan.t, axis=0)  # central differences inside, 0 at the ends (at rest)
        velocity[[0, -1]] = 0.0
        np.testing.assert_allclose([m.velocity for _, m in rows], velocity, atol=1e-9, rtol=0)
        [(when, trajectory)] = decoded["/lbr/joint_trajectory_controller/joint_trajectory"]
        assert when == start and list(trajectory.joint_names) == NAMES
        np.testing.assert_array_equal([p.positions for p in trajectory.points], plan.q)
        assert [
            p.time_from_start.sec * 1_000_000_000 + p.time_from_start.nanosec for p in trajectory.points
        ] == np.round(plan.t * 1e9).astype(np.int64).tolist()
        expected_topics |= {"/lbr/plan/joint_states", "/lbr/joint_trajectory_controller/joint_trajectory"}
    assert set(decoded) == expected_topics


@pytest.mark.heavy
def test_a_plan_alone_gets_its_tf_from_zero(tmp_path, monkeypatch):
    monkeypatch.setattr(bulk, "CHUNK_BYTES", 2000)
    t = np.arange(0, 5) * 0.004
    q = Q0 + np.outer(t, np.linspace(-1, 1, 7))
    write_joint_csv(tmp_path / "plan.csv", JointTrajectory(t=t, q=q))
    code, _, err = run_in_process(["export", tmp_path / "plan.csv", "-o", tmp_path / "plan.mcap"])
    assert code == 0, err
    decoded = rosbags_messages(tmp_path / "plan.mcap")
    plan = read_joint_csv(tmp_path / "plan.csv")
    times = np.round(plan.t * 1e9).astype(np.int64)
    _check_tf(decoded, times, plan.q, None, None)
    assert [bytes(m) for _, m in _raw(tmp_path / "plan.mcap")["/lbr/plan/joint_states"]][0] == _joint_state(
        0, position=plan.q[0], velocity=np.zeros(7)
    )


def test_a_nan_torque_is_refused_naming_file_row_and_column(tmp_path):
    _log(tmp_path / "log.csv", np.random.default_rng(3), 5, True, True, False, False)
    lines = (tmp_path / "log.csv").read_text().splitlines()
    header = lines[0].split(",")
    cells = lines[3].split(",")
    cells[header.index("msr_tau4")] = "nan"
    lines[3] = ",".join(cells)
    (tmp_path / "log.csv").write_text("\n".join(lines) + "\n")
    code, out, err = run_in_process(["export", tmp_path / "log.csv", "-o", tmp_path / "x.mcap"])
    assert code == 2 and len(err.strip().splitlines()) == 1 and "log.csv" in err and "4" in err and "msr_tau4" in err
    assert not (tmp_path / "x.mcap").exists() and out == ""
