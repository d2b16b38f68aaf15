"""The rendered cases' motions: the fourth judge's real pendulum swings slower at a wide amplitude than its small-angle
period, as the exact (elliptic-integral) period says, and loses amplitude to its damping."""

from __future__ import annotations

import math

import numpy as np
from scipy.special import ellipk

from tracking.scenarios import _true_swing


def test_a_real_pendulum_from_60_degrees_has_the_exact_period_and_is_damped():
    t, th = _true_swing(6.0, 60.0, 1.0, 0.0)
    assert th[0] == math.radians(60.0)
    down = np.flatnonzero((th[:-1] > 0) & (th[1:] <= 0))  # crossings of the vertical, swinging one way
    crossings = t[down] + th[down] / (th[down] - th[down + 1]) * 1e-3
    period = float(np.mean(np.diff(crossings)))
    exact = 2.0 / math.pi * ellipk(math.sin(math.radians(30.0)) ** 2)  # × the small-angle period (1 s)
    assert abs(period - exact) < 1e-4 and exact > 1.07  # 7 % slower than a sinusoid of the same small-angle period
    _, damped = _true_swing(6.0, 60.0, 1.0, 0.3)
    assert np.max(np.abs(damped[-1000:])) < 0.5 * math.radians(60.0)
