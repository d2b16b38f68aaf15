"""The delay-compensating observer (planners.feedback.observer) against a simulated rod."""

from __future__ import annotations

import math

import numpy as np

from planners.feedback import DelayedObserver
from planners.rigid_pendulum import RigidPendulum, rk4_step


def _track(delay: float, length_error: float = 1.0) -> tuple[float, float]:
    """Max |φ̂ − φ| [rad] and |φ̂̇ − φ̇| [rad/s] over the last 2 s of a 4 s swing driven by a sinusoidal pivot."""
    p = RigidPendulum(rod_length=0.5)
    dt, rate = 1e-3, 200.0
    obs = DelayedObserver(p.equivalent_length * length_error, dt, delay, 1 / rate, actuation_delay=0)
    phi = omega = 0.0
    hist = []
    err_p, err_w = [], []
    for k in range(4000):
        t = k * dt
        a = 2.0 * math.sin(2 * math.pi * 0.7 * t)
        phi, omega = rk4_step(p, phi, omega, (a, 0.0), (a, 0.0), dt)
        hist.append(round(phi / (2 * math.pi) * 4096) * 2 * math.pi / 4096)
        lag = int(round(delay / dt))
        if k % 5 == 0 and k >= lag:
            obs.correct(hist[k - lag])
        obs.predict(a)
        if t > 2.0:
            err_p.append(abs(obs.phi - phi)), err_w.append(abs(obs.omega - omega))
    return max(err_p), max(err_w)


def test_a_delayed_quantised_reading_is_predicted_to_now():
    for delay in (0.005, 0.010):
        ep, ew = _track(delay)
        assert ep < math.radians(0.5) and ew < 0.1, (delay, ep, ew)


def test_without_the_delay_compensation_the_estimate_lags():
    """The same readings taken as current (delay 0) trail the swing by the delay: several times the error."""
    p = RigidPendulum(rod_length=0.5)
    dt = 1e-3
    obs = DelayedObserver(p.equivalent_length, dt, 0.0, 0.005, actuation_delay=0)
    phi = omega = 0.0
    hist, err = [], []
    for k in range(4000):
        a = 2.0 * math.sin(2 * math.pi * 0.7 * k * dt)
        phi, omega = rk4_step(p, phi, omega, (a, 0.0), (a, 0.0), dt)
        hist.append(phi)
        if k % 5 == 0 and k >= 10:
            obs.correct(hist[k - 10])
        obs.predict(a)
        if k > 2000:
            err.append(abs(obs.phi - phi))
    assert max(err) > 3 * _track(0.010)[0]


def test_a_wrong_model_length_is_corrected_by_the_readings():
    ep, _ = _track(0.005, length_error=1.2)
    assert ep < math.radians(1.5)
    assert np.isfinite(ep)


def _jittered(with_ages: bool, seed: int = 3) -> float:
    """Max |φ̂ − φ| [rad] over the last 2 s when readings at 120 Hz come 20–70 ms late (a camera on a busy PC): told
    each reading's age, or assuming the middle 45 ms for all."""
    p = RigidPendulum(rod_length=0.5)
    dt = 1e-3
    rng = np.random.default_rng(seed)
    obs = DelayedObserver(p.equivalent_length, dt, 0.045, 1 / 120, bandwidth=6.0, actuation_delay=0, max_delay=0.1)
    phi = omega = 0.0
    hist, err, queue = [], [], []
    for k in range(4000):
        a = 2.0 * math.sin(2 * math.pi * 0.7 * k * dt)
        phi, omega = rk4_step(p, phi, omega, (a, 0.0), (a, 0.0), dt)
        hist.append(phi)
        if k % 8 == 0:  # a frame shows now, arrives 20–70 ms later
            queue.append((k + int(rng.uniform(20, 70)), k))
        for arrive, shown in [q for q in queue if q[0] == k]:
            obs.correct(hist[shown], (k - shown) * dt if with_ages else None)
        queue = [q for q in queue if q[0] > k]
        obs.predict(a)
        if k > 2000:
            err.append(abs(obs.phi - phi))
    return max(err)


def test_readings_of_varying_age_are_compared_with_their_own_moment():
    told, assumed = _jittered(True), _jittered(False)
    assert told < math.radians(0.8), math.degrees(told)  # (measured 0.55°; 1.95–2.25° assuming one delay)
    assert assumed > 3 * told, (math.degrees(assumed), math.degrees(told))
