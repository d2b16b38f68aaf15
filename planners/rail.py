"""The arm as a cart on a rail: the TCP moves along base y through the start pose, the joints are a smooth function
q(x) of the cart position x [m] (IK of the whole rail, once), and the cart's speed, acceleration and jerk bounds
keep every joint within its limits: constant ones valid anywhere on the rail at any speed (``limits``, conservative)
and the exact ones at the cart's state (:meth:`Rail.local_bounds`), which the :class:`~.feedback.cart.Cart` uses.

Feedback controllers command a cart acceleration; :meth:`Rail.joints` turns the cart position into the joint
command in a few microseconds (a cubic spline through IK solutions every ``step`` metres, evaluated by hand).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from trajectories.limits import JointLimits
from trajectories.robot import Robot

from .swingup_robot import ArmSetup, axis_bounds, joint_path


@dataclass(frozen=True)
class CartLimits:
    """Bounds of the cart: |x| ≤ travel [m], |ẋ| ≤ velocity [m/s], |ẍ| ≤ acceleration [m/s²], |x⃛| ≤ jerk [m/s³]."""

    travel: float
    velocity: float
    acceleration: float
    jerk: float


@dataclass(frozen=True)
class Rail:
    """q(x) along base y through ``q_start`` [rad]: knots ``x`` (n,) [m], spline ``coeffs`` (4, n − 1, 7)."""

    q_start: tuple[float, ...]
    x: np.ndarray
    coeffs: np.ndarray
    limits: CartLimits
    orientation: str
    joint_velocity: np.ndarray  # (7,) the joints' bounds the cart keeps [rad/s], …
    joint_acceleration: np.ndarray  # [rad/s²]
    joint_jerk: np.ndarray  # [rad/s³]

    def joints(self, x: float) -> np.ndarray:
        """Joint positions (7,) [rad] with the cart at x [m] (clamped to the rail)."""
        return np.array(self.joints_list(x))

    def _segment(self, x: float) -> tuple[tuple[list[float], ...], float]:
        """The spline segment's coefficients at x [m] (clamped to the rail) and the offset into it [m]."""
        k = self.x
        x0, h = float(k[0]), float(k[1] - k[0])
        x = min(max(x, x0), float(k[-1]))
        i = min(int((x - x0) / h), len(k) - 2)
        return self._segments[i], x - (x0 + i * h)

    def joints_list(self, x: float) -> list[float]:
        """:meth:`joints` as a list of floats, for the FRI command (allocation of one list)."""
        (c0, c1, c2, c3), s = self._segment(x)
        return [((c0[j] * s + c1[j]) * s + c2[j]) * s + c3[j] for j in range(len(c0))]

    def __post_init__(self) -> None:
        # per-segment spline coefficients and joint bounds as Python lists: local_bounds runs every FRI cycle, and
        # on 7 numbers plain floats are several times faster than numpy calls
        c = self.coeffs
        object.__setattr__(
            self,
            "_segments",
            [(c[0, i].tolist(), c[1, i].tolist(), c[2, i].tolist(), c[3, i].tolist()) for i in range(c.shape[1])],
        )
        object.__setattr__(
            self,
            "_joint_bounds",
            list(zip(self.joint_velocity.tolist(), self.joint_acceleration.tolist(), self.joint_jerk.tolist())),
        )

    def local_bounds(self, x: float, v: float, a: float) -> tuple[float, float, float, float, float]:
        """Cart bounds at position x [m], velocity v [m/s], acceleration a [m/s²] from the joints' own:
        (speed [m/s], lowest and highest acceleration [m/s²], lowest and highest jerk [m/s³]) such that
        dq/dt = q1·v, its rate q1·a + q2·v² and jerk q1·j + 3·q2·v·a + q3·v³ stay within them (qk the k-th
        derivative of q(x))."""
        (c0, c1, c2, _), s = self._segment(x)
        speed, a_lo, a_hi, j_lo, j_hi = math.inf, -math.inf, math.inf, -math.inf, math.inf
        vv = v * v
        for j, (vm, am, jm) in enumerate(self._joint_bounds):
            d1 = (3.0 * c0[j] * s + 2.0 * c1[j]) * s + c2[j]
            if abs(d1) < 1e-9:
                continue  # this joint does not move with the cart here
            d2 = 6.0 * c0[j] * s + 2.0 * c1[j]
            d3 = 6.0 * c0[j]
            inv = 1.0 / d1
            speed = min(speed, vm * abs(inv))
            if abs(d2) > 1e-9:  # at full speed the curvature of q(x) may use at most half the acceleration bound
                speed = min(speed, math.sqrt(0.5 * am / abs(d2)))
            p, q = (-am - d2 * vv) * inv, (am - d2 * vv) * inv
            if p > q:
                p, q = q, p
            a_lo, a_hi = max(a_lo, p), min(a_hi, q)
            rest = (3.0 * d2 * a + d3 * vv) * v
            p, q = (-jm - rest) * inv, (jm - rest) * inv
            if p > q:
                p, q = q, p
            j_lo, j_hi = max(j_lo, p), min(j_hi, q)
        return speed, a_lo, a_hi, j_lo, j_hi

    def tcp_y(self, robot: Robot, x: float) -> float:
        """The TCP's base-y coordinate [m] with the cart at x (a check of the spline)."""
        return float(robot.fk(self.joints(x)).translation[1])


_OVERRUN = 0.1  # of the travel


def build_rail(robot: Robot, q_start, limits: JointLimits, travel: float = 0.3, orientation: str = "follow",
               margin: float = 0.1, step: float = 0.005) -> Rail:  # fmt: skip
    """IK of the rail |x| ≤ ``travel`` [m] along base y from the TCP at ``q_start`` (``orientation``: "fixed" keeps
    the TCP's orientation, "follow" turns it about the vertical as A1 would) and the cart bounds that keep every
    joint within (1 − ``margin``) of its limits. ValueError (IkError) if the rail is not reachable."""
    from scipy.interpolate import CubicSpline

    if not (math.isfinite(travel) and 0.01 <= travel <= 1.0):
        raise ValueError(f"rail travel must be 0.01..1 m, got {travel:g}")
    setup = ArmSetup(tuple(float(v) for v in q_start), orientation)
    # the spline runs on past ±travel by an overrun where the arm reaches it: a cart that coasted past the end (the
    # controller extrapolated through lost messages) then brakes on the rail instead of against a clamped end
    for reach in (1.0 + _OVERRUN, 1.0):
        n = int(math.ceil(reach * travel / step))
        half = np.linspace(0.0, n * step, n + 1)
        up, e_up = joint_path(robot, setup, half, half, limits)
        down, e_down = joint_path(robot, setup, half, -half, limits)
        if max(e_up, e_down) <= 1e-6:
            break
    x = np.concatenate([-half[::-1], half[1:]])
    q = np.vstack([down.q[::-1], up.q[1:]])
    spline = CubicSpline(x, q, axis=0, bc_type="natural")
    b = axis_bounds(robot, setup, limits, travel, margin=margin)
    lim = limits.scaled(1.0 - margin)
    return Rail(
        setup.q_start,
        x,
        np.ascontiguousarray(spline.c),
        CartLimits(travel, b.v_max, b.a_max, b.j_max),
        orientation,
        lim.velocity,
        lim.acceleration,
        lim.jerk,
    )
