"""A reproducible suite of TCP paths for testing and benchmarking the path IK.

Kinds (each at 1 ms and 5 ms sampling):

- ``joint``: FK of smooth random joint paths (sums of sines) whose positions, speeds and accelerations stay
  inside the limits — reachable by construction, the joint path is the witness;
- ``singular``: the same through or near the wrist (A6 = 0), elbow (A4 = 0) and shoulder (A2 = 0) singularities;
- ``limit``: the same with one joint brushing its position limit;
- ``line``, ``circle``, ``figure8``: Cartesian shapes with the flange down, tilted up to 45° and yawing up to
  ±90°, with smooth (rest-to-rest) or periodic timing. Their reachability is shown by any solver returning a
  joint path that is accurate and inside the limits (see ``verify_joint_path``).

``build_rest_suite`` adds paths the way users write them, mostly starting and ending at rest: handwriting and
drawings on a table and a whiteboard with pens of several lengths and other flanges, near-singular passes,
orientation-heavy moves, FK-built paths time-warped to rest, paths that leave the workspace (beyond the reach,
too close to the shoulder, beyond a joint's limit at every arm angle, A4 faster than its limit), and a 60 s
handwriting path at 1 ms.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.spatial.transform import Rotation

from .chain import rotation_log
from .limits import JointLimits
from .robot import Flange, Robot, RobotConfig
from .start_poses import THESIS_START

DOWN = np.diag([1.0, -1.0, -1.0])  # flange z along base −z


@dataclass(frozen=True)
class TaskPath:
    """TCP poses over time, with the joint path they were made from when built by FK."""

    name: str
    kind: str
    t: np.ndarray  # (n,) [s]
    position: np.ndarray  # (n, 3) [m]
    rotation: np.ndarray  # (n, 3, 3)
    witness: np.ndarray | None = None  # (n, 7) [rad], a feasible joint path for these poses
    config: RobotConfig = RobotConfig()  # flange and tool the poses are of

    @property
    def dt(self) -> float:
        return float(self.t[1] - self.t[0])


@dataclass(frozen=True)
class PathCheck:
    """How well a joint path realises a task path: TCP errors and peak joint rates relative to the limits."""

    position_error: float  # [m], max over samples
    rotation_error: float  # [rad]
    position_ratio: float  # max |q| / limit
    velocity_ratio: float  # max |q̇| / limit (backward differences)
    acceleration_ratio: float  # max |q̈| / limit (second differences)

    def ok(self, position_tolerance: float = 1e-6, rotation_tolerance: float = 1e-5, acceleration: bool = False):
        within = self.position_ratio <= 1.0 and self.velocity_ratio <= 1.0 + 1e-6
        if acceleration:
            within = within and self.acceleration_ratio <= 1.0 + 1e-6
        return bool(self.position_error <= position_tolerance and self.rotation_error <= rotation_tolerance and within)


def verify_joint_path(robot: Robot, path: TaskPath, q: np.ndarray, limits: JointLimits) -> PathCheck:
    """FK of q (n, 7) [rad] against the path, and its peak joint position, speed and acceleration ratios."""
    pos, rot = robot.fk_path(q)
    perr = float(np.linalg.norm(pos - path.position, axis=1).max())
    rerr = float(np.linalg.norm(rotation_log(path.rotation @ rot.transpose(0, 2, 1)), axis=1).max())
    dt = path.dt
    vel = np.abs(np.diff(q, axis=0)) / dt
    acc = np.abs(np.diff(q, 2, axis=0)) / dt**2
    return PathCheck(
        position_error=perr,
        rotation_error=rerr,
        position_ratio=float((np.abs(q) / limits.position).max()),
        velocity_ratio=float((vel / limits.velocity).max()) if len(vel) else 0.0,
        acceleration_ratio=float((acc / limits.acceleration).max()) if len(acc) else 0.0,
    )


def _smooth_ramp(t: np.ndarray, duration: float) -> np.ndarray:
    """0 → 1 quintic rest-to-rest ramp over [0, duration]."""
    s = np.clip(t / duration, 0.0, 1.0)
    return s**3 * (10 - 15 * s + 6 * s**2)


def random_joint_path(
    rng: np.random.Generator,
    limits: JointLimits,
    dt: float,
    duration: float,
    center: np.ndarray,
    amplitude: np.ndarray,
    speed: float = 0.8,
) -> np.ndarray:
    """Smooth joint path (n, 7) [rad] around ``center``: sums of sines starting at rest, scaled so that peak
    speed and acceleration are at most ``speed`` × the limits and positions stay 1° inside the limits."""
    t = np.arange(int(round(duration / dt)) + 1) * dt
    q = np.zeros((len(t), 7))
    for j in range(7):
        for _ in range(3):
            f = rng.uniform(0.1, 0.6)  # [Hz]
            q[:, j] += (
                rng.normal() * (1 - np.cos(2 * np.pi * f * t)) + rng.normal() * 0.3 * np.sin(2 * np.pi * f * t) ** 2
            )
    q -= q[0]
    peak = np.abs(q).max(axis=0) + 1e-12
    q *= amplitude / peak
    vel = np.abs(np.gradient(q, dt, axis=0)).max(axis=0) / limits.velocity
    acc = np.abs(np.gradient(np.gradient(q, dt, axis=0), dt, axis=0)).max(axis=0) / limits.acceleration
    scale = min(1.0, speed / max(vel.max(), 1e-12), speed / max(acc.max(), 1e-12))
    q = q * scale
    bound = limits.position - math.radians(1.0)
    room_up = np.maximum(bound - center, 0.0) / np.maximum(q.max(axis=0), 1e-12)
    room_down = np.maximum(bound + center, 0.0) / np.maximum(-q.min(axis=0), 1e-12)
    return center + q * np.minimum(1.0, np.minimum(room_up, room_down))


def _rot_z(a: np.ndarray) -> np.ndarray:
    return Rotation.from_rotvec(np.outer(a, [0.0, 0.0, 1.0])).as_matrix()


def _cartesian(
    name: str,
    kind: str,
    t: np.ndarray,
    position: np.ndarray,
    tilt: float,
    tilt_axis: float,
    yaw: np.ndarray,
) -> TaskPath:
    """Flange-down orientation tilted by ``tilt`` [rad] about a horizontal axis at ``tilt_axis`` [rad] from x,
    then turned by ``yaw`` (n,) [rad] about the vertical."""
    axis = np.array([math.cos(tilt_axis), math.sin(tilt_axis), 0.0])
    tilted = Rotation.from_rotvec(axis * tilt).as_matrix() @ DOWN
    rot = np.einsum("nij,jk->nik", _rot_z(yaw), tilted)
    return TaskPath(name=name, kind=kind, t=t, position=position, rotation=rot)


def cartesian_path(
    shape: str,
    dt: float,
    center: tuple[float, float, float] = (0.55, 0.0, 0.45),
    size: float = 0.12,  # [m]
    duration: float = 4.0,  # [s]
    tilt_deg: float = 0.0,
    tilt_axis_deg: float = 0.0,
    yaw_deg: float = 0.0,  # amplitude of the yaw oscillation [deg]
    yaw_offset_deg: float = 0.0,
    plane: str = "yz",
    timing: str = "periodic",
    name: str | None = None,
) -> TaskPath:
    """A line, circle or figure-eight of size ``size`` [m] about ``center`` [m] in a base plane."""
    t = np.arange(int(round(duration / dt)) + 1) * dt
    phase = 2 * np.pi * (_smooth_ramp(t, duration) if timing == "smooth" else t / duration)
    if shape == "line":
        u, v = size * np.sin(phase / 2) ** 2 * 2 - size, np.zeros_like(t)
        u = u + size  # start at the centre, go out by 2·size and back
    elif shape == "circle":
        u, v = size * np.sin(phase), size * (np.cos(phase) - 1.0)
    elif shape == "figure8":
        u, v = size * np.sin(phase), size * 0.5 * np.sin(2 * phase)
    else:
        raise ValueError(f"unknown shape {shape!r}")
    axes = {"yz": (1, 2), "xy": (0, 1), "xz": (0, 2)}[plane]
    pos = np.tile(np.asarray(center, dtype=float), (len(t), 1))
    pos[:, axes[0]] += u
    pos[:, axes[1]] += v
    yaw = np.radians(yaw_offset_deg + yaw_deg * np.sin(phase))
    label = name or f"{shape}-{plane}-tilt{tilt_deg:g}-yaw{yaw_deg:g}-{timing}-{dt * 1e3:g}ms"
    return _cartesian(label, shape, t, pos, math.radians(tilt_deg), math.radians(tilt_axis_deg), yaw)


def issue_circle(dt: float) -> TaskPath:
    """Flange-down circle x 0.55, y 0.12 sin, z 0.45 + 0.12 (cos − 1) [m], yaw 30° sin, 4 s."""
    return cartesian_path("circle", dt, yaw_deg=30.0, name=f"issue-circle-{dt * 1e3:g}ms")


# Joint-space centres: the thesis start and other comfortable configurations [rad].
CENTRES = (
    THESIS_START,
    (0.3, 0.6, 0.2, -1.2, 0.3, 0.9, -0.4),
    (-0.8, 0.4, -0.5, -1.6, -0.6, 1.0, 0.8),
    (1.2, -0.5, 0.7, 1.4, -0.4, -0.8, 1.5),
    (0.0, 0.9, 0.0, -0.9, 0.0, 0.9, 0.0),
    (-1.5, 0.3, 1.0, -1.0, 1.2, -1.1, -1.0),
)


def _fk_path(robot: Robot, name: str, kind: str, dt: float, q: np.ndarray) -> TaskPath:
    t = np.arange(len(q)) * dt
    pos, rot = robot.fk_path(q)
    return TaskPath(name=name, kind=kind, t=t, position=pos, rotation=rot, witness=q)


def build_suite(robot: Robot, limits: JointLimits, seed: int = 0, quick: bool = False) -> list[TaskPath]:
    """The path suite, per sample period (1 ms and 5 ms): 25 FK-built joint paths (12 random around 6 centres,
    6 through or near singularities, 7 brushing a position limit) and 13 Cartesian shapes (with the issue's
    circle) → 76 paths; ``quick`` keeps every fourth (and the issue circle)."""
    rng = np.random.default_rng(seed)
    paths: list[TaskPath] = []
    duration = 3.0
    for dt in (1e-3, 5e-3):
        # random joint paths around each centre, moderate and fast
        for c, centre in enumerate(CENTRES):
            for speed, amp in ((0.5, 0.6), (0.9, 1.2)):
                amplitude = np.full(7, amp) * rng.uniform(0.5, 1.0, 7)
                q = random_joint_path(rng, limits, dt, duration, np.array(centre), amplitude, speed)
                paths.append(_fk_path(robot, f"joint-c{c}-v{speed:g}-{dt * 1e3:g}ms", "joint", dt, q))
        # through or near singularities: the named joint crosses (or approaches) 0 while the others move
        for joint, offset in ((5, 0.0), (5, 0.02), (3, 0.03), (3, 0.08), (1, 0.0), (1, 0.05)):
            centre = np.array(CENTRES[rng.integers(len(CENTRES))])
            amplitude = rng.uniform(0.2, 0.6, 7)
            q = random_joint_path(rng, limits, dt, duration, centre, amplitude, 0.6)
            t = np.arange(len(q)) * dt
            wave = np.cos(np.pi * t / duration)
            # through 0 (±0.5 rad), or down to ``offset`` at mid-path and back
            q[:, joint] = 0.5 * wave if offset == 0.0 else offset + 0.5 * wave**2
            kind_name = {5: "wrist", 3: "elbow", 1: "shoulder"}[joint]
            paths.append(_fk_path(robot, f"singular-{kind_name}-{offset:g}-{dt * 1e3:g}ms", "singular", dt, q))
        # brushing a position limit (0.5°–2° inside), one joint at a time
        for joint in range(7):
            centre = np.array(CENTRES[rng.integers(len(CENTRES))])
            amplitude = rng.uniform(0.2, 0.5, 7)
            q = random_joint_path(rng, limits, dt, duration, centre, amplitude, 0.6)
            t = np.arange(len(q)) * dt
            sign = rng.choice([-1.0, 1.0])
            inside = math.radians(rng.uniform(0.5, 2.0))
            peak = sign * (limits.position[joint] - inside)
            q[:, joint] = peak - sign * 0.6 * np.cos(np.pi * t / duration) ** 2  # 0.6 rad inside → limit → back
            paths.append(_fk_path(robot, f"limit-A{joint + 1}-{dt * 1e3:g}ms", "limit", dt, q))
        # Cartesian shapes
        shapes = [
            ("line", dict(center=(0.4, -0.15, 0.4), size=0.15, plane="xy", timing="smooth", duration=6.0)),
            ("line", dict(center=(0.45, 0.0, 0.3), size=0.15, plane="xz", timing="smooth", tilt_deg=30)),
            ("line", dict(center=(0.4, -0.2, 0.5), size=0.2, plane="yz", timing="smooth", yaw_deg=90, duration=8.0)),
            (
                "line",
                dict(center=(0.35, 0.0, 0.25), size=0.1, plane="xy", timing="smooth", tilt_deg=45, tilt_axis_deg=90),
            ),
            ("circle", dict(yaw_deg=30.0)),
            ("circle", dict(center=(0.5, 0.1, 0.35), size=0.1, plane="xy", tilt_deg=20)),
            ("circle", dict(center=(0.55, 0.0, 0.5), size=0.15, plane="yz", tilt_deg=45, tilt_axis_deg=-90)),
            ("circle", dict(center=(0.0, 0.55, 0.4), size=0.12, plane="xz", yaw_deg=90, yaw_offset_deg=90)),
            ("circle", dict(center=(0.5, -0.2, 0.4), size=0.1, plane="xy", tilt_deg=45, yaw_deg=60, timing="smooth")),
            ("figure8", dict(center=(0.55, 0.0, 0.4), size=0.15, plane="yz")),
            ("figure8", dict(center=(0.5, 0.0, 0.3), size=0.12, plane="xy", tilt_deg=30, yaw_deg=45)),
            (
                "figure8",
                dict(
                    center=(-0.3, 0.45, 0.45),
                    size=0.12,
                    plane="xz",
                    tilt_deg=45,
                    tilt_axis_deg=45,
                    yaw_deg=90,
                    yaw_offset_deg=120,
                ),
            ),
        ]
        for shape, kw in shapes:
            paths.append(cartesian_path(shape, dt, **{"duration": 4.0, **kw}))
        paths.append(issue_circle(dt))
    if quick:
        paths = [p for i, p in enumerate(paths) if i % 4 == 0 or p.name.startswith("issue-circle")]
    return paths


# ---- paths the way users write them (``build_rest_suite``) ------------------------------------------------------

PEN = RobotConfig(tool=(0.0, 0.0, 0.1))  # a 10 cm pen on the touch flange
LONG_PEN = RobotConfig(flange=Flange.STANDARD, tool=(0.0, 0.0, 0.18))
OFFSET_PEN = RobotConfig(flange=Flange.TOUCH_PNEUMATIC, tool=(0.04, -0.02, 0.12))


def rest_timing(t: np.ndarray, ramp: float) -> np.ndarray:
    """Path parameter s(t) ∈ [0, 1] at rest at both ends: the speed rises over ``ramp`` [s] (3x² − 2x³: the
    acceleration is continuous), stays constant, and falls to zero at the end."""
    duration = float(t[-1])
    ramp = min(ramp, 0.5 * duration)
    up = np.clip(t / ramp, 0.0, 1.0)
    down = np.clip((duration - t) / ramp, 0.0, 1.0)
    v = np.minimum(up * up * (3 - 2 * up), down * down * (3 - 2 * down))
    s = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])
    return s / s[-1]


def _frame(normal: np.ndarray, yaw: float = 0.0) -> np.ndarray:
    """Rotation whose z axis is ``normal`` (the pen's direction), turned by ``yaw`` [rad] about it."""
    z = np.asarray(normal, dtype=float) / np.linalg.norm(normal)
    ref = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = ref - z * (ref @ z)
    x /= np.linalg.norm(x)
    base = np.column_stack([x, np.cross(z, x), z])
    return base @ Rotation.from_rotvec([0.0, 0.0, yaw]).as_matrix()


def _curve(kind: str, sigma: np.ndarray, size: float) -> np.ndarray:
    """Planar curves (m, 2) [m] of parameter sigma ∈ [0, 1]: handwriting loops, a rose, a spiral, a heart."""
    if kind == "loops":  # cursive "llllll": a prolate trochoid
        th = 2 * np.pi * 6 * sigma
        r = size / (2 * np.pi * 6)
        return np.column_stack([r * th - 0.09 * size * np.sin(th) - 0.5 * size, 0.09 * size * (1 - np.cos(th))])
    if kind == "rose":
        ph = 2 * np.pi * sigma
        rad = 0.5 * size * (0.6 + 0.4 * np.cos(5 * ph))
        return np.column_stack([rad * np.cos(ph) - 0.5 * size, rad * np.sin(ph)])
    if kind == "spiral":
        ph = 2 * np.pi * 3 * sigma
        rad = 0.5 * size * sigma
        return np.column_stack([rad * np.cos(ph), rad * np.sin(ph)])
    if kind == "heart":
        ph = 2 * np.pi * sigma
        x = 16 * np.sin(ph) ** 3
        y = 13 * np.cos(ph) - 5 * np.cos(2 * ph) - 2 * np.cos(3 * ph) - np.cos(4 * ph)
        return 0.5 * size / 17 * np.column_stack([x, y - 5])
    raise ValueError(f"unknown curve {kind!r}")


def drawing_path(
    name: str,
    kind: str,
    dt: float,
    duration: float,
    centre: tuple[float, float, float],
    plane: str = "table",
    size: float = 0.3,
    config: RobotConfig = PEN,
    pen_tilt_deg: float = 0.0,
    yaw_deg: float = 0.0,
    rest: bool = True,
    ramp: float = 0.5,
) -> TaskPath:
    """A curve drawn with a pen: on the ``table`` (horizontal, pen pointing down) or a ``board`` (the vertical plane
    facing the robot, pen pointing along +x), tilted by ``pen_tilt_deg`` toward the drawing direction. ``rest``:
    at rest at both ends; otherwise the pen moves at constant speed from the first sample to the last."""
    t = np.arange(int(round(duration / dt)) + 1) * dt
    sigma = rest_timing(t, ramp) if rest else t / t[-1]
    uv = _curve(kind, sigma, size)
    c = np.asarray(centre, dtype=float)
    if plane == "table":
        e1, e2, normal = np.array([0.0, 1.0, 0.0]), np.array([-1.0, 0.0, 0.0]), np.array([0.0, 0.0, -1.0])
    else:
        e1, e2, normal = np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0])
    pos = c + uv[:, :1] * e1 + uv[:, 1:] * e2
    tilt = Rotation.from_rotvec(e2 * math.radians(pen_tilt_deg)).as_matrix()
    rot = np.broadcast_to(tilt @ _frame(normal, math.radians(yaw_deg)), (len(t), 3, 3)).copy()
    return TaskPath(name=name, kind="drawing", t=t, position=pos, rotation=rot, config=config)


def move_path(
    name: str,
    dt: float,
    duration: float,
    start: tuple[float, float, float],
    end: tuple[float, float, float] | None = None,
    rotation: np.ndarray = DOWN,
    config: RobotConfig = RobotConfig(),
    kind: str = "line",
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0),
    angle_deg: float = 0.0,
) -> TaskPath:
    """A rest-to-rest move (quintic timing): the TCP along a straight line from ``start`` to ``end`` [m] (held at
    ``start`` without one) while its orientation, ``rotation`` at first, turns by ``angle_deg`` about the base
    ``axis``."""
    t = np.arange(int(round(duration / dt)) + 1) * dt
    s = _smooth_ramp(t, float(t[-1]))
    a = np.asarray(start, dtype=float)
    b = a if end is None else np.asarray(end, dtype=float)
    pos = (1 - s[:, None]) * a + s[:, None] * b
    ax = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    rot = Rotation.from_rotvec(np.outer(s * math.radians(angle_deg), ax)).as_matrix() @ rotation
    return TaskPath(name=name, kind=kind, t=t, position=pos, rotation=rot, config=config)


def rest_joint_path(
    robot: Robot, name: str, kind: str, q: np.ndarray, dt: float, limits: JointLimits, share: float = 0.8
) -> TaskPath:
    """FK of a joint path time-warped to start and end at rest (q(T·s(t/T)), s quintic) and stretched in time until
    its speeds and accelerations are within ``share`` of the limits: reachable by construction."""
    t = np.arange(len(q)) * dt
    spline = CubicSpline(t, q, axis=0)
    stretch = 1.0
    for _ in range(20):
        tw = np.arange(int(round(stretch * t[-1] / dt)) + 1) * dt
        qw = spline(_smooth_ramp(tw, float(tw[-1])) * t[-1])
        vel = np.abs(np.diff(qw, axis=0)).max(axis=0) / dt / limits.velocity
        acc = np.abs(np.diff(qw, 2, axis=0)).max(axis=0) / dt**2 / limits.acceleration
        factor = max(vel.max() / share, math.sqrt(acc.max() / share))
        if factor <= 1.0:
            break
        stretch *= factor * 1.02
    return _fk_path(robot, name, kind, dt, qw)


def _drawing_paths(dt: float, ms: str) -> list[TaskPath]:
    """Handwriting and drawings at step ``dt`` [s]: pens of several lengths, the table and the board."""
    paths: list[TaskPath] = []
    # handwriting and drawings, pens of several lengths, the table and the board
    paths += [
        drawing_path(f"write-table-pen-{ms}", "loops", dt, 6.0, (0.5, 0.0, 0.15), "table", 0.36),
        drawing_path(f"write-board-{ms}", "loops", dt, 6.0, (0.62, 0.0, 0.55), "board", 0.4, RobotConfig()),
        drawing_path(
            f"write-board-longpen-tilt20-{ms}",
            "loops",
            dt,
            5.0,
            (0.7, 0.05, 0.45),
            "board",
            0.32,
            LONG_PEN,
            pen_tilt_deg=20.0,
        ),
        drawing_path(
            f"rose-table-offsetpen-{ms}", "rose", dt, 5.0, (0.62, 0.1, 0.12), "table", 0.3, OFFSET_PEN, yaw_deg=40.0
        ),
        drawing_path(f"spiral-table-{ms}", "spiral", dt, 4.0, (0.6, -0.15, 0.2), "table", 0.3),
        drawing_path(
            f"heart-board-pen-tilt30-{ms}", "heart", dt, 4.0, (0.6, -0.1, 0.5), "board", 0.3, pen_tilt_deg=30.0
        ),
        drawing_path(f"spiral-board-fast-{ms}", "spiral", dt, 1.5, (0.78, 0.1, 0.55), "board", 0.3, LONG_PEN),
        drawing_path(f"write-table-moving-ends-{ms}", "loops", dt, 5.0, (0.5, 0.0, 0.15), "table", 0.36, rest=False),
        drawing_path(
            f"rose-board-moving-ends-{ms}",
            "rose",
            dt,
            4.0,
            (0.6, 0.0, 0.5),
            "board",
            0.3,
            RobotConfig(),
            rest=False,
        ),
    ]
    return paths


def _move_paths(dt: float, ms: str) -> list[TaskPath]:
    """Moves at rest at both ends: near-singular passes and orientation-heavy moves."""
    paths: list[TaskPath] = []
    # near-singular passes: over the base axis (shoulder), at full stretch (elbow), forearm along the flange
    paths += [
        move_path(f"near-full-stretch-{ms}", dt, 3.0, (0.65, 0.0, 0.4), (0.9, 0.0, 0.4), _frame([1.0, 0.0, 0.0])),
        move_path(f"near-wrist-singular-{ms}", dt, 3.0, (0.4, -0.2, 0.6), (0.4, 0.2, 0.6)),
        move_path(f"pen-near-wrist-singular-{ms}", dt, 3.0, (0.5, -0.3, 0.3), (0.5, 0.3, 0.3), DOWN, PEN),
    ]
    # orientation-heavy moves at rest at both ends
    paths += [
        move_path(f"spin-flange-170-{ms}", dt, 3.0, (0.55, 0.0, 0.4), kind="orientation", angle_deg=170.0),
        move_path(
            f"tumble-to-horizontal-{ms}",
            dt,
            3.0,
            (0.5, 0.1, 0.45),
            kind="orientation",
            axis=(0, 1, 0),
            angle_deg=-90.0,
        ),
        move_path(f"tilt-pen-50-{ms}", dt, 2.0, (0.5, -0.2, 0.25), None, DOWN, PEN, "orientation", (1, -1, 0), 50.0),
        move_path(f"spin-pen-300-{ms}", dt, 4.0, (0.5, 0.0, 0.3), None, DOWN, PEN, "orientation", angle_deg=300.0),
    ]
    return paths


def _rest_joint_paths(robot: Robot, limits: JointLimits, dt: float, ms: str) -> list[TaskPath]:
    """FK-built joint paths time-warped to rest: random, through singularities, brushing a limit."""
    paths: list[TaskPath] = []
    # FK-built joint paths time-warped to rest: random, through singularities, brushing a limit
    rng = np.random.default_rng(17 if dt < 2e-3 else 18)
    for c, centre in enumerate(CENTRES[:4]):
        q = random_joint_path(rng, limits, dt, 3.0, np.array(centre), np.full(7, 0.8) * rng.uniform(0.5, 1, 7), 0.5)
        paths.append(rest_joint_path(robot, f"rest-joint-c{c}-{ms}", "joint", q, dt, limits))
    for joint in (5, 3, 1):
        q = random_joint_path(rng, limits, dt, 3.0, np.array(CENTRES[1]), rng.uniform(0.2, 0.6, 7), 0.5)
        q[:, joint] = 0.5 * np.cos(np.pi * np.arange(len(q)) * dt / 3.0) + (0.03 if joint == 3 else 0.0)
        paths.append(rest_joint_path(robot, f"rest-singular-A{joint + 1}-{ms}", "singular", q, dt, limits))
    return paths


def _leaving_paths(dt: float, ms: str) -> list[TaskPath]:
    """Paths that leave the workspace (refused: the first pose no joint path reaches inside the limits)."""
    paths: list[TaskPath] = []
    # leaving the workspace (refused: the first pose that no joint path reaches inside the limits)
    paths += [
        move_path(f"leave-over-the-base-{ms}", dt, 3.0, (0.05, -0.25, 0.75), (0.05, 0.25, 0.75), kind="leave"),
        move_path(f"leave-reach-outward-{ms}", dt, 3.0, (0.5, 0.0, 0.3), (1.0, 0.0, 0.3), kind="leave"),
        move_path(f"leave-reach-upward-pen-{ms}", dt, 3.0, (0.3, 0.2, 0.6), (0.3, 0.2, 1.2), DOWN, PEN, "leave"),
        move_path(f"leave-to-shoulder-{ms}", dt, 3.0, (0.5, 0.0, 0.3), (0.12, 0.0, 0.3), kind="leave"),
        move_path(f"leave-tumble-up-{ms}", dt, 3.0, (0.45, 0.0, 0.15), kind="leave", axis=(0, 1, 0), angle_deg=150.0),
        move_path(f"leave-a4-too-fast-{ms}", dt, 0.25, (0.45, 0.0, 0.45), (0.75, 0.0, 0.45), kind="leave"),
    ]
    return paths


def build_rest_suite(limits: JointLimits, quick: bool = False) -> list[TaskPath]:
    """The paths of the module docstring's second part (``quick``: a third of them, and no 60 s path)."""
    robot = Robot()
    paths: list[TaskPath] = []
    for dt in (1e-3, 5e-3):
        ms = f"{dt * 1e3:g}ms"
        paths += _drawing_paths(dt, ms) + _move_paths(dt, ms) + _rest_joint_paths(robot, limits, dt, ms)
        paths += _leaving_paths(dt, ms)
    if quick:
        paths = paths[::3]
    else:
        paths.append(long_writing(1e-3, 60.0))
        paths.append(long_writing(1e-3, 60.0, leave_at=50.0))
    return paths


def long_writing(dt: float, duration: float, leave_at: float | None = None) -> TaskPath:
    """Handwriting for ``duration`` [s] on the table with a pen, at rest at both ends: 120 loops (≈ 0.15 m/s) on a
    baseline that sweeps left and right three times while it comes 0.15 m closer; with ``leave_at`` [s] the pen
    drifts away from the robot from that time on, out of reach."""
    t = np.arange(int(round(duration / dt)) + 1) * dt
    sigma = rest_timing(t, 0.5)
    theta = 2 * np.pi * 120 * sigma
    loop = 0.012  # [m]
    pos = np.column_stack(
        [
            0.60 - 0.15 * sigma - loop * (1 - np.cos(theta)),
            0.25 * np.sin(2 * np.pi * 3 * sigma) - loop * np.sin(theta),
            np.full(len(t), 0.15),
        ]
    )
    name = f"write-60s-{dt * 1e3:g}ms"
    if leave_at is not None:
        pos[:, 0] += 0.04 * np.clip(t - leave_at, 0.0, None) ** 2
        name = f"write-60s-leaving-at-{leave_at:g}s-{dt * 1e3:g}ms"
    rot = np.broadcast_to(_frame([0.0, 0.0, -1.0]), (len(t), 3, 3)).copy()
    return TaskPath(
        name=name, kind="drawing" if leave_at is None else "leave", t=t, position=pos, rotation=rot, config=PEN
    )
