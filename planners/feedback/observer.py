"""Estimate of a pendulum's angle and rate now from delayed, quantised angle readings.

Between readings the estimate runs the model φ̈ = −(g·sin φ + a·cos φ)/l − d·φ̇ − μ·sgn φ̇ forward every cycle with the cart
acceleration a the robot actually applied (the command, ``actuation_delay`` cycles late). A reading that arrives
now is the angle ``delay`` cycles ago: its innovation against the estimate kept for that moment corrects the
current estimate (and the kept history) with the gains of a second-order observer of bandwidth ``bandwidth``
[rad/s] for the reading interval — the delay-compensating predictor of a Smith-type observer, without its matrices.
A sensor that knows each reading's own age (a camera's frames come late by varying amounts) passes it to
:meth:`DelayedObserver.correct`; the history then reaches back ``max_delay``. Allocation-free per cycle.
"""

from __future__ import annotations

import math

from ..pendulum import G
from ..rigid_pendulum import wrap_angle


class DelayedObserver:
    """(φ [rad], φ̇ [rad/s]) of a pendulum of equivalent length ``length`` [m], estimated every ``dt`` [s]."""

    def __init__(self, length: float, dt: float, delay: float, reading_interval: float, bandwidth: float = 30.0,
                 damping_ratio: float = 0.8, actuation_delay: int = 2, friction: float = 0.0,
                 phi0: float = 0.0, coulomb: float = 0.0, max_delay: float | None = None) -> None:  # fmt: skip
        if not (length > 0 and dt > 0 and delay >= 0 and reading_interval > 0 and bandwidth > 0):
            raise ValueError("observer: length, step, reading interval and bandwidth must be > 0, the delay >= 0")
        self.length, self.dt, self.friction = length, dt, friction  # [m], [s], [1/s]
        self.coulomb = coulomb  # [rad/s²] the bearing's dry friction per inertia
        self.phi, self.omega = phi0, 0.0
        self._lag = max(0, int(round(delay / dt)))  # cycles between the reading's moment and now
        keep = max(self._lag, int(round(max_delay / dt)) if max_delay is not None else 0)
        self._hist = [phi0] * (keep + 1)  # φ̂ of the last keep + 1 cycles (ring)
        self._at = 0
        w = bandwidth
        self.gain_phi = min(0.9, 2.0 * damping_ratio * w * reading_interval)
        self.gain_omega = w * w * reading_interval
        self._u = [0.0] * (max(0, actuation_delay) + 1)  # commanded accelerations, oldest applied now (ring)
        self._u_at = 0
        self.readings = 0
        self.last_innovation = 0.0  # [rad]

    def predict(self, accel_command: float) -> None:
        """One cycle forward; ``accel_command`` [m/s²] is the cart acceleration commanded this cycle."""
        u = self._u
        i = self._u_at
        a = u[i]  # commanded actuation_delay cycles ago: what the pivot does now
        u[i] = accel_command
        self._u_at = (i + 1) % len(u)
        dt, l = self.dt, self.length
        alpha = (-(G * math.sin(self.phi) + a * math.cos(self.phi)) / l - self.friction * self.omega
                 - self.coulomb * math.tanh(self.omega / 0.05))  # fmt: skip
        self.omega += alpha * dt
        self.phi += self.omega * dt
        self._at = (self._at + 1) % len(self._hist)
        self._hist[self._at] = self.phi

    def lag_of(self, age: float | None) -> int:
        """Cycles back to a reading's moment: ``age`` [s] (None: the ``delay``), within the history kept."""
        if age is None:
            return self._lag
        lag = int(round(age / self.dt))
        return 0 if lag < 0 else min(lag, len(self._hist) - 1)

    def predicted_reading(self, age: float | None = None) -> float:
        """The estimate [rad] for the moment a reading arriving now shows (``age`` [s] ago; default ``delay``)."""
        h = self._hist
        return h[(self._at - self.lag_of(age)) % len(h)]

    def correct(self, reading: float, age: float | None = None) -> None:
        """A reading [rad] of the angle ``age`` [s] ago (default ``delay``) arrived this cycle."""
        h = self._hist
        lag = self.lag_of(age)
        then = h[(self._at - lag) % len(h)]  # the estimate kept for that moment
        e = wrap_angle(reading - then)
        self.last_innovation = e
        dp, dw = self.gain_phi * e, self.gain_omega * e
        self.phi += dp
        self.omega += dw
        lag_dt = self.dt * lag
        self.phi += dw * lag_dt  # the rate correction has acted since the reading's moment
        for k in range(len(h)):
            h[k] += dp
        self.readings += 1

    def reset(self, phi: float, omega: float = 0.0) -> None:
        self.phi, self.omega = phi, omega
        for k in range(len(self._hist)):
            self._hist[k] = phi
