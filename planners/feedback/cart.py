"""The cart a feedback controller drives: position x [m], velocity v [m/s], acceleration a [m/s²], moved each cycle
by a jerk [m/s³] that keeps it inside its bounds.

Bounds come from ``bounds(x, v, a)`` — the rail's exact ones at the cart's state (speed, acceleration interval,
jerk interval; :meth:`planners.rail.Rail.local_bounds`) — or, without it, the constant :class:`CartLimits`. The
governor keeps the jerk and the acceleration in their intervals and brakes early enough that the velocity reached
when the acceleration has been ramped back to zero at the jerk bound stays within the speed bound, and within the
speed from which the cart can still stop before the end of the rail (|x| ≤ travel) at half the acceleration bound.
A request that would break a bound is trimmed (``trimmed`` counts those cycles). A state already outside the bounds
(set from outside, or coasted onto another part of the rail) goes back into the acceleration interval at the constant
jerk bound: the rail's jerk interval there can lie wholly on the far side (its curvature terms grow with v·a).
"""

from __future__ import annotations

import math
from typing import Callable

from ..rail import CartLimits

Bounds = Callable[[float, float, float], "tuple[float, float, float, float, float]"]


def _ramp_cap(dv: float, jerk: float, dt: float) -> float:
    """Acceleration a [m/s²] from which ramping to zero at ``jerk`` in steps of ``dt`` [s] changes the velocity by
    exactly dv [m/s] (signed): a²/(2·jerk) + a·dt/2 = |dv|."""
    h = 0.5 * jerk * dt
    a = math.sqrt(h * h + 2.0 * jerk * abs(dv)) - h
    return a if dv >= 0.0 else -a


def _stop_speed(room: float, brake: float, jerk: float) -> float:
    """Speed [m/s] from which the cart stops within ``room`` [m]: ramping to the deceleration ``brake`` [m/s²] at
    ``jerk`` [m/s³] (counted twice: the ramp in and a margin) and braking, v·t_r + v²/(2·brake) ≤ room."""
    if room <= 0.0:
        return 0.0
    t_r = 2.0 * brake / jerk
    return brake * (math.sqrt(t_r * t_r + 2.0 * room / brake) - t_r)


class Cart:
    """Jerk-driven cart, stepped every ``dt`` [s]."""

    def __init__(self, limits: CartLimits, dt: float, x: float = 0.0, bounds: Bounds | None = None) -> None:
        if not (dt > 0 and math.isfinite(dt)):
            raise ValueError(f"cart step must be > 0 s, got {dt!r}")
        self.limits = limits
        self.dt = dt
        self.bounds = bounds
        self.x, self.v, self.a = x, 0.0, 0.0  # [m], [m/s], [m/s²]
        self.trimmed = 0  # cycles whose request was trimmed by a bound
        self._last: tuple[float, float, float, float, float] | None = None  # the bounds of the last step

    def _bounds(self) -> tuple[float, float, float, float, float]:
        if self.bounds is not None:
            return self.bounds(self.x, self.v, self.a)
        lim = self.limits
        return lim.velocity, -lim.acceleration, lim.acceleration, -lim.jerk, lim.jerk

    @property
    def acceleration_bound(self) -> float:
        """The smaller magnitude of the acceleration interval [m/s²] (as of the last step)."""
        _, lo, hi, _, _ = self._last if self._last is not None else self._bounds()
        return max(0.0, min(-lo, hi))

    def step(self, jerk: float) -> None:
        """Advance one step with the requested jerk [m/s³] (trimmed to the bounds)."""
        dt, travel = self.dt, self.limits.travel
        self._last = b = self._bounds()
        speed, a_lo, a_hi, j_lo, j_hi = b
        ramp = max(min(-j_lo, j_hi), 1e-3)
        brake = 0.5 * max(min(-a_lo, a_hi), 1e-3)
        v_hi = min(speed, _stop_speed(travel - self.x, brake, ramp))
        v_lo = -min(speed, _stop_speed(travel + self.x, brake, ramp))
        a_hi = min(a_hi, _ramp_cap(v_hi - self.v, ramp, dt))
        a_lo = max(a_lo, -_ramp_cap(self.v - v_lo, ramp, dt))
        j = jerk
        top = min(j_hi, (a_hi - self.a) / dt)
        bottom = max(j_lo, (a_lo - self.a) / dt)
        if j > top:
            j = max(top, j_lo)
        if j < bottom:
            j = min(bottom, j_hi)
        if (self.a > a_hi and j > 0.0) or (self.a < a_lo and j < 0.0) or j_lo > j_hi:
            j = self._recover(jerk, a_lo, a_hi)
        if j != jerk:
            self.trimmed += 1
        a0 = self.a
        self.a = a0 + j * dt
        self.x += self.v * dt + (0.5 * a0 + j * dt / 6.0) * dt * dt
        self.v += 0.5 * (a0 + self.a) * dt

    def _recover(self, jerk: float, a_lo: float, a_hi: float) -> float:
        """The jerk [m/s³] from a state outside the bounds (set from outside the governor, e.g. coasted through lost
        messages onto another part of the rail): the rail's jerk interval there can push the acceleration further out
        (its curvature terms grow with v·a: a runaway), so the acceleration goes back into its interval at the
        constant jerk bound instead."""
        lim, a, dt = self.limits.jerk, self.a, self.dt
        if a > a_hi:
            return max(-lim, (a_hi - a) / dt) if a_lo <= a_hi else -lim
        if a < a_lo:
            return min(lim, (a_lo - a) / dt) if a_lo <= a_hi else lim
        return min(max(jerk, -lim, (a_lo - a) / dt), lim, (a_hi - a) / dt)

    def track(self, accel: float, time_constant: float) -> None:
        """Step toward the acceleration ``accel`` [m/s²] with a first-order lag ``time_constant`` [s]."""
        self.step((accel - self.a) / max(time_constant, self.dt))
