"""The sway sensor's checks: a healthy sensor with noise, a late link and a string 20 % off never trips them; a stuck,
frozen, jumping, reversed or NaN sensor does; the fitted residual sees through noise."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planners.feedback.health import SensorHealth, swing_amplitude
from tests.helpers.tracing import line_events

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


def _reference_check(o, rec, t: float) -> str | None:
    """The checks as first written: one pass over the whole window per reading (the cost that ended `lbr control
    damp`'s 1 ms sessions 0.54 s into the rows) — the judge of the constant-work version's verdicts."""
    rec[:] = [r for r in rec if r[0] >= t - max(o.still_s, o.window_s)]
    if rec[-1][0] - rec[0][0] < 0.9 * min(o.still_s, o.window_s):
        return None
    still = [r for r in rec if r[0] >= t - o.still_s]
    dv = lo = hi = 0.0
    for (t0, *_), (t1, _, _, a1) in zip(still, still[1:]):
        dv += a1 * (t1 - t0)
        lo, hi = min(lo, dv), max(hi, dv)
    vals_still = [r[1] for r in still]
    pred = np.array([r[2] for r in rec])
    if max(vals_still) - min(vals_still) <= o.still_range and (np.ptp(pred) > o.moving_range or hi - lo > o.drive):
        return "stood still"
    return None


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_windowed_checks_judge_as_a_pass_over_the_window(seed):
    """Readings that stand still now and then while the plan swings or the pivot is pushed: the stuck verdict comes
    at the same reading as from a pass over the whole window (short windows keep the reference cheap)."""
    from planners.feedback.health import HealthOptions

    o = HealthOptions(still_s=0.05, window_s=0.08, still_range=math.radians(0.5), moving_range=math.radians(1.0))
    rng = np.random.default_rng(seed)
    n = 1500
    t = np.cumsum(rng.uniform(0.5e-3, 1.5e-3, n))
    moving = np.repeat(rng.random(n // 50) < 0.7, 50)
    readings = np.where(moving, math.radians(3) * np.sin(30 * t), 0.0) + rng.normal(0, math.radians(0.05), n)
    ref = math.radians(2) * np.sin(30 * t) * np.repeat(rng.random(n // 50) < 0.5, 50)
    drive = rng.normal(0, 1.0, n) * np.repeat(rng.random(n // 50) < 0.5, 50)
    h, rec, expected = SensorHealth("θ", o), [], None
    for k in range(n):
        rec.append((t[k], readings[k], ref[k], drive[k]))
        expected = _reference_check(o, rec, t[k])
        got = h.reading(float(t[k]), float(readings[k]), float(readings[k]), float(ref[k]), float(drive[k]))
        assert (got is not None and "stood still" in got) == (expected is not None), k
        if got is not None:
            break
    assert expected is not None  # the case reached a verdict (it tests something)


@pytest.mark.parametrize("window_s", [1.0, 4.0])
def test_a_reading_costs_the_same_however_long_the_window(window_s):
    """`lbr control damp` judges each reading inside the 1 ms FRI cycle: once the window was full, a pass over it
    (≈ 1,000 readings, 0.7 ms a reading per axis) made every cycle late and the simulator's quality rule ended each
    session at 547 commanding cycles. The work per reading must not grow with the window."""
    from planners.feedback.health import HealthOptions

    h = SensorHealth("θ", HealthOptions(window_s=window_s))
    t, ref, true, drive = _swing(0.25, n=int(window_s * 1000) + 600)
    for k in range(len(t) - 300):  # the window full (and the sign judged once)
        h.reading(float(t[k]), float(true[k]), float(true[k]), float(ref[k]), float(drive[k]))
    rest = range(len(t) - 300, len(t))
    lines = line_events(lambda: [h.reading(float(t[k]), float(true[k]), float(true[k]), float(ref[k]),
                                            float(drive[k])) for k in rest])  # fmt: skip
    assert h.fault is None
    assert lines / len(rest) < 150  # (≈ 70) a pass over the window ran thousands of lines per reading
