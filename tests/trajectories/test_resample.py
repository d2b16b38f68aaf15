"""Resampling a joint trajectory at another step."""

from __future__ import annotations

import numpy as np
import pytest

from trajectories.resample import resample
from trajectories.trajectory import JointTrajectory
from tests.helpers.cli import Q_START

Q0 = tuple(Q_START.tolist())  # [rad]


def test_resample_keeps_the_samples_and_interpolates_smoothly():
    t = np.arange(0, 1.0 + 1e-12, 0.005)
    q = np.array(Q0) + np.sin(np.pi * t)[:, None] * 0.1
    rs = resample(JointTrajectory(t=t, q=q), 0.001)
    assert len(rs) == 1001 and rs.dt == pytest.approx(0.001)
    np.testing.assert_allclose(rs.q[::5], q, atol=1e-12)
    np.testing.assert_allclose(rs.q, np.array(Q0) + np.sin(np.pi * rs.t)[:, None] * 0.1, atol=1e-6)
    np.testing.assert_array_equal(rs.q[-1], q[-1])
