"""The swing-up's pivot path on the arm: TCP poses along base y, IK, task-space bounds, and verification.

The pivot (TCP = flange + tool, the string attachment) starts at its pose at q_start and moves along base +y
at constant x and z. Its orientation is either kept ``fixed`` (thesis §5.3.2: T_start with y substituted) or
``follow``s the direction from the base z axis (turned about the vertical by atan2(y, x), as joint A1 alone
would turn it). The ball only feels the pivot position; ``fixed`` is badly conditioned at the thesis pose
(wrist near singular: ≈0.18 m/s and ≈0.9 m/s² along y within the joint limits), ``follow`` is not (≈1 m/s,
≈5 m/s²).

Verification: joint path → FK of the TCP → acceleration realised by position commands at the sample rate
(``pendulum.SampledAcceleration``) → the project's string model without the cup (``string_sim``: the spherical
pendulum while taut, free flight when the string goes slack, the jerk when it tightens again), θ = θ_y of the
anchor→ball direction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from trajectories.differences import derivatives
from trajectories.ik import IkOptions, solve_ik_path
from trajectories.limits import JointLimits
from trajectories.robot import Robot
from trajectories.trajectory import JointTrajectory

from .pendulum import SampledAcceleration, direction_from_angles
from .swingup_plan import TaskBounds

ORIENTATIONS = ("fixed", "follow")
# Strong null-space pull toward q_start: q becomes (nearly) a function of the pivot position, so the arm
# rests as soon as the pivot does (the default 0.02/sample leaves a slow self-motion after the stop).
IK_OPTIONS = IkOptions(nullspace_gain=0.3)


@dataclass(frozen=True)
class ArmSetup:
    """Where the swing happens: start configuration q_start (7,) [rad] and the pivot orientation mode."""

    q_start: tuple[float, ...]
    orientation: str = "follow"  # "fixed" | "follow"

    def __post_init__(self) -> None:
        if self.orientation not in ORIENTATIONS:
            raise ValueError(f"orientation must be one of {ORIENTATIONS}, got {self.orientation!r}")


def _rot_z(angle: np.ndarray) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    r = np.zeros((np.size(angle), 3, 3))
    r[:, 0, 0], r[:, 0, 1], r[:, 1, 0], r[:, 1, 1], r[:, 2, 2] = c, -s, s, c, 1.0
    return r


def pivot_poses(robot: Robot, setup: ArmSetup, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """TCP positions (n, 3) [m] and rotations (n, 3, 3) for pivot displacements x [m]: (n,) along base y, or
    (n, 2) along base y and z."""
    start = robot.fk(np.asarray(setup.q_start, dtype=float))
    p0, r0 = start.translation, start.rotation
    x = np.asarray(x, dtype=float)
    yz = np.column_stack([x, np.zeros_like(x)]) if x.ndim == 1 else x
    pos = p0[None, :] + np.column_stack([np.zeros(len(yz)), yz])
    if setup.orientation == "fixed":
        rot = np.broadcast_to(r0, (len(pos), 3, 3)).copy()
    else:
        yaw = np.arctan2(pos[:, 1], pos[:, 0]) - math.atan2(p0[1], p0[0])
        rot = np.einsum("nij,jk->nik", _rot_z(yaw), r0)
    return pos, rot


def joint_path(
    robot: Robot, setup: ArmSetup, t: np.ndarray, x: np.ndarray, limits: JointLimits, progress=None
) -> tuple[JointTrajectory, float]:
    """IK of the pivot path (thesis §5.3.2, one pose per sample) → joint trajectory and max TCP error [m]."""
    pos, rot = pivot_poses(robot, setup, x)
    res = solve_ik_path(
        robot, pos, rot, np.asarray(setup.q_start, dtype=float), limits, IK_OPTIONS, times=t, progress=progress
    )
    return JointTrajectory(t=np.asarray(t, dtype=float), q=res.q), res.max_position_error


def axis_bounds(
    robot: Robot,
    setup: ArmSetup,
    limits: JointLimits,
    travel: float,
    margin: float = 0.1,
    samples: int = 41,
    first_order: bool = False,
    axis: str = "y",
) -> TaskBounds:
    """Pivot speed, acceleration and jerk along base y (``axis`` "z": base z) that keep every joint within
    (1 − margin)·limits.

    q(y) is solved by IK over |y| ≤ travel [m]; with q' = dq/dy, q'' and q''' (finite differences, max over
    the band) the joint rates are q̇ = q'·v, q̈ = q'·a + q''·v², q⃛ = q'·j + 3q''·v·a + q'''·v³, bounded
    joint by joint (worst cases combined: conservative). ``first_order`` keeps only the q' terms, an
    optimistic first guess for plans that are checked and rescaled afterwards.
    """
    y = np.linspace(-travel, travel, samples)
    mid = samples // 2

    def disp(d: np.ndarray) -> np.ndarray:
        return d if axis == "y" else np.column_stack([np.zeros_like(d), d])

    up, _ = joint_path(robot, setup, y[mid:], disp(y[mid:]), limits)
    down, _ = joint_path(robot, setup, y[mid::-1], disp(y[mid::-1]), limits)
    q = np.vstack([down.q[::-1], up.q[1:]])
    h = y[1] - y[0]
    d1, d2, d3 = derivatives(q, h, 3)
    w1, w2, w3 = (np.abs(d).max(axis=0) + 1e-9 for d in (d1, d2, d3))
    lim = limits.scaled(1.0 - margin)
    v = float(np.min(lim.velocity / w1))
    if first_order:
        return TaskBounds(v_max=v, a_max=float(np.min(lim.acceleration / w1)), j_max=float(np.min(lim.jerk / w1)))
    for _ in range(20):
        a = float(np.min((lim.acceleration - w2 * v**2) / w1))
        j = float(np.min((lim.jerk - 3 * w2 * v * a - w3 * v**3) / w1)) if a > 0 else -1.0
        if a > 0 and j > 0:
            return TaskBounds(v_max=v, a_max=a, j_max=j)
        v *= 0.8
    raise ValueError("no pivot motion along y fits the joint limits at this start pose")


@dataclass(frozen=True)
class Verification:
    """The nonlinear ball simulation driven by the joint path: θ_y (n,) [rad] of the anchor→ball direction, tension
    per mass (n,) [m/s²] (NaN where the string is slack)."""

    t: np.ndarray
    theta: np.ndarray
    tension: np.ndarray
    pivot: np.ndarray  # (n, 3) TCP positions [m]
    pivot_acc: np.ndarray  # (n, 3) realised accelerations [m/s²]
    run: object  # string_sim.BallRun

    @property
    def max_theta(self) -> float:
        return float(np.max(np.abs(self.theta)))

    @property
    def slack(self) -> np.ndarray:
        """(n,) bool: the string is slack at the sample."""
        return ~np.isfinite(self.tension)

    @property
    def first_slack(self) -> float | None:
        """First time the string went slack [s] (None: taut throughout)."""
        return self.run.first_slack

    @property
    def max_taut_theta(self) -> float:
        """Largest |θ| [rad] while the string is taut."""
        taut = np.isfinite(self.tension)
        return float(np.max(np.abs(self.theta[taut]))) if taut.any() else 0.0


def verify(
    robot: Robot,
    traj: JointTrajectory,
    length: float,
    theta0: float = 0.0,
    theta_dot0: float = 0.0,
    damping: float = 0.0,
    mass: float | None = None,
) -> Verification:
    """Simulate the ball (the string model, no cup; the default ball, of ``mass`` [kg] if given) under the TCP path
    the joint trajectory realises."""
    from .string_model import Ball, StringModel
    from .string_sim import PivotMotion, simulate_string

    pos, _ = robot.fk_path(traj.q)
    s0 = direction_from_angles(0.0, theta0)
    sdot0 = np.array([0.0, math.cos(theta0), math.sin(theta0)]) * theta_dot0
    ball = Ball() if mass is None else Ball(mass=mass)
    run = simulate_string(
        StringModel(length, ball=ball, cup=None, damping=damping),
        PivotMotion(traj.t, pos),
        float(traj.t[-1]),
        traj.t,
        s0,
        sdot0,
        rtol=1e-9,
        atol=1e-10,
    )
    return Verification(
        t=traj.t,
        theta=run.theta_y,
        tension=run.tension,
        pivot=pos,
        pivot_acc=SampledAcceleration(traj.t, pos).samples(),
        run=run,
    )
