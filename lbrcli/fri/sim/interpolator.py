"""The simulated controller's joint interpolator: follows commanded positions within velocity/acceleration limits.

Each cycle of length dt [s] the interpolator takes a target joint position. If reaching it in one step keeps
every joint within its velocity [rad/s] and acceleration [rad/s²] limits, the robot lands exactly on it
(tracking performance 1). Otherwise the step is clipped per joint — a braking bound on the speed relative to
the target's own velocity (the discrete √(2·a_max·|e|)) so that the target is caught up with without overshoot,
the velocity limit, and the acceleration window around the current velocity — and the tracking performance is
the achieved fraction of the requested step of the worst joint (0..1; an overshoot by x % counts as 1 − x %). A
joint that was catching up lands on the target only once it can also keep to the target's velocity. All arrays are
preallocated; ``step`` allocates only numpy temporaries of 7 elements.
"""

from __future__ import annotations

import numpy as np


class Interpolator:
    """Joint state q [rad], v [rad/s], a [rad/s²] driven towards per-cycle targets at a fixed step dt [s]."""

    def __init__(self, q0: np.ndarray, max_velocity: np.ndarray, max_acceleration: np.ndarray, dt: float) -> None:
        self.q = np.array(q0, dtype=float)
        self.v = np.zeros_like(self.q)
        self.a = np.zeros_like(self.q)
        self.vmax = np.asarray(max_velocity, dtype=float)  # [rad/s]
        self.amax = np.asarray(max_acceleration, dtype=float)  # [rad/s^2]
        self.dt = float(dt)  # [s]
        self._dv = self.amax * self.dt  # [rad/s] largest velocity change per step
        self._tol = 1e-9  # relative slack on the limits for "exactly reachable"
        self._prev_target = self.q.copy()  # last cycle's target [rad]
        self._catching = np.zeros(self.q.shape, dtype=bool)  # joints clipped in the last cycle

    def hold(self) -> None:
        """Stand still at the current position (v = a = 0), e.g. after the robot stopped."""
        self.v[:] = 0.0
        self.a[:] = 0.0
        self._prev_target[:] = self.q
        self._catching[:] = False

    def _brake(self, err: np.ndarray) -> np.ndarray:
        """Fastest speed relative to the target [rad/s] from which whole-step braking at a_max stops within
        |err| [rad]: n·a·dt with a·dt²·n(n+1)/2 = |err| (the discrete √(2·a·|err|))."""
        adt = self._dv
        return adt * (np.sqrt(0.25 + 2.0 * np.abs(err) / (adt * self.dt)) - 0.5)

    def step(self, target: np.ndarray) -> float:
        """Advance one cycle towards ``target`` [rad]; returns the tracking performance of this step (0..1)."""
        dt = self.dt
        err = target - self.q
        v_req = err / dt
        a_req = (v_req - self.v) / dt
        lim = 1.0 + self._tol
        exact = (np.abs(v_req) <= self.vmax * lim) & (np.abs(a_req) <= self.amax * lim)
        v_t = brake = None
        if self._catching.any():
            # a joint catching up lands on the target only if it can then keep to the target's velocity
            v_t = np.clip((target - self._prev_target) / dt, -self.vmax, self.vmax)
            brake = self._brake(err - v_t * dt)  # distance to go in the frame moving with the target
            exact &= ~self._catching | (np.abs(v_req - v_t) <= brake * lim + 1e-12)
        if exact.all():
            self.a[:] = a_req
            self.v[:] = v_req
            self.q[:] = target
            self._prev_target[:] = target
            self._catching[:] = False
            return 1.0
        # joints that cannot land on the target: relative to the target's velocity no faster than the braking
        # bound, then the velocity limit, then the acceleration window
        if v_t is None:
            v_t = np.clip((target - self._prev_target) / dt, -self.vmax, self.vmax)
            brake = self._brake(err - v_t * dt)
        self._prev_target[:] = target
        v_new = v_t + np.clip(v_req - v_t, -brake, brake)
        np.clip(v_new, -self.vmax, self.vmax, out=v_new)
        np.clip(v_new, self.v - self._dv, self.v + self._dv, out=v_new)
        v_new[exact] = v_req[exact]
        step = v_new * dt
        clipped = ~exact
        e_c = err[clipped]
        # achieved fraction of the requested step (0 where a joint was asked to stop dead and could not); a joint that
        # could not brake hard enough overshoots (fraction > 1) and counts as far off: 1 − |1 − fraction|
        frac = np.divide(step[clipped], e_c, out=np.zeros_like(e_c), where=np.abs(e_c) > 1e-15)
        frac = 1.0 - np.abs(1.0 - frac)
        self.a[:] = (v_new - self.v) / dt
        self.v[:] = v_new
        self.q += step
        self.q[exact] = target[exact]
        self._catching[:] = clipped
        return float(np.clip(frac.min(), 0.0, 1.0))
