"""The simulated controller's joint interpolator: follows commanded positions within velocity/acceleration limits.

Each cycle of length dt [s] the interpolator takes a target joint position. If reaching it in one step keeps
every joint within its velocity [rad/s] and acceleration [rad/s²] limits, the robot lands exactly on it
(tracking performance 1). Otherwise the step is clipped per joint — acceleration window around the current
velocity, a braking bound (the discrete √(2·a_max·|e|)) so that a distant target is approached without overshoot, and the
velocity limit — and the tracking performance is the achieved fraction of the requested step of the worst
joint (0..1). All arrays are preallocated; ``step`` allocates only numpy temporaries of 7 elements.
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

    def hold(self) -> None:
        """Stand still at the current position (v = a = 0), e.g. after the robot stopped."""
        self.v[:] = 0.0
        self.a[:] = 0.0

    def step(self, target: np.ndarray) -> float:
        """Advance one cycle towards ``target`` [rad]; returns the tracking performance of this step (0..1)."""
        dt = self.dt
        err = target - self.q
        v_req = err / dt
        a_req = (v_req - self.v) / dt
        lim = 1.0 + self._tol
        exact = (np.abs(v_req) <= self.vmax * lim) & (np.abs(a_req) <= self.amax * lim)
        if exact.all():
            self.a[:] = a_req
            self.v[:] = v_req
            self.q[:] = target
            return 1.0
        # joints that cannot land on the target: braking bound towards it, velocity limit, acceleration window
        # fastest velocity from which whole-step braking at a_max stops within |err|: n·a·dt with
        # a·dt²·n(n+1)/2 = |err|
        adt = self._dv
        brake = adt * (np.sqrt(0.25 + 2.0 * np.abs(err) / (adt * dt)) - 0.5)
        v_new = np.clip(v_req, -brake, brake)
        np.clip(v_new, -self.vmax, self.vmax, out=v_new)
        np.clip(v_new, self.v - self._dv, self.v + self._dv, out=v_new)
        v_new[exact] = v_req[exact]
        step = v_new * dt
        clipped = ~exact
        e_c = err[clipped]
        # achieved fraction of the requested step (0 where a joint was asked to stop dead and could not)
        frac = np.divide(step[clipped], e_c, out=np.zeros_like(e_c), where=np.abs(e_c) > 1e-15)
        self.a[:] = (v_new - self.v) / dt
        self.v[:] = v_new
        self.q += step
        self.q[exact] = target[exact]
        return float(np.clip(frac.min(), 0.0, 1.0))
