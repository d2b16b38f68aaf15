"""Execution logs and plans as an MCAP file in ROS 2's standard messages (rosbag2's layout: ``cdr`` messages,
``ros2msg`` schemas), written with Foxglove's SDK. Topics (``lbr`` is ``--prefix``):

| topic | type | from |
|---|---|---|
| /lbr/joint_states | sensor_msgs/JointState | measured position (msr_q) [rad], measured torque (msr_tau) as effort [Nm] |
| /lbr/command/joint_states | sensor_msgs/JointState | commanded position (cmd_q), the controller's commanded torque (cmd_tau) |
| /lbr/ipo/joint_states | sensor_msgs/JointState | the interpolator's position (ipo_q) |
| /lbr/external_torque | sensor_msgs/JointState | external torque (ext_tau) as effort [Nm] |
| /tf | tf2_msgs/TFMessage | the measured arm: lbr_link_0 → lbr_link_1 … lbr_link_7 (A1..A7), lbr_link_0 → lbr_ball |
| /tf_static | tf2_msgs/TFMessage | lbr_link_7 → lbr_flange → lbr_tcp (flange and --tool), once |
| /lbr/ball | geometry_msgs/PointStamped | the simulated ball [m] in lbr_link_0 (TCP + length · string direction) |
| /lbr/plan/joint_states | sensor_msgs/JointState | a plan's rows: position, velocity (central differences) |
| /lbr/joint_trajectory_controller/joint_trajectory | trajectory_msgs/JointTrajectory | the plan, one message |
| /lbr/robot_description | std_msgs/String | the URDF (also attached as robot_description.urdf) |

Times: a log's controller timestamps (``stamp_sec``, ``stamp_nsec``) when it has them, else its ``t``; a plan on
its own from 0, with a log placed where the log commanded its first row.
"""

from __future__ import annotations

import errno
import logging
import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from trajectories.description import joint_names, link_names
from trajectories.trajectory import N_JOINTS

from . import msgs
from .cdr import stamps

LATCHED_QOS = ("- history: keep_last\n  depth: 1\n  reliability: reliable\n  durability: transient_local\n"
               "  deadline:\n    sec: 0\n    nsec: 0\n  lifespan:\n    sec: 0\n    nsec: 0\n"
               "  liveliness: automatic\n  liveliness_lease_duration:\n    sec: 0\n    nsec: 0\n"
               "  avoid_ros_namespace_conventions: false\n")


@dataclass(frozen=True)
class LogSeries:
    """What an execution log holds for the bag (arrays over its rows)."""

    time_ns: np.ndarray  # (n,) int64 [ns]
    clock: str  # "controller" (its timestamps) or "log" (its t column)
    cmd_q: np.ndarray  # (n, 7) [rad]
    msr_q: np.ndarray
    ipo_q: np.ndarray
    msr_tau: np.ndarray  # (n, 7) [Nm]
    cmd_tau: np.ndarray | None
    ext_tau: np.ndarray
    ball_direction: np.ndarray | None  # (n, 3) unit string direction (simulator's ball_theta, ball_phi)
    plan_start_ns: int | None  # time of the plan's first row (phase 2, row 0)


def log_times(table) -> tuple[np.ndarray, str]:
    """Row times [ns]: the controller's timestamps when present, non-zero and increasing; else the log's t."""
    if table.has("stamp_sec") and table.has("stamp_nsec"):
        sec = table.column("stamp_sec").astype(np.int64)
        ns = sec * 1_000_000_000 + table.column("stamp_nsec").astype(np.int64)
        if sec.min() > 0 and np.all(np.diff(ns) > 0):
            return ns, "controller"
    return np.round(table.column("t") * 1e9).astype(np.int64), "log"


def read_log_series(table) -> LogSeries:
    """The bag's view of an execution log (``table``: trajectories.csvio.Table with LOG_COLUMNS)."""
    ns, clock = log_times(table)

    def joints(prefix: str) -> np.ndarray:
        return np.column_stack([table.column(f"{prefix}{i}") for i in range(1, N_JOINTS + 1)])

    direction = None
    if table.has("ball_theta") and table.has("ball_phi"):
        theta, phi = table.column("ball_theta"), table.column("ball_phi")
        st = np.sin(theta)
        direction = np.column_stack([st * np.cos(phi), st * np.sin(phi), -np.cos(theta)])
    start = None
    if table.has("phase") and table.has("row"):
        rows = np.flatnonzero((table.column("phase") == 2) & (table.column("row") == 0))
        start = int(ns[rows[0]]) if rows.size else None
    return LogSeries(ns, clock, joints("cmd_q"), joints("msr_q"), joints("ipo_q"), joints("msr_tau"),
                     joints("cmd_tau") if table.has("cmd_tau1") else None, joints("ext_tau"), direction, start)


def joint_transforms(robot, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Parent → child transforms of joints A1..A7 along q (n, 7): translations (n, 7, 3) [m] and quaternions
    (n, 7, 4) as (x, y, z, w) — each joint's placement in the model followed by its rotation about z."""
    from scipy.spatial.transform import Rotation

    n = len(q)
    trans = np.empty((n, N_JOINTS, 3))
    quat = np.empty((n, N_JOINTS, 4))
    for i in range(N_JOINTS):
        placement = robot.model.jointPlacements[i + 1]
        px, py, pz, pw = Rotation.from_matrix(placement.rotation).as_quat()
        c, s = np.cos(q[:, i] / 2), np.sin(q[:, i] / 2)  # placement ⊗ (c, 0, 0, s)
        quat[:, i] = np.column_stack([px * c + py * s, py * c - px * s, pz * c + pw * s, pw * c - pz * s])
        trans[:, i] = placement.translation
    return trans, quat


class _WriterErrors(logging.Handler):
    """Collects what foxglove-sdk logs about failed writes (it logs the I/O error, then raises a bare RuntimeError
    at the next write): kept for the error message, not printed."""

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.messages: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(record.getMessage())


class Bag:
    """An MCAP file being written (foxglove-sdk's writer in a context of its own). A write the medium refuses (a
    full disk, a quota, a file-size limit) is an OSError with its errno (``atomic_path`` names the user's file)."""

    def __init__(self, path: Path, compression: str = "zstd") -> None:
        import foxglove
        from foxglove.mcap import MCAPCompression, MCAPWriteOptions

        self.path = path
        self._errors = _WriterErrors()
        logging.getLogger("foxglove").addHandler(self._errors)
        codec = {"zstd": MCAPCompression.Zstd, "lz4": MCAPCompression.Lz4, "none": None}[compression]
        self.context = foxglove.Context()
        self.writer = foxglove.open_mcap(str(path), allow_overwrite=True, context=self.context,
                                         writer_options=MCAPWriteOptions(compression=codec, profile="ros2"))
        self.channels: dict[str, object] = {}
        self.counts: dict[str, int] = {}

    def channel(self, topic: str, short_type: str, latched: bool = False):
        import foxglove

        if topic not in self.channels:
            schema = foxglove.Schema(name=msgs.type_name(short_type), encoding="ros2msg",
                                     data=msgs.definition(short_type).encode())
            metadata = {"offered_qos_profiles": LATCHED_QOS} if latched else None
            self.channels[topic] = foxglove.Channel(topic, schema=schema, message_encoding="cdr",
                                                    context=self.context, metadata=metadata)
            self.counts[topic] = 0
        return self.channels[topic]

    def _write(self, topic: str, short_type: str, times_ns: np.ndarray, data: np.ndarray | list[bytes],
               latched: bool) -> None:
        log = self.channel(topic, short_type, latched).base.log  # bytes straight to the writer's core
        if isinstance(data, list):
            for when, row in zip(times_ns.tolist(), data):
                log(row, when, None)
        else:  # one bytes object, sliced per message (C-speed), not a Python object per row first
            blob, size = data.tobytes(), data.shape[1]
            for k, when in enumerate(times_ns.tolist()):
                log(blob[k * size:(k + 1) * size], when, None)
        self.counts[topic] += len(times_ns)

    def write(self, topic: str, short_type: str, times_ns: np.ndarray, data: np.ndarray | list[bytes],
              latched: bool = False) -> None:
        """One message per row of ``data`` ((n, size) bytes) at ``times_ns``."""
        try:
            self._write(topic, short_type, times_ns, data, latched)
        except RuntimeError as exc:
            raise self._failed(exc) from None

    def close(self) -> None:
        try:
            self.writer.close()
        except RuntimeError as exc:
            raise self._failed(exc) from None
        finally:
            logging.getLogger("foxglove").removeHandler(self._errors)

    def _failed(self, exc: RuntimeError) -> OSError:
        """The OSError behind a failed write: the errno foxglove logged (``Os { code: 28, … }``), else the one a
        probe write to the (doomed, temporary) file meets — a full disk, a quota, a file-size limit —, else EIO."""
        logged = " ".join(self._errors.messages)
        found = re.search(r"Os \{ code: (\d+)", logged)
        if found:
            return OSError(int(found.group(1)), f"the MCAP writer failed: {logged}")
        try:
            with open(self.path, "ab") as fh:
                fh.write(b"\0" * 65536)
                fh.flush()
                os.fsync(fh.fileno())
        except OSError as probe:
            return OSError(probe.errno, f"the MCAP writer failed: {probe.strerror}")
        return OSError(errno.EIO, f"the MCAP writer failed: {exc}")


def _joint_state_topic(bag: Bag, topic: str, names, ns, sec, nsec, position=None, velocity=None, effort=None):
    layout = msgs.joint_state(names, position=position is not None, velocity=velocity is not None,
                              effort=effort is not None)
    values = {"stamp.sec": sec, "stamp.nanosec": nsec}
    for key, arr in (("position", position), ("velocity", velocity), ("effort", effort)):
        if arr is not None:
            values[key] = arr
    bag.write(topic, "sensor_msgs/JointState", ns, layout.fill(len(ns), values))


def write_tf(bag: Bag, robot, prefix: str, ns: np.ndarray, q: np.ndarray, ball: np.ndarray | None = None) -> None:
    """/tf of the arm along q (and the ball's frame), /tf_static of the flange and TCP (at the first time)."""
    links = link_names(prefix)
    edges = tuple((links[i], links[i + 1]) for i in range(N_JOINTS))
    trans, quat = joint_transforms(robot, q)
    if ball is not None:
        edges += ((links[0], f"{prefix}_ball"),)
        trans = np.concatenate([trans, np.nan_to_num(ball)[:, None, :]], axis=1)
        quat = np.concatenate([quat, np.tile([0.0, 0.0, 0.0, 1.0], (len(q), 1, 1))], axis=1)
    sec, nsec = stamps(ns)
    values = {}
    for k in range(len(edges)):
        values[f"stamp{k}.sec"], values[f"stamp{k}.nanosec"] = sec, nsec
        for j, axis in enumerate("xyz"):
            values[f"t{k}.{axis}"] = trans[:, k, j]
        for j, axis in enumerate("xyzw"):
            values[f"r{k}.{axis}"] = quat[:, k, j]
    bag.write("/tf", "tf2_msgs/TFMessage", ns, msgs.tf_message(edges).fill(len(ns), values))
    model = robot.model
    flange = model.frames[robot.flange_id].placement
    tcp = flange.inverse() * model.frames[robot.tcp_id].placement
    static = msgs.tf_message(((links[N_JOINTS], links[-2]), (links[-2], links[-1])))
    fixed = {}
    from scipy.spatial.transform import Rotation

    for k, placement in enumerate((flange, tcp)):
        fixed[f"stamp{k}.sec"], fixed[f"stamp{k}.nanosec"] = sec[:1], nsec[:1]
        for j, axis in enumerate("xyz"):
            fixed[f"t{k}.{axis}"] = placement.translation[j]
        for j, axis in enumerate("xyzw"):
            fixed[f"r{k}.{axis}"] = Rotation.from_matrix(placement.rotation).as_quat()[j]
    bag.write("/tf_static", "tf2_msgs/TFMessage", ns[:1], static.fill(1, fixed), latched=True)


def write_log(bag: Bag, series: LogSeries, robot, prefix: str, length: float) -> None:
    """Every topic of an execution log."""
    names = joint_names(prefix)
    ns = series.time_ns
    sec, nsec = stamps(ns)
    _joint_state_topic(bag, f"/{prefix}/joint_states", names, ns, sec, nsec, position=series.msr_q,
                       effort=series.msr_tau)
    _joint_state_topic(bag, f"/{prefix}/command/joint_states", names, ns, sec, nsec, position=series.cmd_q,
                       effort=series.cmd_tau)
    _joint_state_topic(bag, f"/{prefix}/ipo/joint_states", names, ns, sec, nsec, position=series.ipo_q)
    _joint_state_topic(bag, f"/{prefix}/external_torque", names, ns, sec, nsec, effort=series.ext_tau)
    ball = None
    if series.ball_direction is not None:
        tcp = robot.link_frames(series.msr_q)[:, N_JOINTS + 1, :3, 3]
        ball = tcp + length * series.ball_direction
        layout = msgs.point_stamped(link_names(prefix)[0])
        bag.write(f"/{prefix}/ball", "geometry_msgs/PointStamped", ns,
                  layout.fill(len(ns), {"stamp.sec": sec, "stamp.nanosec": nsec, "x": ball[:, 0], "y": ball[:, 1],
                                        "z": ball[:, 2]}))
    write_tf(bag, robot, prefix, ns, series.msr_q, ball)


def write_plan(bag: Bag, t: np.ndarray, q: np.ndarray, robot, prefix: str, start_ns: int, with_tf: bool) -> None:
    """A plan: its rows as joint states (and /tf when it is the only motion), and one JointTrajectory."""
    from trajectories.differences import derivatives

    dt = float((t[-1] - t[0]) / (len(t) - 1)) if len(t) > 1 else 1.0
    qd, qdd = derivatives(q, dt, order=2)
    qd[[0, -1]] = qdd[[0, -1]] = 0.0  # plans start and end at rest (lbr check)
    names = joint_names(prefix)
    ns = start_ns + np.round(t * 1e9).astype(np.int64)
    sec, nsec = stamps(ns)
    _joint_state_topic(bag, f"/{prefix}/plan/joint_states", names, ns, sec, nsec, position=q, velocity=qd)
    message = msgs.joint_trajectory(names, t, q, qd, qdd)
    bag.write(f"/{prefix}/joint_trajectory_controller/joint_trajectory", "trajectory_msgs/JointTrajectory",
              ns[:1], [message])
    if with_tf:
        write_tf(bag, robot, prefix, ns, q)


def write_description(bag: Bag, urdf: str, prefix: str, time_ns: int) -> None:
    """The URDF as a latched std_msgs/String and as the attachment robot_description.urdf."""
    bag.write(f"/{prefix}/robot_description", "std_msgs/String", np.array([time_ns]), [msgs.string_message(urdf)],
              latched=True)
    bag.writer.attach(log_time=time_ns, create_time=time_ns, name="robot_description.urdf",
                      media_type="application/xml", data=urdf.encode())
