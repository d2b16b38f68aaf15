"""Jerk-limited braking stop: from the last command's position, velocity and acceleration to rest (ruckig).

Every stop the client initiates (interrupt, guard refusal, a client's end, a failed observer) runs through here,
so the commanded deceleration never exceeds the acceleration and jerk limits. The state is taken from the last
three commands sent as the braking envelope defines it (:mod:`trajectories.envelope`: the step velocity plus half a
period of the step acceleration, and that acceleration), so the stop's first sampled step continues the history
within the jerk limit; each joint stops on its own, time-optimally (ruckig's velocity interface, no
synchronisation: the distances the envelope reserves are each joint's shortest). A command admitted into the
envelope always leaves this stop inside the velocity, acceleration, jerk and position limits. Computed online one
cycle at a time; done when ruckig says Finished.
"""

from __future__ import annotations

import math
from typing import Sequence

from ruckig import ControlInterface, InputParameter, OutputParameter, Result, Ruckig, Synchronization

from trajectories.limits import JointLimits

INSIDE = 1.0 - 1e-6  # the stop's limits, a hair inside the guard's (ruckig's rounding at the limits)
EFFORT_RAMP_MIN_S = 0.05  # [s] the shortest effort ramp of a stop


def set_continuous_state(inp: InputParameter, q: Sequence[float], q_1: Sequence[float], q_2: Sequence[float],
                         dt: float) -> None:  # fmt: skip
    """Ruckig's current state from the positions ``q``, ``q_1``, ``q_2`` [rad] one period ``dt`` [s] apart (newest
    first): the continuous state the step history continues into — v_k + a_k·dt/2 (second-order backward
    difference) and a_k — so that the first sampled step continues the history within the jerk limit."""
    inp.current_position = list(q)
    inp.current_velocity = [(3.0 * a - 4.0 * b + c) / (2.0 * dt) for a, b, c in zip(q, q_1, q_2)]
    inp.current_acceleration = [(a - 2.0 * b + c) / (dt * dt) for a, b, c in zip(q, q_1, q_2)]


class BrakingStop:
    """Online braking profile; ``start()`` it with the last commands, then ``next()`` once per cycle."""

    def __init__(self, limits: JointLimits, period_s: float, scale: float = 1.0) -> None:
        self.period_s = period_s
        self._otg = Ruckig(7, period_s)
        self._inp = InputParameter(7)
        self._out = OutputParameter(7)
        self._inp.control_interface = ControlInterface.Velocity
        self._inp.synchronization = Synchronization.No
        lim = limits.scaled(scale * INSIDE)
        # a stop must not stall on a limit it already exceeds: ruckig brakes into the limits first
        self._inp.max_velocity = lim.velocity.tolist()
        self._inp.max_acceleration = lim.acceleration.tolist()
        self._inp.max_jerk = lim.jerk.tolist()
        self._inp.target_velocity = [0.0] * 7
        self._inp.target_acceleration = [0.0] * 7
        self.cycles = 0  # cycles commanded so far
        self.done = False
        self._hold: tuple[float, ...] = ()

    def start(self, q: Sequence[float], q_1: Sequence[float], q_2: Sequence[float]) -> None:
        """Brake from the command ``q`` [rad] that followed ``q_1`` and ``q_2`` (one and two periods before)."""
        inp = self._inp
        set_continuous_state(inp, q, q_1, q_2, self.period_s)
        self.cycles = 0
        self.done = not any(inp.current_velocity) and not any(inp.current_acceleration)
        self._hold = tuple(q)

    def next(self) -> tuple[float, ...]:
        """The next command [rad]; ``done`` becomes True when the robot is at rest."""
        if self.done:
            return self._hold
        res = self._otg.update(self._inp, self._out)
        self.cycles += 1
        if res not in (Result.Working, Result.Finished):  # cannot happen within the limits; hold what we have
            self.done = True
            return self._hold
        q = tuple(self._out.new_position)
        self._out.pass_to_input(self._inp)
        if res == Result.Finished:
            self.done = True
            self._hold = q
        return q


class Coast(BrakingStop):
    """While the controller's confirmations lag (late or lost replies), the motion every bridging model agrees on:
    the acceleration brought to 0 within the jerk limit, then constant velocity — so that a controller that
    extrapolates, holds the velocity or carries a late command forward executes the same positions we send."""

    def start(self, q: Sequence[float], q_1: Sequence[float], q_2: Sequence[float]) -> None:
        super().start(q, q_1, q_2)
        inp = self._inp
        # the velocity reached when the acceleration goes to 0 at the jerk limit (within the velocity limit)
        inp.target_velocity = [max(-vm, min(vm, v + a * abs(a) / (2.0 * j))) for v, a, j, vm
                               in zip(inp.current_velocity, inp.current_acceleration, inp.max_jerk, inp.max_velocity)]  # fmt: skip
        self.done = not any(inp.current_acceleration)
        self._step = tuple((a - b) for a, b in zip(q, q_1)) if self.done else (0.0,) * len(q)

    def next(self) -> tuple[float, ...]:
        """The next command [rad]: along the profile, then at its final velocity."""
        if self.done:
            self._hold = tuple(x + s for x, s in zip(self._hold, self._step))
            return self._hold
        q = super().next()
        if self.done:  # (the profile's end: constant velocity from here)
            self._step = tuple(v * self.period_s for v in self._out.new_velocity)
        return q


class EffortRamp:
    """The torque or wrench of a stop: from the last one sent to zero along a raised cosine whose steepest rate is at
    most ``rates`` [Nm/s or N/s per component] (and that lasts at least ``EFFORT_RAMP_MIN_S``)."""

    def __init__(self, rates: Sequence[float], period_s: float) -> None:
        self.rates = tuple(rates)
        self.period_s = period_s
        self._from: tuple[float, ...] = ()
        self._n = 0
        self._k = 0

    def start(self, effort: Sequence[float]) -> None:
        self._from = tuple(effort)
        # a raised cosine from e to 0 over T has its steepest rate π·|e| / (2T)
        t = max([EFFORT_RAMP_MIN_S] + [math.pi * abs(e) / (2.0 * r) for e, r in zip(self._from, self.rates)])
        self._n = max(1, int(math.ceil(t / self.period_s)))
        self._k = 0

    @property
    def done(self) -> bool:
        return self._k >= self._n

    def next(self) -> tuple[float, ...]:
        if self._k < self._n:
            self._k += 1
        s = 0.5 * (1.0 + math.cos(math.pi * self._k / self._n))
        return tuple(e * s for e in self._from)
