"""Jerk-limited tracking of a moving reference: ruckig planned to intercept it.

Ruckig's position interface plans to a target *state* as if the target stood still once reached; fed the moving
reference's present state cycle after cycle it lags and swings (its time-optimal plan to where the reference is now
takes the jerk limit's time, by which the reference is elsewhere). The tracker instead plans to where the reference
*will be* when the plan arrives: the interception time ``T`` is found by iteration (``T`` ← the time-optimal duration
to reach the reference's state at ``T`` ahead, from one period), then ruckig plans to that state in exactly ``T``.
On the reference this is one period and the command is the reference itself; after a disturbance (a clamp, a bridged
message, the first target far away) the plan meets the reference later, never leaving the limits. The first period
of the plan is the command; the next cycle plans again.
"""

from __future__ import annotations

import math
from typing import Callable, Sequence

import numpy as np
from ruckig import InputParameter, Result, Ruckig, RuckigError, Trajectory

from trajectories.limits import JointLimits

Reference = tuple[np.ndarray, np.ndarray, np.ndarray]  # position [rad], velocity [rad/s], acceleration [rad/s²]
MAX_ITERATIONS = 6  # interception-time refinements per cycle (on the reference: one)
_OK = (Result.Working, Result.Finished)


class Untrackable(RuntimeError):
    """Ruckig found no trajectory (the message names its result)."""


class ReferenceTracker:
    """Follows a reference within ``limits``; :attr:`q`, :attr:`v`, :attr:`a` are the commanded state [rad, rad/s,
    rad/s²]."""

    def __init__(self, limits: JointLimits, period_s: float, q: Sequence[float]) -> None:
        n = len(q)
        self.period_s = period_s
        self.v_max = 0.99 * np.asarray(limits.velocity, dtype=float)  # [rad/s] a target state ruckig may end in
        self.a_max = 0.99 * np.asarray(limits.acceleration, dtype=float)  # [rad/s²]
        self.j_max = np.asarray(limits.jerk, dtype=float)  # [rad/s³]
        self._otg = Ruckig(n)
        self._inp = InputParameter(n)
        self._inp.max_velocity = np.asarray(limits.velocity, dtype=float).tolist()
        self._inp.max_acceleration = np.asarray(limits.acceleration, dtype=float).tolist()
        self._inp.max_jerk = self.j_max.tolist()
        self._traj = Trajectory(n)
        self._vm, self._am, self._jm = self.v_max.tolist(), self.a_max.tolist(), self.j_max.tolist()  # (per cycle)
        self._vl = np.asarray(limits.velocity, dtype=float).tolist()
        self._al = np.asarray(limits.acceleration, dtype=float).tolist()
        self.q = np.array(q, dtype=float)
        self.v = np.zeros(n)
        self.a = np.zeros(n)
        self.intercept_s = period_s  # [s] when the last plan met the reference
        self.on_reference = 0  # cycles the plan met the reference one period ahead
        self.catching_up = 0  # cycles it met it later (a disturbance, a reference faster than the limits)
        self.error = ""  # ruckig's last complaint

    def reset(self, q: Sequence[float], v: Sequence[float], a: Sequence[float]) -> None:
        """The commanded state is (``q``, ``v``, ``a``) [rad, rad/s, rad/s²] (re-plan from what was executed)."""
        self.q, self.v, self.a = np.array(q, dtype=float), np.array(v, dtype=float), np.array(a, dtype=float)

    def _target(self, ref: Reference) -> None:
        q, v, a = ref
        vt, at = [], []
        for vj, aj, vm, am, jm in zip(v.tolist(), a.tolist(), self._vm, self._am, self._jm):
            vj = -vm if vj < -vm else (vm if vj > vm else vj)
            aj = -am if aj < -am else (am if aj > am else aj)
            if aj * vj < 0.0:  # arriving while decelerating it was faster just before: |v| + a²/2j ≤ the limit
                room = math.sqrt(max(0.0, 2.0 * jm * (vm - abs(vj))))
                aj = -room if aj < -room else (room if aj > room else aj)
            vt.append(vj)
            at.append(aj)
        inp = self._inp
        inp.target_position, inp.target_velocity, inp.target_acceleration = q.tolist(), vt, at

    def _current(self) -> None:
        """The commanded state as ruckig's start (a state re-planned from what was executed may sit beyond what
        ruckig accepts: at the velocity limit with an acceleration still pushing outwards)."""
        v0, a0 = [], []
        for vj, aj, vm, am, jm in zip(self.v.tolist(), self.a.tolist(), self._vl, self._al, self._jm):
            vj = -vm if vj < -vm else (vm if vj > vm else vj)
            aj = -am if aj < -am else (am if aj > am else aj)
            if aj * vj > 0.0:
                room = math.sqrt(max(0.0, 2.0 * jm * (vm - abs(vj))))
                aj = -room if aj < -room else (room if aj > room else aj)
            v0.append(vj)
            a0.append(aj)
        inp = self._inp
        inp.current_position, inp.current_velocity, inp.current_acceleration = self.q.tolist(), v0, a0

    def _calculate(self) -> Result:
        try:
            return self._otg.calculate(self._inp, self._traj)
        except RuckigError as exc:  # an input ruckig refuses: reported as a result …
            self.error = str(exc).strip()
        # … unless it is one of ruckig's numerical edge cases (its step 2 fails to synchronise an axis for some exact
        # states): the start's velocity (then also its acceleration) smaller by a relative 1e-9 (then 1e-7), far
        # below what a command resolves
        inp = self._inp
        for shrink in (1e-9, 1e-7):
            inp.current_velocity = [v * (1.0 - shrink) for v in inp.current_velocity]
            if shrink > 1e-9:
                inp.current_acceleration = [a * (1.0 - shrink) for a in inp.current_acceleration]
            try:
                return self._otg.calculate(inp, self._traj)
            except RuckigError:
                pass
        return Result.ErrorInvalidInput

    def hold(self) -> np.ndarray:
        """The next commanded position [rad] without a reference: where the commanded state stops. At rest that is
        where it is, without planning (a holding client's cycle stays short); moving, the jerk-limited stop."""
        if self.v.any() or self.a.any():
            zero = np.zeros(len(self.q))
            return self.step(lambda t, q=self.q: (q, zero, zero))
        self.intercept_s = self.period_s
        self.on_reference += 1
        return self.q

    def step(self, reference: Callable[[float], Reference]) -> np.ndarray:
        """The next commanded position [rad]; ``reference(t)`` is the reference's state ``t`` [s] after the next
        command's time minus one period (``reference(period)``: at the next command)."""
        dt = self.period_s
        inp, traj = self._inp, self._traj
        self._current()
        t_meet = dt
        inp.minimum_duration = None
        for i in range(MAX_ITERATIONS):
            self._target(reference(t_meet))
            res = self._calculate()
            if res not in _OK:
                raise Untrackable(f"ruckig could not follow the target ({res.name}: {self.error})")
            if traj.duration <= t_meet * (1 + 1e-9):
                if traj.duration < t_meet * (1 - 1e-9):  # faster than the reference: arrive with it
                    inp.minimum_duration = t_meet
                    res = self._calculate()
                    if res not in _OK:  # (no plan of exactly that duration: the time-optimal one)
                        inp.minimum_duration = None
                        self._calculate()
                break
            # not on the reference: from where the last plan met it, if that is later (fewer refinements)
            t_meet = max(traj.duration, self.intercept_s - dt) if i == 0 else traj.duration
        self.intercept_s = t_meet
        if t_meet <= dt * (1 + 1e-9):
            self.on_reference += 1
        else:
            self.catching_up += 1
        q, v, a = traj.at_time(dt)  # (past a plan shorter than a period ruckig carries its end state on)
        self.q, self.v, self.a = np.array(q), np.array(v), np.array(a)
        return self.q
