"""Closed-loop simulation without FRI: a rigid pendulum on the cart, its encoder (12 bit, sampled, delayed, with
jitter) and a controller — for tests and quick tuning. The FRI simulator runs the same loop with the real arm."""

from __future__ import annotations

import math
import random
from dataclasses import dataclass

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


def simulate_upright(pendulum: RigidPendulum, limits: CartLimits, duration: float, bounds=None, sensor: Sensor = Sensor(),
                     options: UprightOptions = UprightOptions(), dt: float = 1e-3, actuation_delay: int = 2,
                     pushes: tuple[tuple[float, float], ...] = (), park_at: float | None = None,
                     model_length: float | None = None, seed: int = 0) -> UprightRun:  # fmt: skip
    """Run the swing-up and balance for ``duration`` [s]; ``pushes`` (t [s], Δφ [rad]) knock the rod."""
    rng = random.Random(seed)
    n = int(round(duration / dt))
    cart = Cart(limits, dt, bounds=bounds)
    l_model = model_length or pendulum.equivalent_length
    ctl = UprightController(l_model, cart, options)
    obs = DelayedObserver(
        l_model, dt, sensor.delay + 0.5 * sensor.jitter, 1.0 / sensor.rate_hz, actuation_delay=actuation_delay
    )
    applied = [0.0] * (actuation_delay + 1)
    phi = omega = 0.0
    a_prev = 0.0
    queue: list[tuple[float, float]] = []
    next_sample = 0.0
    push = sorted(pushes)
    out = np.zeros((n, 7))
    for k in range(n):
        t = k * dt
        # plant: the pivot acceleration is the cart's, actuation_delay cycles late
        a_now = applied[k % len(applied)]
        phi, omega = rk4_step(pendulum, phi, omega, (a_prev, 0.0), (a_now, 0.0), dt)
        a_prev = a_now
        while push and push[0][0] <= t:
            phi += push.pop(0)[1]
        phi = wrap_angle(phi)
        if t + 1e-12 >= next_sample:
            next_sample += 1.0 / sensor.rate_hz
            count = round(phi / (2 * math.pi) * sensor.counts)
            queue.append((t + sensor.delay + rng.uniform(0, sensor.jitter), count * 2 * math.pi / sensor.counts))
        reading = None
        while queue and queue[0][0] <= t + 1e-12:
            reading = queue.pop(0)[1]
        if reading is not None:
            obs.correct(reading)
        if park_at is not None and t >= park_at and ctl.mode is not Mode.PARK:
            ctl.park()
        ctl.update(obs.phi, obs.omega)
        applied[k % len(applied)] = cart.a
        obs.predict(cart.a)
        out[k] = (t, phi, obs.phi, cart.x, cart.v, cart.a, int(ctl.mode))
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
                     seed: int = 0, controller: UprightOptions = UprightOptions()) -> SessionRun:  # fmt: skip
    """Run :class:`~.session.UprightSession` (options ``options``) for the rod ``pendulum`` while the controller
    assumes ``model_length`` [m]: until the session is done (or ``duration`` [s]); ``pushes`` (t [s] after the
    first catch, Δφ [rad]) knock the rod."""
    from .session import SessionOptions, UprightSession

    rng = random.Random(seed)
    cart = Cart(limits, dt, bounds=bounds)
    opts = options or SessionOptions()
    session = UprightSession(model_length, cart, 1.0 / sensor.rate_hz, opts, controller)
    applied = [0.0] * (actuation_delay + 1)
    phi = omega = 0.0
    a_prev = 0.0
    queue: list[tuple[float, float]] = []
    next_sample = 0.0
    push = sorted(pushes)
    limit = duration if duration is not None else (opts.wait_s + 10 + opts.fit_timeout_s + opts.swing_timeout_s
                                                   + opts.hold_s + 3 * opts.recatch_s + opts.lower_timeout_s + 5)  # fmt: skip
    ts, phis, xs, phases = [], [], [], []
    k = 0
    while not session.done and k * dt < limit:
        t = k * dt
        a_now = applied[k % len(applied)]
        phi, omega = rk4_step(pendulum, phi, omega, (a_prev, 0.0), (a_now, 0.0), dt)
        a_prev = a_now
        if session.swing_up_s is not None:
            caught = session._swing_t0 + session.swing_up_s
            while push and caught + push[0][0] <= t:
                phi += push.pop(0)[1]
        phi = wrap_angle(phi)
        if t + 1e-12 >= next_sample:
            next_sample += 1.0 / sensor.rate_hz
            count = sensor.sign * round(phi / (2 * math.pi) * sensor.counts) + sensor.offset
            if sensor.noise:
                count += rng.randint(-sensor.noise, sensor.noise)
            queue.append((t + sensor.delay + rng.uniform(0, sensor.jitter), count * 2 * math.pi / sensor.counts))
        reading = None
        while queue and queue[0][0] <= t + 1e-12:
            reading = queue.pop(0)[1]
        if reading is not None:
            session.reading(reading)
        session.step()
        applied[k % len(applied)] = cart.a
        ts.append(t)
        phis.append(phi)
        xs.append(cart.x)
        phases.append(session.phase)
        k += 1
    return SessionRun(np.array(ts), np.array(phis), np.array(xs), phases, session)
