"""Active sway damping without FRI: the reference, the damper on a ball whose string length is wrong, its bounds."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planners.feedback.damping import (DampingOptions, SwayDamper, pivot_acceleration, simulate_damping,
                                       sway_reference)  # fmt: skip
from planners.pendulum import natural_period

DT = 0.005


def _min_jerk(n: int) -> np.ndarray:
    s = np.linspace(0.0, 1.0, n)
    return 10 * s**3 - 15 * s**4 + 6 * s**5


def _crane_path(moves=((0.2, 0.0, 1.5), (0.0, 0.15, 1.2), (-0.15, -0.05, 1.2)), hold: float = 0.3) -> np.ndarray:
    """Unshaped rest-to-rest pivot moves (dx, dy [m], duration [s]) with holds between: they leave the ball swinging."""
    p = np.array([0.5, -0.2, 0.45])
    out = [np.repeat(p[None], int(hold / DT), axis=0)]
    for dx, dy, dur in moves:
        s = _min_jerk(int(dur / DT))[:, None]
        seg = p + s * np.array([dx, dy, 0.0])
        out += [seg, np.repeat(seg[-1:], int(hold / DT), axis=0)]
        p = seg[-1]
    return np.vstack(out)


def _residual_deg(run, t_end: float, periods: float, true_length: float) -> float:
    m = run.t >= t_end + periods * natural_period(true_length)
    return float(np.degrees(run.theta[m].max()))


def test_reference_is_zero_without_motion_and_fades_after_it():
    acc = np.zeros((400, 2))
    th, rate = sway_reference(acc, 0.25, DT)
    assert np.all(th == 0) and np.all(rate == 0)
    path = _crane_path()
    acc = pivot_acceleration(path[:, :2], DT)
    acc = np.vstack([acc, np.zeros((600, 2))])
    th, _ = sway_reference(acc, 0.25, DT)
    assert np.abs(th).max() > math.radians(3)  # the unshaped moves swing the model
    assert np.all(th[-200:] == 0)  # faded out after the motion


@pytest.mark.parametrize("off", [0.8, 1.2])
@pytest.mark.parametrize("delay", [0.006, 0.011])
def test_damper_removes_the_sway_a_wrong_length_leaves(off, delay):
    path = _crane_path()
    t_end = (len(path) - 1) * DT
    model = 0.25
    true = model * off
    open_ = simulate_damping(path, DT, true, model, sensor_delay=delay, damping=False, after_s=3.0)
    closed = simulate_damping(path, DT, true, model, sensor_delay=delay, after_s=3.0)
    assert _residual_deg(open_, t_end, 2, true) > 5.0  # unshaped: the ball swings on
    assert _residual_deg(closed, t_end, 2, true) <= 0.5
    assert _residual_deg(closed, t_end, 2, true) < 0.1 * _residual_deg(open_, t_end, 2, true)
    # the offset stays small and comes back toward the path
    assert np.abs(closed.offset).max() < 0.08
    assert np.abs(closed.offset[-1]).max() < 0.01


def test_right_length_gives_no_correction_to_speak_of():
    """With the model's own length the deviation from the reference is only the spherical coupling: tiny offsets."""
    path = _crane_path()
    moving = np.arange(len(path) + 200) * DT < (len(path) - 1) * DT
    run = simulate_damping(path, DT, 0.25, 0.25, sensor_delay=0.0, after_s=1.0)
    wrong = simulate_damping(path, DT, 0.3, 0.25, sensor_delay=0.0, after_s=1.0)
    assert np.abs(run.offset[moving]).max() < 0.6 * np.abs(wrong.offset[moving]).max()


def test_offsets_respect_their_bounds():
    path = _crane_path()
    n = len(path) + int(3.0 / DT)
    b = np.tile([0.1, -0.8, 0.8, -8.0, 8.0], (n, 1))
    run = simulate_damping(path, DT, 0.35, 0.25, sensor_delay=0.011, after_s=3.0, bounds=b)
    acc = run.accel[2:-2]
    assert np.abs(acc).max() <= 0.8 * 1.02
    vel = np.abs(np.diff(run.offset, axis=0)) / DT
    assert vel.max() <= 0.1 * 1.02
    # tighter bounds damp more slowly but still damp
    free = simulate_damping(path, DT, 0.35, 0.25, sensor_delay=0.011, after_s=3.0, damping=False)
    t_end = (len(path) - 1) * DT
    assert _residual_deg(run, t_end, 2, 0.35) < 0.5 * _residual_deg(free, t_end, 2, 0.35)


def test_observer_delay_bridged_each_axis_independent():
    d = SwayDamper(0.25, DT, 0.01, DT, DampingOptions())
    for _ in range(10):
        d.correct(0, 0.05)
        d.step((0.0, 0.0), (0.0, 0.0), (0.0, 0.0))
    x, y = d.offset
    assert x != 0.0 and y == 0.0  # only the swinging axis moves


def test_bad_options_refused():
    with pytest.raises(ValueError):
        SwayDamper(0.25, DT, 0.0, DT, DampingOptions(jerk=0.0))
