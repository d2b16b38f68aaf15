"""What the 3D view draws, frame by frame, as plain arrays: arm poses (the project's kinematic model), balls and
their pivots, the session state, pivot paths, turning points, obstacles. No drawing here (:mod:`.draw` does it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .inputs import JOINT, LOG, ArmSeries, BallSeries, InputFile
from .timeline import Alignment

N_FRAMES = 9  # poses per arm: bodies A1..A7, flange, TCP
TCP = 8
PATH_POINTS = 4000  # a drawn path keeps at most this many points
STATE_NAMES = ("IDLE", "MONITORING_WAIT", "MONITORING_READY", "COMMANDING_WAIT", "COMMANDING_ACTIVE")
PHASE_NAMES = ("", "move to start", "trajectory", "settle", "brake", "ipo held", "waiting for the sway")


@dataclass(frozen=True)
class ViewSettings:
    """How to draw: string length [m], frame rate of the replay [1/s], ball radius [m], cup (radius, depth) [m]."""

    length: float = 0.25  # [m], flange + tool to the ball centre
    fps: float = 30.0  # [1/s]
    ball_radius: float = 0.02  # [m]
    cup: tuple[float, float] | None = None  # (inner radius, depth) [m] of an open cylinder on the TCP


@dataclass(frozen=True)
class ArmTrack:
    """One arm over the frames: poses of its 9 frames as position [m] + quaternion (w, x, y, z)."""

    key: str  # scene node group, e.g. "run_log/measured"
    label: str
    role: str  # planned, commanded or measured
    poses: np.ndarray  # (m, 9, 7)


@dataclass(frozen=True)
class BallTrack:
    """One ball over the frames (NaN rows: not drawn) and the pivot its string hangs from."""

    key: str
    label: str
    kind: str  # predicted, simulated or tracked
    ball: np.ndarray  # (m, 3) [m]
    pivot: np.ndarray  # (m, 3) [m]


@dataclass(frozen=True)
class PathTrack:
    key: str
    label: str
    points: np.ndarray  # (k, 3) [m]
    role: str  # planned, commanded, measured or task


@dataclass(frozen=True)
class Scene:
    """Everything drawn, on frames t = k / fps of the time line."""

    t: np.ndarray  # (m,) [s]
    arms: tuple[ArmTrack, ...]
    balls: tuple[BallTrack, ...]
    status: tuple[str, ...]  # (m,) session state and phase per frame
    paths: tuple[PathTrack, ...] = ()
    turning_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))  # (j, 3) [m]
    obstacles: tuple = ()  # planners.obstacles.Obstacle
    cup_arm: str | None = None  # key of the arm carrying the cup
    settings: ViewSettings = ViewSettings()

    @property
    def duration(self) -> float:
        return float(self.t[-1]) if len(self.t) else 0.0


def node_key(path: str) -> str:
    """A scene-node name for a file: its stem with anything but letters, digits, - and _ replaced."""
    stem = Path(path).stem
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in stem) or "file"


def poses_from_frames(frames: np.ndarray) -> np.ndarray:
    """(m, k, 4, 4) homogeneous transforms → (m, k, 7) position + quaternion (w, x, y, z)."""
    from scipy.spatial.transform import Rotation

    m, k = frames.shape[:2]
    quat = Rotation.from_matrix(frames[..., :3, :3].reshape(-1, 3, 3)).as_quat(scalar_first=True).reshape(m, k, 4)
    return np.concatenate([frames[..., :3, 3], quat], axis=2)


def sample(t_file: np.ndarray, values: np.ndarray, times: np.ndarray, clamp: bool = True) -> np.ndarray:
    """Values (n, c) at ``times`` by linear interpolation; outside the file's span the end values (clamp) or NaN."""
    out = np.column_stack([np.interp(times, t_file, values[:, j]) for j in range(values.shape[1])])
    if not clamp:
        out[(times < t_file[0] - 1e-9) | (times > t_file[-1] + 1e-9)] = np.nan
    return out


def turning_points(p: np.ndarray, dt: float, stop_share: float = 0.02, turn_deg: float = 20.0) -> np.ndarray:
    """Where a pivot path (n, 3) [m] sampled every ``dt`` [s] starts, ends, or stops or reverses and turns by more
    than ``turn_deg``: one point per stop (j, 3). Stopped: slower than ``stop_share`` of the peak speed."""
    if len(p) < 3:
        return p[:1].copy()
    v = np.diff(p, axis=0) / dt
    speed = np.linalg.norm(v, axis=1)
    vmax = float(speed.max())
    if vmax < 1e-4:  # [m/s]: the pivot does not move
        return p[:1].copy()
    stopped = speed < stop_share * vmax
    reverses = np.zeros(len(v), dtype=bool)
    reverses[1:] = np.einsum("ij,ij->i", v[1:], v[:-1]) < 0.0
    candidate = np.flatnonzero(stopped | reverses)
    if candidate.size == 0:
        return np.zeros((0, 3))
    groups = np.split(candidate, np.flatnonzero(np.diff(candidate) > 1) + 1)
    moving = np.flatnonzero(~stopped)
    idx = []
    for g in groups:
        before, after = moving[moving < g[0]], moving[moving > g[-1]]
        if before.size and after.size:  # a pause on a straight line (a shaper's dwell) is no turning point
            a, b = v[before[-1]], v[after[0]]
            if np.dot(a, b) > np.cos(np.radians(turn_deg)) * np.linalg.norm(a) * np.linalg.norm(b):
                continue
        idx.append(int(g[np.argmin(speed[g])]))
    return p[idx]


def _decimate(n: int, limit: int) -> slice:
    return slice(None, None, max(1, math.ceil(n / limit)))


def _status(
    state_file: InputFile | None, offset: float, plan: ArmSeries | None, plan_offset: float, times: np.ndarray
) -> tuple[str, ...]:
    """'t = 1.23 s · COMMANDING_ACTIVE · trajectory row 45' per frame."""
    out = []
    if state_file is not None:
        st = state_file.state
        tv = st.t + offset
        k = np.clip(np.searchsorted(tv, times, side="right") - 1, 0, len(tv) - 1)
        inside = (times >= tv[0] - 1e-9) & (times <= tv[-1] + 1e-9)
        for tau, j, ok in zip(times, k, inside):
            if not ok:
                out.append(f"t = {tau:.3f} s · outside {Path(state_file.path).name}")
                continue
            state = STATE_NAMES[st.state[j]] if 0 <= st.state[j] < len(STATE_NAMES) else f"state {st.state[j]}"
            phase = PHASE_NAMES[st.phase[j]] if 0 <= st.phase[j] < len(PHASE_NAMES) else f"phase {st.phase[j]}"
            row = f" row {st.row[j]}" if st.row[j] >= 0 and phase == "trajectory" else ""
            out.append(f"t = {tau:.3f} s · {state}" + (f" · {phase}{row}" if phase else ""))
        return tuple(out)
    if plan is not None and len(plan.t) > 1:
        dt = (plan.t[-1] - plan.t[0]) / (len(plan.t) - 1)
        rows = np.clip(np.round((times - plan_offset - plan.t[0]) / dt), 0, len(plan.t) - 1).astype(int)
        return tuple(f"t = {tau:.3f} s · plan row {r}" for tau, r in zip(times, rows))
    return tuple(f"t = {tau:.3f} s" for tau in times)


def build_scene(files: list[InputFile], alignment: Alignment, robot, settings: ViewSettings = ViewSettings()) -> Scene:
    """Frames of everything the files describe, on the aligned time line (``robot``: trajectories.robot.Robot)."""
    duration = alignment.duration
    m = max(1, int(math.floor(duration * settings.fps + 1e-9)) + 1)
    times = np.arange(m) / settings.fps
    off = alignment.offsets
    arms: list[ArmTrack] = []
    tcp_at_frames: dict[tuple[str, str], np.ndarray] = {}
    paths: list[PathTrack] = []
    for f in files:
        for series in f.arms:
            key = f"{node_key(f.path)}/{series.role}"
            q = sample(series.t + off[f.path], series.q, times)
            frames = robot.link_frames(q)
            arms.append(ArmTrack(key, f"{f.name} ({series.role})", series.role, poses_from_frames(frames)))
            tcp_at_frames[(f.path, series.role)] = frames[:, TCP, :3, 3]
            if series.role in ("planned", "measured"):
                dec = _decimate(len(series.q), PATH_POINTS)
                paths.append(
                    PathTrack(
                        f"{node_key(f.path)}/{series.role}_path",
                        f"{f.name} pivot path",
                        robot.link_frames(series.q[dec])[:, TCP, :3, 3],
                        series.role,
                    )
                )
        if f.pivot_path is not None:
            dec = _decimate(len(f.pivot_path), PATH_POINTS)
            paths.append(PathTrack(f"{node_key(f.path)}/path", f"{f.name} pivot path", f.pivot_path[dec], "task"))
    balls = [_ball_track(f, b, off[f.path], times, settings, tcp_at_frames) for f in files for b in f.balls]
    plan_file = next((f for f in files if f.kind == JOINT), None)
    logs = [f for f in files if f.kind == LOG]
    turning = np.zeros((0, 3))
    source = plan_file.arms[0] if plan_file else (logs[0].arms[0] if logs else None)
    if source is not None and len(source.t) > 2:
        dec = _decimate(len(source.q), 20000)
        p = robot.link_frames(source.q[dec])[:, TCP, :3, 3]
        turning = turning_points(p, float(np.median(np.diff(source.t[dec]))))
    status = _status(
        logs[0] if logs else None,
        off[logs[0].path] if logs else 0.0,
        plan_file.arms[0] if plan_file else None,
        off[plan_file.path] if plan_file else 0.0,
        times,
    )
    obstacles = tuple(o for f in files for o in f.obstacles)
    carrier = next((a.key for a in arms if a.role == "measured"), arms[0].key if arms else None)
    return Scene(
        times,
        tuple(arms),
        tuple(b for b in balls if b is not None),
        status,
        tuple(paths),
        turning,
        obstacles,
        carrier if settings.cup else None,
        settings,
    )


def _ball_track(
    f: InputFile,
    ball: BallSeries,
    offset: float,
    times: np.ndarray,
    settings: ViewSettings,
    tcp_at_frames: dict[tuple[str, str], np.ndarray],
) -> BallTrack | None:
    """A ball at the frames: its own file's measured arm as pivot (simulated), else the plan's (predicted), else any
    measured arm (tracked); a ball with no arm at all hangs from the origin."""
    prefer = {
        "simulated": ("measured", "planned"),
        "predicted": ("planned", "commanded", "measured"),
        "tracked": ("measured", "planned", "commanded"),
    }[ball.kind]
    pivot = tcp_at_frames.get((f.path, prefer[0]))
    for role in prefer:
        if pivot is not None:
            break
        pivot = next((p for (path, r), p in tcp_at_frames.items() if r == role), None)
    if pivot is None:
        pivot = np.zeros((len(times), 3))
    tv = ball.t + offset
    if ball.position is not None:
        position = sample(tv, ball.position, times, clamp=False)
    else:
        s = sample(tv, ball.direction, times, clamp=False)
        s /= np.linalg.norm(s, axis=1, keepdims=True)
        position = pivot + settings.length * s
    return BallTrack(f"{node_key(f.path)}/ball_{ball.kind}", f"{f.name} ({ball.kind} ball)", ball.kind, position, pivot)
