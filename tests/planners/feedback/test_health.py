"""The sway sensor's checks: a healthy sensor with noise, a late link and a string 20 % off never trips them; a stuck,
frozen, jumping, reversed or NaN sensor does; the fitted residual sees through noise."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planners.feedback.health import SensorHealth, swing_amplitude

G = 9.81


def _swing(length: float, n: int = 4000, dt: float = 1e-3, amp: float = math.radians(4.0)):
    """The plan's swing (model length 0.25 m) and a ball of ``length`` [m] under the same pivot push (linear)."""
    t = np.arange(n) * dt
    w_model, w_true = math.sqrt(G / 0.25), math.sqrt(G / length)
    ref = amp * np.sin(w_model * t) * np.minimum(1.0, t / 0.5)
    true = amp * np.sin(w_true * t) * np.minimum(1.0, t / 0.5)
    drive = -G * ref  # the pivot's acceleration that makes the plan's swing [m/s²] (θ̈ ≈ −(gθ + a)/l)
    return t, ref, true, drive


def _feed(h: SensorHealth, t, readings, ref, drive, predicted=None) -> str | None:
    for k in range(len(t)):
        p = readings[k] if predicted is None else predicted[k]
        fault = h.reading(float(t[k]), float(readings[k]), float(p), float(ref[k]), float(drive[k]))
        if fault:
            return fault
    return h.fault


@pytest.mark.heavy
@pytest.mark.parametrize(
    "length, noise, late", [(0.25, 0.0, 0), (0.30, math.radians(0.3), 30), (0.20, math.radians(0.6), 10)]
)
def test_a_healthy_sensor_never_trips(length, noise, late):
    t, ref, true, drive = _swing(length)
    rng = np.random.default_rng(1)
    readings = np.concatenate([np.zeros(late), true])[: len(t)] + rng.normal(0, noise, len(t))
    assert _feed(SensorHealth("θ"), t, readings, ref, drive, predicted=true) is None


@pytest.mark.heavy
@pytest.mark.parametrize("fault, words", [("stuck", "stood still"), ("frozen", "stood still"), ("reversed", "reversed"),
                                          ("jump", "jumped"), ("nan", "not a number")])  # fmt: skip
def test_a_lying_sensor_is_found(fault, words):
    t, ref, true, drive = _swing(0.25)
    readings = true.copy()
    predicted = true.copy()
    if fault == "stuck":
        readings[:] = 0.0
    elif fault == "frozen":
        readings[1500:] = readings[1500]
    elif fault == "reversed":
        readings = -true
        predicted = readings  # the observer follows whatever the sensor says
    elif fault == "jump":
        readings[2000:] += math.radians(20)
    else:
        readings[2500] = math.nan
    assert words in (_feed(SensorHealth("θ"), t, readings, ref, drive, predicted) or "")


def test_a_runaway_estimate_is_found():
    h = SensorHealth("θ")
    assert h.estimate(math.radians(10)) is None and "runs away" in h.estimate(math.radians(40))


def test_the_fitted_residual_sees_through_noise():
    t = np.arange(0, 1.2, 1e-3)
    period = 2 * math.pi * math.sqrt(0.25 / G)
    true = math.radians(0.03) * np.sin(2 * math.pi * t / period + 0.4)
    noisy = true + np.random.default_rng(2).normal(0, math.radians(0.3), len(t))
    assert np.degrees(np.abs(noisy).max()) > 0.6  # a peak of readings reports the noise …
    assert abs(math.degrees(swing_amplitude(t, noisy, period)) - 0.03) < 0.03  # … the fit the swing
