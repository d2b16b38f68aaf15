import numpy as np
import pytest

from trajectories.check import check_trajectory
from trajectories.retime import retime_within
from trajectories.trajectory import JointTrajectory


def test_retime_makes_a_too_fast_path_feasible_and_keeps_the_path(limits, q_start):
    h = 0.005
    s = 0.5 - 0.5 * np.cos(np.pi * np.linspace(0, 1, 201))
    q = q_start + np.outer(s, [1.5, 0.5, 1, 1, 1, 1, 2])
    fast = JointTrajectory.from_samples(q, h)  # 1 s: far beyond the velocity limits
    assert not check_trajectory(fast, limits).ok
    res, _ = retime_within(fast, limits, h)  # toppra, then the samples verified step by step
    out = res.trajectory
    assert check_trajectory(out, limits).ok
    assert out.dt == pytest.approx(h)
    assert np.allclose(out.q[0], q[0]) and np.allclose(out.q[-1], q[-1])
    # the same geometric path: every output sample lies on the input path (straight line in joint space here)
    direction = (q[-1] - q[0]) / np.linalg.norm(q[-1] - q[0])
    offsets = out.q - q[0]
    residual = offsets - np.outer(offsets @ direction, direction)
    assert np.abs(residual).max() < 1e-6
    # near time-optimal within limits: some joint runs at ≥ 90 % of a limit (the samples are verified step by step)
    ratios = check_trajectory(out, limits).ratios()
    assert max(ratios["velocity"].max(), ratios["acceleration"].max()) > 0.9
    assert res.duration_out > res.duration_in
