"""How a horizontal offset of the pivot maps onto the joints along a planned joint path, and how much offset the
joints have room for — computed once, before anything is sent, so that the damper's cycle is a table lookup.

Per row k: ``maps[k]`` (7, 2) = the first two columns of the TCP Jacobian's pseudo-inverse (base-aligned): a TCP
offset (Δx, Δy) [m] with unchanged height and orientation is Δq ≈ maps[k]·(Δx, Δy) [rad]. ``bounds[k]`` = (speed
[m/s], −a, a [m/s²], −j, j [m/s³]) of the offset on each axis such that the planned joint velocity and acceleration
plus those of the offset stay within ``share`` of the limits (the rest is left for the terms of the moving map), the
jerk within half the joint jerk limits; a window around each row takes the smallest bound, so that the offset has
time to ramp its acceleration down before a row that leaves little room. ``travel`` [m]: the offset all rows allow
(joint position limits with a margin). ``rejoin_bounds[k]``: the same while the joints do not follow the rows but
a rejoin after lost FRI messages that uses up to ``rejoin_share`` of the limits (never more than ``bounds[k]``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .damping import DampingOptions, pivot_acceleration


@dataclass(frozen=True)
class CorrectionPlan:
    """The tables of a planned path of n rows at ``dt`` [s] (see the module)."""

    dt: float
    maps: np.ndarray  # (n, 7, 2) [rad/m]
    bounds: np.ndarray  # (n, 5) speed [m/s], a_lo, a_hi [m/s²], j_lo, j_hi [m/s³]
    planned_accel: np.ndarray  # (n, 2) TCP acceleration along base x, y [m/s²] (second differences)
    travel: float  # [m]
    rejoin_bounds: np.ndarray  # (n, 5) as bounds, while a rejoin moves the joints
    rejoin_share: float  # of the velocity/acceleration/jerk limits a rejoin may use

    def __len__(self) -> int:
        return len(self.maps)


def _window_min(x: np.ndarray, half: int) -> np.ndarray:
    """min over [k − half, k + half] per k."""
    from scipy.ndimage import minimum_filter1d

    return minimum_filter1d(x, size=2 * half + 1, mode="nearest")


def correction_plan(robot, q: np.ndarray, limits, dt: float, options: DampingOptions = DampingOptions(),
                    share: float = 0.95, rejoin_share: float = 0.8) -> CorrectionPlan:  # fmt: skip
    """The tables for the joint path ``q`` (n, 7) [rad] sampled every ``dt`` [s] on ``robot``
    (:class:`trajectories.robot.Robot`, its TCP is the pivot); ``limits`` the joint limits."""
    import pinocchio as pin

    q = np.asarray(q, dtype=float)
    n = len(q)
    model, data, fid = robot.model, robot.data, robot.tcp_id
    maps = np.empty((n, 7, 2))
    pos = np.empty((n, 3))
    for k in range(n):
        J = pin.computeFrameJacobian(model, data, q[k], fid, pin.LOCAL_WORLD_ALIGNED)
        pos[k] = data.oMf[fid].translation
        maps[k] = np.linalg.pinv(J)[:, :2]
    spread = np.abs(maps).sum(axis=2)  # (n, 7): joint motion per unit offset motion on both axes at once
    spread = np.maximum(spread, 1e-9)
    vel = np.zeros((n, 7))
    acc = np.zeros((n, 7))
    if n > 1:
        d = np.diff(q, axis=0) / dt
        vel[:-1] = np.abs(d)
        vel[1:] = np.maximum(vel[1:], np.abs(d))
    if n > 2:
        acc[1:-1] = np.abs(np.diff(q, 2, axis=0)) / dt**2
    v_room = np.clip(share * np.asarray(limits.velocity) - vel, 0.0, None) / spread
    a_room = np.clip(share * np.asarray(limits.acceleration) - acc, 0.0, None) / spread
    j_room = 0.5 * np.asarray(limits.jerk) / spread
    half = int(math.ceil(options.acceleration / options.jerk / dt)) + 2
    bounds = _bounds(v_room, a_room, j_room, half, options)
    spare = max(0.0, share - rejoin_share)
    v_spare = spare * np.asarray(limits.velocity) / spread
    a_spare = spare * np.asarray(limits.acceleration) / spread
    j_spare = 0.5 * (1.0 - rejoin_share) * np.asarray(limits.jerk) / spread
    rejoin_bounds = _bounds(np.minimum(v_room, v_spare), np.minimum(a_room, a_spare), np.minimum(j_room, j_spare),
                            half, options)  # fmt: skip
    upper = np.asarray(limits.position)
    p_room = ((0.98 * upper - np.abs(q)) / spread).min()
    travel = float(max(0.0, min(options.travel, p_room)))
    return CorrectionPlan(dt, maps, bounds, pivot_acceleration(pos[:, :2], dt), travel, rejoin_bounds, rejoin_share)


def _bounds(
    v_room: np.ndarray, a_room: np.ndarray, j_room: np.ndarray, half: int, options: DampingOptions
) -> np.ndarray:
    """(n, 5) offset bounds from per-joint room (n, 7) in offset units, the smallest over a window of ±half rows."""
    speed = np.minimum(_window_min(v_room.min(axis=1), half), options.velocity)
    a = np.minimum(_window_min(a_room.min(axis=1), half), options.acceleration)
    j = np.minimum(_window_min(j_room.min(axis=1), half), options.jerk)
    return np.column_stack([speed, -a, a, -j, j])
