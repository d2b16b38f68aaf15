"""Execution logs and plans as an MCAP file in ROS 2's standard messages (rosbag2's layout: ``cdr`` messages,
``ros2msg`` schemas), written in bulk (:mod:`.bulk`). Topics (``lbr`` is ``--prefix``):

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

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from trajectories.description import joint_names, link_names
from trajectories.trajectory import N_JOINTS

from . import msgs
from .cdr import Layout, stamps

LATCHED_QOS = (
    "- history: keep_last\n  depth: 1\n  reliability: reliable\n  durability: transient_local\n"
    "  deadline:\n    sec: 0\n    nsec: 0\n  lifespan:\n    sec: 0\n    nsec: 0\n"
    "  liveliness: automatic\n  liveliness_lease_duration:\n    sec: 0\n    nsec: 0\n"
    "  avoid_ros_namespace_conventions: false\n"
)


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

    def joints(prefix: str) -> np.ndarray:  # (n, 7): a view of the table when the columns are in order
        names = tuple(f"{prefix}{i}" for i in range(1, N_JOINTS + 1))
        first = table.names.index(names[0])
        if table.names[first : first + N_JOINTS] == names:
            return table.data[:, first : first + N_JOINTS]
        return np.column_stack([table.column(name) for name in names])

    direction = None
    if table.has("ball_theta") and table.has("ball_phi"):
        theta, phi = table.column("ball_theta"), table.column("ball_phi")
        st = np.sin(theta)
        direction = np.column_stack([st * np.cos(phi), st * np.sin(phi), -np.cos(theta)])
    start = None
    if table.has("phase") and table.has("row"):
        rows = np.flatnonzero((table.column("phase") == 2) & (table.column("row") == 0))
        start = int(ns[rows[0]]) if rows.size else None
    return LogSeries(
        ns,
        clock,
        joints("cmd_q"),
        joints("msr_q"),
        joints("ipo_q"),
        joints("msr_tau"),
        joints("cmd_tau") if table.has("cmd_tau1") else None,
        joints("ext_tau"),
        direction,
        start,
    )


def joint_transforms(robot, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Parent → child transforms of joints A1..A7 along q (n, 7): translations (7, 3) [m] (fixed) and quaternions
    (n, 7, 4) as (x, y, z, w) — each joint's placement in the model followed by its rotation about z."""
    from scipy.spatial.transform import Rotation

    trans = np.empty((N_JOINTS, 3))
    quat = np.empty((len(q), N_JOINTS, 4))
    for i in range(N_JOINTS):
        placement = robot.model.jointPlacements[i + 1]
        px, py, pz, pw = Rotation.from_matrix(placement.rotation).as_quat()
        c, s = np.cos(q[:, i] / 2), np.sin(q[:, i] / 2)  # placement ⊗ (c, 0, 0, s)
        quat[:, i] = np.column_stack([px * c + py * s, py * c - px * s, pz * c + pw * s, pw * c - pz * s])
        trans[i] = placement.translation
    return trans, quat


def _rotate(x, y, z, w, v) -> tuple:
    """v (3,) rotated by unit quaternions with components x, y, z, w (n,): v + w t + u × t with t = 2 u × v."""
    tx, ty, tz = 2 * (y * v[2] - z * v[1]), 2 * (z * v[0] - x * v[2]), 2 * (x * v[1] - y * v[0])
    return v[0] + w * tx + (y * tz - z * ty), v[1] + w * ty + (z * tx - x * tz), v[2] + w * tz + (x * ty - y * tx)


def chain_positions(trans: np.ndarray, quat: np.ndarray, tip: np.ndarray) -> np.ndarray:
    """(n, 3) [m] in the base: the point ``tip`` (3,) of the last joint's frame through the joint transforms of
    :func:`joint_transforms` — what a TF client composes from /tf (quaternion products component by component)."""
    x, y, z, w = quat[:, 0].T
    p = trans[0]
    for i in range(1, len(trans)):
        p = tuple(a + b for a, b in zip(p, _rotate(x, y, z, w, trans[i])))
        bx, by, bz, bw = quat[:, i].T
        x, y, z, w = (
            w * bx + x * bw + y * bz - z * by,
            w * by - x * bz + y * bw + z * bx,
            w * bz + x * by - y * bx + z * bw,
            w * bw - x * bx - y * by - z * bz,
        )
    return np.column_stack([a + b for a, b in zip(p, _rotate(x, y, z, w, tip))])


class Bag:
    """An MCAP file being built (rosbag2's layout, written in bulk by :mod:`.bulk` when closed). A write the medium
    refuses (a full disk, a quota, a file-size limit) is an OSError with its errno (``atomic_path`` names the file)."""

    def __init__(self, path: Path, compression: str = "zstd") -> None:
        from .bulk import BulkWriter

        self.path = path
        self.writer = BulkWriter(compression, profile="ros2", library="lbr")
        self.channels: dict[str, int] = {}
        self.counts: dict[str, int] = {}

    def channel(self, topic: str, short_type: str, latched: bool = False) -> int:
        if topic not in self.channels:
            schema = self.writer.schema(msgs.type_name(short_type), "ros2msg", msgs.definition(short_type).encode())
            metadata = {"offered_qos_profiles": LATCHED_QOS} if latched else None
            self.channels[topic] = self.writer.channel(topic, "cdr", schema, metadata)
            self.counts[topic] = 0
        return self.channels[topic]

    def write(
        self,
        topic: str,
        short_type: str,
        times_ns: np.ndarray,
        message: Layout | bytes,
        values: dict[str, np.ndarray] | None = None,
        latched: bool = False,
    ) -> None:
        """Messages at ``times_ns``: a layout with its slots' ``values`` (arrays over the messages or constants), or
        one message's bytes."""
        layout = message if isinstance(message, Layout) else Layout(bytearray(message))
        self.writer.add(self.channel(topic, short_type, latched), times_ns, layout.buf, layout.slots, values)
        self.counts[topic] += len(times_ns)

    def attach(self, name: str, media_type: str, data: bytes, time_ns: int) -> None:
        self.writer.attach(name, media_type, data, log_time=time_ns, create_time=time_ns)

    def close(self) -> None:
        with open(self.path, "wb") as fh:
            self.writer.write(fh)


def _joint_state_topic(bag: Bag, topic: str, names, ns, stamp, position=None, velocity=None, effort=None):
    layout = msgs.joint_state(
        names, position=position is not None, velocity=velocity is not None, effort=effort is not None
    )
    values = {"stamp": stamp}
    for key, arr in (("position", position), ("velocity", velocity), ("effort", effort)):
        if arr is not None:
            values[key] = arr
    bag.write(topic, "sensor_msgs/JointState", ns, layout, values)


def write_tf(
    bag: Bag, robot, prefix: str, ns: np.ndarray, trans: np.ndarray, quat: np.ndarray, ball: np.ndarray | None = None
) -> None:
    """/tf of the arm (the joint transforms of :func:`joint_transforms`) and the ball's frame, /tf_static of the
    flange and TCP (at the first time)."""
    from scipy.spatial.transform import Rotation

    links = link_names(prefix)
    stamp = stamps(ns)
    edges = tuple((links[i], links[i + 1]) for i in range(N_JOINTS))
    values = {}
    for k in range(N_JOINTS):
        values[f"stamp{k}"], values[f"t{k}"], values[f"r{k}"] = stamp, trans[k], quat[:, k]
    if ball is not None:
        edges += ((links[0], f"{prefix}_ball"),)
        k = N_JOINTS
        values[f"stamp{k}"], values[f"t{k}"], values[f"r{k}"] = stamp, np.nan_to_num(ball), np.array([0, 0, 0, 1.0])
    bag.write("/tf", "tf2_msgs/TFMessage", ns, msgs.tf_message(edges), values)
    model = robot.model
    flange = model.frames[robot.flange_id].placement
    tcp = flange.inverse() * model.frames[robot.tcp_id].placement
    static = msgs.tf_message(((links[N_JOINTS], links[-2]), (links[-2], links[-1])))
    fixed = {}
    for k, placement in enumerate((flange, tcp)):
        fixed[f"stamp{k}"], fixed[f"t{k}"] = stamp[:1], placement.translation
        fixed[f"r{k}"] = Rotation.from_matrix(placement.rotation).as_quat()
    bag.write("/tf_static", "tf2_msgs/TFMessage", ns[:1], static, fixed, latched=True)


def write_log(bag: Bag, series: LogSeries, robot, prefix: str, length: float) -> None:
    """Every topic of an execution log."""
    names = joint_names(prefix)
    ns = series.time_ns
    stamp = stamps(ns)
    _joint_state_topic(bag, f"/{prefix}/joint_states", names, ns, stamp, position=series.msr_q, effort=series.msr_tau)
    _joint_state_topic(
        bag, f"/{prefix}/command/joint_states", names, ns, stamp, position=series.cmd_q, effort=series.cmd_tau
    )
    _joint_state_topic(bag, f"/{prefix}/ipo/joint_states", names, ns, stamp, position=series.ipo_q)
    _joint_state_topic(bag, f"/{prefix}/external_torque", names, ns, stamp, effort=series.ext_tau)
    trans, quat = joint_transforms(robot, series.msr_q)
    ball = None
    if series.ball_direction is not None:
        tcp = chain_positions(trans, quat, robot.model.frames[robot.tcp_id].placement.translation)
        ball = tcp + length * series.ball_direction
        bag.write(
            f"/{prefix}/ball",
            "geometry_msgs/PointStamped",
            ns,
            msgs.point_stamped(link_names(prefix)[0]),
            {"stamp": stamp, "point": ball},
        )
    write_tf(bag, robot, prefix, ns, trans, quat, ball)


def write_plan(bag: Bag, t: np.ndarray, q: np.ndarray, robot, prefix: str, start_ns: int, with_tf: bool) -> None:
    """A plan: its rows as joint states (and /tf when it is the only motion), and one JointTrajectory."""
    from trajectories.differences import derivatives

    dt = float((t[-1] - t[0]) / (len(t) - 1)) if len(t) > 1 else 1.0
    qd, qdd = derivatives(q, dt, order=2)
    qd[[0, -1]] = qdd[[0, -1]] = 0.0  # plans start and end at rest (lbr check)
    names = joint_names(prefix)
    ns = start_ns + np.round(t * 1e9).astype(np.int64)
    _joint_state_topic(bag, f"/{prefix}/plan/joint_states", names, ns, stamps(ns), position=q, velocity=qd)
    message = msgs.joint_trajectory(names, t, q, qd, qdd)
    bag.write(
        f"/{prefix}/joint_trajectory_controller/joint_trajectory", "trajectory_msgs/JointTrajectory", ns[:1], message
    )
    if with_tf:
        write_tf(bag, robot, prefix, ns, *joint_transforms(robot, q))


def write_description(bag: Bag, urdf: str, prefix: str, time_ns: int) -> None:
    """The URDF as a latched std_msgs/String and as the attachment robot_description.urdf."""
    bag.write(
        f"/{prefix}/robot_description", "std_msgs/String", np.array([time_ns]), msgs.string_message(urdf), latched=True
    )
    bag.attach("robot_description.urdf", "application/xml", urdf.encode(), time_ns)
