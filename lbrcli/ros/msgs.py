"""The standard ROS 2 messages `lbr export` writes: their definitions (the ``ros2msg`` schemas an MCAP file carries,
dependencies appended as rosbag2 writes them) and their CDR layouts (:mod:`.cdr`).
"""

from __future__ import annotations

import numpy as np

from .cdr import Layout, stamps

_DEFS = {
    "builtin_interfaces/Time": "int32 sec\nuint32 nanosec\n",
    "builtin_interfaces/Duration": "int32 sec\nuint32 nanosec\n",
    "std_msgs/Header": "builtin_interfaces/Time stamp\nstring frame_id\n",
    "std_msgs/String": "string data\n",
    "sensor_msgs/JointState": "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\n"
    "float64[] effort\n",
    "geometry_msgs/Vector3": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/Point": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
    "geometry_msgs/Transform": "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n",
    "geometry_msgs/TransformStamped": "std_msgs/Header header\nstring child_frame_id\n"
    "geometry_msgs/Transform transform\n",
    "geometry_msgs/PointStamped": "std_msgs/Header header\ngeometry_msgs/Point point\n",
    "tf2_msgs/TFMessage": "geometry_msgs/TransformStamped[] transforms\n",
    "trajectory_msgs/JointTrajectoryPoint": "float64[] positions\nfloat64[] velocities\nfloat64[] accelerations\n"
    "float64[] effort\nbuiltin_interfaces/Duration time_from_start\n",
    "trajectory_msgs/JointTrajectory": "std_msgs/Header header\nstring[] joint_names\n"
    "trajectory_msgs/JointTrajectoryPoint[] points\n",
}
_DEPS = {
    "std_msgs/Header": ("builtin_interfaces/Time",),
    "sensor_msgs/JointState": ("std_msgs/Header", "builtin_interfaces/Time"),
    "geometry_msgs/Transform": ("geometry_msgs/Vector3", "geometry_msgs/Quaternion"),
    "geometry_msgs/TransformStamped": (
        "std_msgs/Header",
        "builtin_interfaces/Time",
        "geometry_msgs/Transform",
        "geometry_msgs/Vector3",
        "geometry_msgs/Quaternion",
    ),
    "geometry_msgs/PointStamped": ("std_msgs/Header", "builtin_interfaces/Time", "geometry_msgs/Point"),
    "tf2_msgs/TFMessage": (
        "geometry_msgs/TransformStamped",
        "std_msgs/Header",
        "builtin_interfaces/Time",
        "geometry_msgs/Transform",
        "geometry_msgs/Vector3",
        "geometry_msgs/Quaternion",
    ),
    "trajectory_msgs/JointTrajectoryPoint": ("builtin_interfaces/Duration",),
    "trajectory_msgs/JointTrajectory": (
        "std_msgs/Header",
        "builtin_interfaces/Time",
        "trajectory_msgs/JointTrajectoryPoint",
        "builtin_interfaces/Duration",
    ),
}
_SEPARATOR = "=" * 80


def type_name(short: str) -> str:
    """'sensor_msgs/JointState' → 'sensor_msgs/msg/JointState' (the name MCAP schemas and rosbag2 use)."""
    package, name = short.split("/")
    return f"{package}/msg/{name}"


def definition(short: str) -> str:
    """The ``ros2msg`` schema text of a message with its dependencies."""
    parts = [_DEFS[short]]
    for dep in _DEPS.get(short, ()):
        parts.append(f"{_SEPARATOR}\nMSG: {dep}\n{_DEFS[dep]}")
    return "\n".join(parts)


def header(layout: Layout, stamp: str, frame_id: str) -> None:
    layout.stamp(stamp)
    layout.string(frame_id)


def joint_state(
    names: tuple[str, ...], frame_id: str = "", position: bool = True, velocity: bool = False, effort: bool = False
) -> Layout:
    """sensor_msgs/JointState with slots ``stamp``, ``position``, ``velocity``, ``effort`` (those asked for)."""
    n = len(names)
    layout = Layout()
    header(layout, "stamp", frame_id)
    layout.strings(names)
    for field, wanted in (("position", position), ("velocity", velocity), ("effort", effort)):
        layout.float64s(field, n if wanted else 0)
    return layout


def _transform(layout: Layout, k: int, parent: str, child: str) -> None:
    header(layout, f"stamp{k}", parent)
    layout.string(child)
    layout.float64(f"t{k}", 3)
    layout.float64(f"r{k}", 4)


def tf_message(edges: tuple[tuple[str, str], ...]) -> Layout:
    """tf2_msgs/TFMessage of transforms parent → child (slots ``stamp{k}``, translation ``t{k}`` (x, y, z) [m],
    rotation ``r{k}`` (x, y, z, w))."""
    layout = Layout()
    layout.count(len(edges))
    for k, (parent, child) in enumerate(edges):
        _transform(layout, k, parent, child)
    return layout


def point_stamped(frame_id: str) -> Layout:
    """geometry_msgs/PointStamped (slots ``stamp``, ``point`` (x, y, z) [m])."""
    layout = Layout()
    header(layout, "stamp", frame_id)
    layout.float64("point", 3)
    return layout


def string_message(text: str) -> bytes:
    """std_msgs/String."""
    layout = Layout()
    layout.string(text)
    return bytes(layout.buf)


def joint_trajectory(
    names: tuple[str, ...],
    t: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    qdd: np.ndarray,
    stamp_ns: int = 0,
    frame_id: str = "",
) -> bytes:
    """trajectory_msgs/JointTrajectory: one point per row (positions, velocities, accelerations; time from start
    = t [s])."""
    layout = Layout()
    header(layout, "stamp", frame_id)
    layout.strings(names)
    layout.count(len(t))
    n = len(names)
    for k in range(len(t)):
        for field in ("p", "v", "a"):
            layout.float64s(f"{field}{k}", n)
        layout.float64s(f"e{k}", 0)
        layout.stamp(f"d{k}")
    durations = stamps(np.round(np.asarray(t, dtype=float) * 1e9).astype(np.int64))
    values: dict[str, np.ndarray] = {"stamp": stamps(stamp_ns)}
    for k in range(len(t)):
        values[f"p{k}"], values[f"v{k}"], values[f"a{k}"], values[f"d{k}"] = q[k], qd[k], qdd[k], durations[k]
    return layout.fill(1, values)[0].tobytes()
