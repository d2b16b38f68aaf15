"""Closed-loop simulation without FRI: a rigid pendulum on the cart, its encoder (12 bit, sampled, delayed, with
jitter) and a controller — for tests and quick tuning. The FRI simulator runs the same loop with the real arm."""

from __future__ import annotations

import math
import random
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..rail import CartLimits
from ..rigid_pendulum import RigidPendulum, rk4_step, wrap_angle
from .cart import Cart
from .observer import DelayedObserver
from .upright import Mode, UprightController, UprightOptions


@dataclass(frozen=True)
class Sensor:
    """The encoder link: readings per second [Hz], delay and jitter [s], resolution [counts per turn], and its
    faults: uniform noise of ±``noise`` counts, a zero ``offset`` [counts], a ``sign`` (−1: reversed)."""

    rate_hz: float = 200.0
    delay: float = 0.005
    jitter: float = 0.001
    counts: int = 4096
    noise: int = 0
    offset: int = 0
    sign: int = 1


@dataclass(frozen=True)
class UprightRun:
    t: np.ndarray  # [s]
    phi: np.ndarray  # true angle [rad]
    phi_est: np.ndarray  # estimate [rad]
    x: np.ndarray  # cart [m]
    v: np.ndarray  # [m/s]
    a: np.ndarray  # [m/s²]
    mode: np.ndarray  # Mode per cycle
    catches: int
    falls: int


PlantStep = Callable[[float, float, float, float, float], "tuple[float, float]"]


class _Bench:
    """The plant and its encoder link, one cycle at a time (the one home of both loops below): the rod driven by the
    cart's acceleration ``actuation_delay`` cycles late (RK4 of ``pendulum``, or ``plant_step``), knocked by
    :meth:`knock`, sampled at the sensor's rate, quantised (sign, offset, noise) and delivered late with jitter."""

    def __init__(self, pendulum: RigidPendulum | None, sensor: Sensor, dt: float, actuation_delay: int, seed: int,
                 plant_step: PlantStep | None = None) -> None:  # fmt: skip
        self.pendulum, self.sensor, self.dt, self.plant_step = pendulum, sensor, dt, plant_step
        self.rng = random.Random(seed)
        self.applied = [0.0] * (actuation_delay + 1)  # the commanded accelerations, a ring over the actuation delay
        self.phi = self.omega = 0.0  # the true rod [rad], [rad/s]
        self._a_prev = 0.0
        self._queue: list[tuple[float, float]] = []  # (arrival [s], reading [rad])
        self._next_sample = 0.0

    def plant(self, k: int) -> None:
        """Cycle ``k``: the rod one step on with the pivot's acceleration applied now."""
        a_now = self.applied[k % len(self.applied)]
        if self.plant_step is None:
            self.phi, self.omega = rk4_step(
                self.pendulum, self.phi, self.omega, (self._a_prev, 0.0), (a_now, 0.0), self.dt
            )
        else:
            self.phi, self.omega = self.plant_step(self.phi, self.omega, self._a_prev, a_now, self.dt)
        self._a_prev = a_now

    def knock(self, dphi: float) -> None:
        self.phi += dphi

    def sense(self, t: float) -> float | None:
        """At ``t`` [s]: sample the rod when due; the latest reading [rad] that arrived by now, or None."""
        self.phi = wrap_angle(self.phi)
        sensor, rng = self.sensor, self.rng
        if t + 1e-12 >= self._next_sample:
            self._next_sample += 1.0 / sensor.rate_hz
            count = sensor.sign * round(self.phi / (2 * math.pi) * sensor.counts) + sensor.offset
            if sensor.noise:
                count += rng.randint(-sensor.noise, sensor.noise)
            self._queue.append((t + sensor.delay + rng.uniform(0, sensor.jitter), count * 2 * math.pi / sensor.counts))
        reading = None
        while self._queue and self._queue[0][0] <= t + 1e-12:
            reading = self._queue.pop(0)[1]
        return reading

    def actuate(self, k: int, accel: float) -> None:
        """The cart's acceleration [m/s²] commanded in cycle ``k`` (the pivot's ``actuation_delay`` cycles later)."""
        self.applied[k % len(self.applied)] = accel


def simulate_upright(pendulum: RigidPendulum, limits: CartLimits, duration: float, bounds=None, sensor: Sensor = Sensor(),
                     options: UprightOptions = UprightOptions(), dt: float = 1e-3, actuation_delay: int = 2,
                     pushes: tuple[tuple[float, float], ...] = (), park_at: float | None = None,
                     model_length: float | None = None, seed: int = 0, friction: float = 0.0) -> UprightRun:  # fmt: skip
    """Run the swing-up and balance for ``duration`` [s]; ``pushes`` (t [s], Δφ [rad]) knock the rod; ``friction``
    μ [rad/s²]: the bearing's dry friction the controller and its observer are told (as the identification would)."""
    n = int(round(duration / dt))
    cart = Cart(limits, dt, bounds=bounds)
    l_model = model_length or pendulum.equivalent_length
    ctl = UprightController(l_model, cart, options, friction=friction)
    obs = DelayedObserver(l_model, dt, sensor.delay + 0.5 * sensor.jitter, 1.0 / sensor.rate_hz,
                          actuation_delay=actuation_delay, coulomb=friction)  # fmt: skip
    bench = _Bench(pendulum, sensor, dt, actuation_delay, seed)
    push = sorted(pushes)
    out = np.zeros((n, 7))
    for k in range(n):
        t = k * dt
        bench.plant(k)
        while push and push[0][0] <= t:
            bench.knock(push.pop(0)[1])
        reading = bench.sense(t)
        if reading is not None:
            obs.correct(reading)
        if park_at is not None and t >= park_at and ctl.mode is not Mode.PARK:
            ctl.park()
        ctl.update(obs.phi, obs.omega)
        bench.actuate(k, cart.a)
        obs.predict(cart.a)
        out[k] = (t, bench.phi, obs.phi, cart.x, cart.v, cart.a, int(ctl.mode))
    return UprightRun(
        out[:, 0], out[:, 1], out[:, 2], out[:, 3], out[:, 4], out[:, 5], out[:, 6].astype(int), ctl.catches, ctl.falls
    )


@dataclass(frozen=True)
class SessionRun:
    """A whole upright session (:class:`~.session.UprightSession`) on the fast simulation."""

    t: np.ndarray  # [s]
    phi: np.ndarray  # true angle [rad] (0 hanging)
    x: np.ndarray  # cart [m]
    phase: list[str]  # per cycle
    session: object  # the UprightSession at the end (figures, rod, verdict)


def simulate_session(pendulum: RigidPendulum, limits: CartLimits, model_length: float, options=None,
                     sensor: Sensor = Sensor(), duration: float | None = None, dt: float = 1e-3,
                     actuation_delay: int = 2, pushes: tuple[tuple[float, float], ...] = (), bounds=None,
                     seed: int = 0, controller: UprightOptions = UprightOptions(),
                     plant_step: PlantStep | None = None) -> SessionRun:  # fmt: skip
    """Run :class:`~.session.UprightSession` (options ``options``) for the rod ``pendulum`` while the controller
    assumes ``model_length`` [m]: until the session is done (or ``duration`` [s]); ``pushes`` (t [s] after the
    first catch, Δφ [rad]) knock the rod. ``plant_step(φ, φ̇, a0, a1, h) -> (φ, φ̇)`` integrates the rod over one
    cycle with the pivot's acceleration going from a0 to a1 [m/s²] (default: RK4 of ``pendulum``)."""
    from .session import SessionOptions, UprightSession

    cart = Cart(limits, dt, bounds=bounds)
    opts = options or SessionOptions()
    session = UprightSession(model_length, cart, 1.0 / sensor.rate_hz, opts, controller)
    bench = _Bench(pendulum, sensor, dt, actuation_delay, seed, plant_step)
    push = sorted(pushes)
    limit = duration if duration is not None else (opts.wait_s + 10 + opts.fit_timeout_s + opts.swing_timeout_s
                                                   + opts.hold_s + 3 * opts.recatch_s + opts.lower_timeout_s + 5)  # fmt: skip
    ts, phis, xs, phases = [], [], [], []
    k = 0
    while not session.done and k * dt < limit:
        t = k * dt
        bench.plant(k)
        if session.swing_up_s is not None:
            caught = session._swing_t0 + session.swing_up_s
            while push and caught + push[0][0] <= t:
                bench.knock(push.pop(0)[1])
        reading = bench.sense(t)
        if reading is not None:
            session.reading(reading)
        session.step()
        bench.actuate(k, cart.a)
        ts.append(t)
        phis.append(bench.phi)
        xs.append(cart.x)
        phases.append(session.phase)
        k += 1
    return SessionRun(np.array(ts), np.array(phis), np.array(xs), phases, session)
