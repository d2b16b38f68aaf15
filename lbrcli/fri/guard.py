"""Per-cycle command guard: every command that leaves the client is one the robot can follow.

Joint position: 7 finite values inside the position limits — with room to stop before them (a jerk-limited stop from
the command's velocity: v²/2a + v·a/2j) — the step from the previous command within the velocity limit and the
second difference within the acceleration limit (both × period, as the controller executes them).
Torque (TORQUE mode): 7 finite values within the torque table. Wrench (WRENCH mode): 6 finite values within the
configured force [N] and torque [Nm] bounds. Limits are compared with a stated relative tolerance (REL_TOL), so a
command exactly at a limit passes. Pure Python over 7 floats: cheaper per cycle than numpy on tiny arrays.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

from trajectories.limits import JointLimits

REL_TOL = 1e-9  # relative slack on every limit (floating-point rounding of a command exactly at a limit)
DEFAULT_MAX_FORCE = 20.0  # [N] per axis, WRENCH mode
DEFAULT_MAX_MOMENT = 2.0  # [Nm] per axis, WRENCH mode


@dataclass(frozen=True)
class CommandGuard:
    """Bounds for one command period ``period_s`` [s] (send period × receive multiplier)."""

    upper: tuple[float, ...]  # [rad] |q| ≤ upper
    max_step: tuple[float, ...]  # [rad] velocity limit × period
    max_second: tuple[float, ...]  # [rad] acceleration limit × period²
    stop_k: tuple[tuple[float, float], ...]  # per joint (acceleration limit, jerk limit): for stopping distances
    free: tuple[float, ...]  # [rad] |q| ≤ free: any stop within the velocity/acceleration limits ends inside
    max_torque: tuple[float, ...]  # [Nm]
    max_force: float  # [N] per axis
    max_moment: float  # [Nm] per axis
    period_s: float

    @classmethod
    def from_limits(
        cls,
        limits: JointLimits,
        period_s: float,
        max_force: float = DEFAULT_MAX_FORCE,
        max_moment: float = DEFAULT_MAX_MOMENT,
    ) -> "CommandGuard":
        k = 1.0 + REL_TOL
        upper = tuple(float(p) * k for p in limits.position)
        stop_k = tuple((float(a), float(j)) for a, j in zip(limits.acceleration, limits.jerk))
        # the longest stop a command inside the step and second-difference bounds can need (stopping_distance grows
        # with |v| and with a in the direction of motion), with 1 % to spare: closer to a limit, computed per command
        worst = tuple(1.01 * stopping_distance(float(v) * k, float(a) * k, float(a), float(j))
                      for v, a, j in zip(limits.velocity, limits.acceleration, limits.jerk))  # fmt: skip
        return cls(
            upper=upper,
            max_step=tuple(float(v) * period_s * k for v in limits.velocity),
            max_second=tuple(float(a) * period_s * period_s * k for a in limits.acceleration),
            stop_k=stop_k,
            free=tuple(u - w for u, w in zip(upper, worst)),
            max_torque=tuple(float(t) * k for t in limits.torque),
            max_force=max_force,
            max_moment=max_moment,
            period_s=period_s,
        )

    def refuse_position(
        self, q: Sequence[float], prev: Sequence[float], prev2: Sequence[float], room_to_stop: bool = True
    ) -> str | None:
        """None if ``q`` [rad] may follow the commands ``prev`` and ``prev2`` (one and two periods before);
        ``room_to_stop``: also a jerk-limited stop from there must end inside the position limits."""
        if q is None or len(q) != 7:
            return f"the joint position command has {0 if q is None else len(q)} values, not 7"
        # most commands are far from every limit: one chained comparison per joint, the full check only near one
        j = 0
        for x, p1, p2, free, max_step, max_second in zip(q, prev, prev2, self.free, self.max_step, self.max_second):
            step = x - p1
            second = step - (p1 - p2)
            if not (-free <= x <= free and -max_step <= step <= max_step and -max_second <= second <= max_second):
                problem = self._joint_problem(j, x, step, second, room_to_stop)  # also NaN
                if problem is not None:
                    return problem
            j += 1
        return None

    def _joint_problem(self, j: int, x: float, step: float, second: float, room_to_stop: bool) -> str | None:
        """The full check of joint ``j`` (index) at ``x`` [rad] after ``step`` [rad] and ``second`` difference [rad]."""
        dt = self.period_s
        if not (-self.upper[j] <= x <= self.upper[j]):  # also NaN
            return f"A{j + 1} command {x:.6f} rad outside the position limit ±{self.upper[j]:.6f} rad"
        if not (-self.max_step[j] <= step <= self.max_step[j]):
            return (f"A{j + 1} step {step:+.6f} rad in {dt * 1e3:g} ms = {step / dt:+.4f} rad/s exceeds the "
                    f"velocity limit {self.max_step[j] / dt:.4f} rad/s")  # fmt: skip
        if not (-self.max_second[j] <= second <= self.max_second[j]):
            return (f"A{j + 1} second difference {second:+.3e} rad = {second / (dt * dt):+.2f} rad/s² exceeds the "
                    f"acceleration limit {self.max_second[j] / (dt * dt):.2f} rad/s²")  # fmt: skip
        if room_to_stop and step != 0.0:
            a_max, j_max = self.stop_k[j]
            stop = x + stopping_distance(step / dt, second / (dt * dt), a_max, j_max)
            if not (-self.upper[j] <= stop <= self.upper[j]):
                return (f"A{j + 1} at {x:.6f} rad moving {step / dt:+.4f} rad/s cannot stop before the position limit "
                        f"±{self.upper[j]:.6f} rad (it needs to {stop:.6f} rad)")  # fmt: skip
        return None

    def refuse_torque(self, tau: Sequence[float] | None) -> str | None:
        if tau is None or len(tau) != 7:
            return f"the torque command has {0 if tau is None else len(tau)} values, not 7"
        for j in range(7):
            x = tau[j]
            if not (-self.max_torque[j] <= x <= self.max_torque[j]):
                return f"A{j + 1} torque command {x:.4f} Nm outside the torque limit ±{self.max_torque[j]:.1f} Nm"
        return None

    def refuse_wrench(self, w: Sequence[float] | None) -> str | None:
        if w is None or len(w) != 6:
            return f"the wrench command has {0 if w is None else len(w)} values, not 6"
        for i in range(6):
            bound = self.max_force if i < 3 else self.max_moment
            x = w[i]
            if not (-bound <= x <= bound) or math.isnan(x):
                unit = "N" if i < 3 else "Nm"
                return f"wrench component {'xyzxyz'[i]}{'' if i < 3 else ' moment'} {x:.4f} {unit} outside ±{bound:g} {unit}"
        return None


def stopping_distance(v: float, a: float, a_max: float, j_max: float) -> float:
    """Signed distance [rad] a jerk-limited stop travels from velocity ``v`` [rad/s] and acceleration ``a``
    [rad/s²] (an upper bound, exact for fast stops): first the acceleration to 0 (or from 0, if it already brakes),
    then a stop at ``a_max`` with jerk ``j_max``."""
    sign = 1.0 if v > 0.0 else -1.0
    v, a = abs(v), a * sign  # a > 0: still speeding up in the direction of motion
    t = abs(a) / j_max
    if a > 0.0:  # ramp the acceleration down first: it keeps going
        d1 = v * t + 0.5 * a * t * t - j_max * t * t * t / 6.0
        v1 = v + 0.5 * a * t
        return sign * (d1 + v1 * v1 / (2.0 * a_max) + v1 * a_max / (2.0 * j_max))
    # braking already: as a stop that started from a = 0 at the higher velocity, minus the part already done
    v0 = v + 0.5 * a * a / j_max
    done = v0 * t - j_max * t * t * t / 6.0
    return sign * max(0.0, v0 * v0 / (2.0 * a_max) + v0 * a_max / (2.0 * j_max) - done)
