"""Active sway damping: the measured swing of a ball (or the pendulum module) corrects the pivot's path.

The pivot follows a planned path (a joint CSV through forward kinematics) plus a small horizontal offset Δp per base
axis, x and y, each a jerk-driven :class:`Cart`. The plan itself makes the ball swing (a shaped move swings and
stops it again); what the damper fights is the swing the plan did not intend. The intended one, θ_ref, is the
model's answer to the planned pivot acceleration alone (:func:`sway_reference`, with the assumed string length);
the actual one, θ̂, comes from the delay-compensating :class:`DelayedObserver` driven by the planned acceleration plus
the correction. With the linear model θ̈ = −(g·θ + a)/l the deviation e = θ − θ_ref obeys ë = −(g·e + Δa)/l: the
cart–pendulum system of :mod:`.lqr` about hanging, state (Δp, Δv, Δa, e, ė), input the jerk of Δp. Its LQR gain
brings the deviation and the offset back to zero; after the plan ends θ_ref is (nearly) zero and the damper
removes whatever sway a wrong string length left.

Sign convention (as the simulator's ball IO): θ_x = atan2(s_x, −s_z), θ_y = atan2(s_y, −s_z) for the string
direction s; a pivot acceleration +a along the axis swings the ball to −θ.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from ..pendulum import G
from ..rail import CartLimits
from .cart import Cart
from .lqr import lqr_gain
from .observer import DelayedObserver


@dataclass(frozen=True)
class DampingOptions:
    """Weights of the LQR cost ∫ zᵀ·diag(weights)·z + jerk_weight·j² dt for z = (Δp [m], Δv [m/s], Δa [m/s²],
    e [rad], ė [rad/s]); the observer's bandwidth; the correction's own bounds (a client narrows them per row to
    the joints' headroom)."""

    weights: tuple[float, float, float, float, float] = (400.0, 10.0, 0.1, 400.0, 4.0)
    jerk_weight: float = 1e-3
    bandwidth: float = 20.0  # [rad/s] of the observer's correction
    travel: float = 0.08  # [m] largest offset from the planned path per axis
    velocity: float = 0.3  # [m/s]
    acceleration: float = 2.5  # [m/s²]
    jerk: float = 60.0  # [m/s³]

    def limits(self) -> CartLimits:
        return CartLimits(self.travel, self.velocity, self.acceleration, self.jerk)

    def validate(self) -> None:
        vals = (
            *self.weights,
            self.jerk_weight,
            self.bandwidth,
            self.travel,
            self.velocity,
            self.acceleration,
            self.jerk,
        )
        if not all(math.isfinite(v) for v in vals) or min(self.weights) < 0 or min(vals[5:]) <= 0:
            raise ValueError("damping options: weights >= 0, the jerk weight, bandwidth and bounds > 0")


def damping_gain(length: float, options: DampingOptions = DampingOptions()) -> np.ndarray:
    """LQR gain K (5,) for the deviation of a pendulum of ``length`` [m] (hanging); jerk = −K·z."""
    return lqr_gain(length, False, options.weights, options.jerk_weight)


def sway_reference(accel: np.ndarray, length: float, dt: float, actuation_delay: int = 1,
                   fade_s: float | None = None) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """θ_ref, θ̇_ref (n, m) [rad], [rad/s]: the planar swing the pivot accelerations ``accel`` (n, m) [m/s²], one row
    per cycle of ``dt`` [s], cause on a pendulum of ``length`` [m] starting at rest — the observer's own model and
    discretisation, so that the planned motion alone leaves the deviation exactly zero. After the last row with a
    non-zero acceleration the reference fades to zero over ``fade_s`` [s] (default half a period): the plan's own
    residual sway is not kept alive."""
    accel = np.asarray(accel, dtype=float)
    n, m = accel.shape
    theta, rate = np.zeros((n, m)), np.zeros((n, m))
    for i in range(m):
        obs = DelayedObserver(length, dt, 0.0, dt, actuation_delay=actuation_delay)
        col = accel[:, i].tolist()
        for k in range(n):
            theta[k, i], rate[k, i] = obs.phi, obs.omega
            obs.predict(col[k])
    moving = np.flatnonzero(np.any(np.abs(accel) > 1e-9, axis=1))
    if len(moving):
        fade = fade_s if fade_s is not None else math.pi * math.sqrt(length / G)
        k0 = int(moving[-1]) + actuation_delay + 1
        k = np.arange(n) - k0
        w = np.where(k <= 0, 1.0, 0.5 * (1.0 + np.cos(np.pi * np.clip(k * dt / max(fade, dt), 0.0, 1.0))))
        theta *= w[:, None]
        rate *= w[:, None]
    return theta, rate


class SwayDamper:
    """The correction Δp of ``axes`` pivot axes, stepped every ``dt`` [s] from delayed angle readings.

    ``delay`` [s]: from the moment a reading shows to when it is handed to :meth:`correct` (or each reading's own
    age, up to ``max_delay`` [s]); ``reading_interval`` [s]: between readings; ``bounds``: optional (x, v, a) →
    (speed, a_lo, a_hi, j_lo, j_hi) for every axis (the joints' headroom), else the options' constant bounds.
    """

    def __init__(self, length: float, dt: float, delay: float, reading_interval: float,
                 options: DampingOptions = DampingOptions(), gain: np.ndarray | None = None, axes: int = 2,
                 actuation_delay: int = 1, bounds: Callable | None = None, max_delay: float | None = None) -> None:  # fmt: skip
        options.validate()
        self.length, self.dt, self.options = length, dt, options
        k = damping_gain(length, options) if gain is None else np.asarray(gain, dtype=float)
        self.gain = tuple(float(v) for v in k)
        lim = options.limits()
        self.carts = [Cart(lim, dt, bounds=bounds) for _ in range(axes)]
        self.observers = [DelayedObserver(length, dt, delay, reading_interval, options.bandwidth,
                                          actuation_delay=actuation_delay, max_delay=max_delay)
                          for _ in range(axes)]  # fmt: skip
        self.deviation = [0.0] * axes  # e [rad] at the last step
        self.active = True  # False: no feedback; the offsets return smoothly to the planned path

    def correct(self, axis: int, reading: float, age: float | None = None) -> None:
        """A reading of the angle of ``axis`` [rad] arrived this cycle, ``age`` [s] old (default: ``delay``)."""
        self.observers[axis].correct(reading, age)

    def step(self, ref_angle: Sequence[float], ref_rate: Sequence[float], planned_accel: Sequence[float]) -> None:
        """One cycle: the feedback jerk per axis from the estimate against the reference (θ_ref [rad], θ̇_ref
        [rad/s]), the carts stepped, the observers predicted with the planned acceleration [m/s²] plus the cart's."""
        k0, k1, k2, k3, k4 = self.gain
        dev = self.deviation
        for i, (cart, obs) in enumerate(zip(self.carts, self.observers)):
            e = obs.phi - ref_angle[i]
            de = obs.omega - ref_rate[i]
            dev[i] = e
            if self.active:
                cart.step(-(k0 * cart.x + k1 * cart.v + k2 * cart.a + k3 * e + k4 * de))
            else:  # no feedback: the offset returns to the planned path, critically damped (ω = 2 rad/s)
                cart.track(-4.0 * cart.x - 4.0 * cart.v, 0.05)
            obs.predict(planned_accel[i] + cart.a)

    def coast(self, planned_accel: Sequence[float]) -> None:
        """One cycle without feedback: the offsets move on at constant velocity (no acceleration of their own), the
        observers are predicted with the pivot acceleration ``planned_accel`` [m/s²]."""
        for i, (cart, obs) in enumerate(zip(self.carts, self.observers)):
            cart.a = 0.0
            cart.x += cart.v * self.dt
            obs.predict(planned_accel[i])

    @property
    def offset(self) -> tuple[float, ...]:
        """Δp per axis [m]."""
        return tuple(c.x for c in self.carts)

    @property
    def velocity(self) -> tuple[float, ...]:
        """Δv per axis [m/s]."""
        return tuple(c.v for c in self.carts)


@dataclass(frozen=True)
class DampingRun:
    """A simulated run: t (n,) [s]; true θ_x, θ_y (n, 2) [rad]; the string tilt θ (n,) [rad]; offsets Δp (n, 2)
    [m] and their acceleration (n, 2) [m/s²]."""

    t: np.ndarray
    theta_xy: np.ndarray
    theta: np.ndarray
    offset: np.ndarray
    accel: np.ndarray


def pivot_acceleration(path: np.ndarray, dt: float) -> np.ndarray:
    """Second differences of a sampled path (n, m) [m] → (n, m) [m/s²] (zero at both ends)."""
    path = np.asarray(path, dtype=float)
    acc = np.zeros_like(path)
    acc[1:-1] = (path[2:] - 2 * path[1:-1] + path[:-2]) / (dt * dt)
    return acc


def simulate_damping(path: np.ndarray, dt: float, true_length: float, model_length: float, *,
                     after_s: float = 4.0, sensor_delay: float = 0.006, damping: bool = True,
                     options: DampingOptions = DampingOptions(), actuation_delay: int = 1,
                     bounds: np.ndarray | None = None) -> DampingRun:  # fmt: skip
    """The ball on a string of ``true_length`` [m] under the planned pivot ``path`` (n, 3) [m] sampled every ``dt``
    [s] (then held for ``after_s``), the damper (assuming ``model_length``) reading θ_x, θ_y ``sensor_delay`` [s]
    late, every cycle. Without ``damping`` the plan runs open loop. ``bounds`` (n, 5): the offset's bounds per row
    (:class:`~.correction.CorrectionPlan`; the last row's hold after the end). No FRI: for tests and tuning."""
    from ..pendulum import rk4_step_floats

    path = np.asarray(path, dtype=float)
    extra = int(round(after_s / dt))
    path = np.vstack([path, np.repeat(path[-1:], extra, axis=0)])
    n = len(path)
    acc_plan = pivot_acceleration(path, dt)
    ref, ref_rate = sway_reference(acc_plan[:, :2], model_length, dt, actuation_delay)
    rows = [tuple(float(v) for v in b) for b in bounds] if bounds is not None else None
    at = [0]
    damper = SwayDamper(
        model_length,
        dt,
        sensor_delay,
        dt,
        options,
        actuation_delay=actuation_delay,
        bounds=(lambda x, v, a: rows[min(at[0], len(rows) - 1)]) if rows else None,
    )
    lag = max(0, int(round(sensor_delay / dt)))
    s, sdot = (0.0, 0.0, -1.0), (0.0, 0.0, 0.0)
    offsets = np.zeros((n, 2))
    pivot_hist = [path[0].tolist()] * 3  # the pivot's last three positions (actuation lag applied)
    cmd_hist = [path[0].tolist()] * (actuation_delay + 1)
    seen: list[tuple[float, float]] = []
    theta_xy = np.zeros((n, 2))
    theta = np.zeros(n)
    acc_prev = (0.0, 0.0, 0.0)
    for k in range(n):
        at[0] = k
        # the plant: the pivot reaches the command of actuation_delay cycles ago
        p = cmd_hist[k % len(cmd_hist)]
        pivot_hist = [pivot_hist[1], pivot_hist[2], p]
        a = tuple((pivot_hist[2][i] - 2 * pivot_hist[1][i] + pivot_hist[0][i]) / (dt * dt) for i in range(3))
        s, sdot = rk4_step_floats(s, sdot, acc_prev, a, dt, true_length)
        acc_prev = a
        tx, ty = math.atan2(s[0], -s[2]), math.atan2(s[1], -s[2])
        theta_xy[k] = tx, ty
        theta[k] = math.acos(max(-1.0, min(1.0, -s[2])))
        seen.append((tx, ty))
        if damping and len(seen) > lag:
            r = seen[-1 - lag]
            damper.correct(0, r[0])
            damper.correct(1, r[1])
        if damping:
            damper.step(ref[k], ref_rate[k], acc_plan[k, :2])
        offsets[k] = damper.offset
        nxt = path[k].copy()
        nxt[:2] += offsets[k]
        cmd_hist[k % len(cmd_hist)] = nxt.tolist()
    acc_off = pivot_acceleration(offsets, dt)
    return DampingRun(np.arange(n) * dt, theta_xy, theta, offsets, acc_off)
