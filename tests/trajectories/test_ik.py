import numpy as np
import pytest

from trajectories.errors import IkError
from trajectories.ik import solve_ik_path


def _path(robot, q_start, n=2001, dt=1e-3, amplitude=0.3):
    t = np.arange(n) * dt
    wave = np.sin(2 * np.pi * 0.5 * t)[:, None] * amplitude * np.array([1, 0.5, 0.3, 0.4, 0.6, 0.5, 1])
    q = q_start + wave
    return t, q, *robot.fk_path(q)


@pytest.mark.heavy
def test_ik_round_trip_with_changing_orientation(robot, limits, q_start):
    t, q_true, pos, rot = _path(robot, q_start)
    # the orientation really changes along this path
    angles = [np.degrees(np.arccos((np.trace(rot[0].T @ r) - 1) / 2)) for r in rot]
    assert max(angles) > 20
    res = solve_ik_path(robot, pos, rot, q_start, limits, times=t)
    pos2, rot2 = robot.fk_path(res.q)
    assert np.abs(pos2 - pos).max() < 1e-6
    rot_err = [np.arccos(np.clip((np.trace(a.T @ b) - 1) / 2, -1, 1)) for a, b in zip(rot, rot2)]
    assert max(rot_err) < 1e-5
    assert res.max_position_error < 1e-6 and res.max_rotation_error < 1e-5


def test_ik_never_flips_configuration(robot, limits, q_start):
    t, _, pos, rot = _path(robot, q_start, amplitude=0.5)
    res = solve_ik_path(robot, pos, rot, q_start, limits, times=t)
    step = np.abs(np.diff(res.q, axis=0)).max()
    assert step < 0.01  # [rad] per 1 ms sample: continuous, no jump to another branch
    assert np.all(np.abs(res.q) <= limits.position)


def test_ik_redundancy_resolved_toward_q0(robot, limits, q_start):
    # A single pose reachable with many elbow angles: the solution starts from and stays near q0.
    M = robot.fk(q_start)
    res = solve_ik_path(robot, M.translation[None], M.rotation[None], q_start, limits)
    assert np.abs(res.q[0] - q_start).max() < 1e-6


def test_unreachable_pose_names_the_sample(robot, limits, q_start):
    t, _, pos, rot = _path(robot, q_start, n=200)
    pos = pos.copy()
    pos[150:] += np.array([2.0, 0.0, 0.0])  # 2 m further out: beyond reach
    with pytest.raises(IkError) as exc:
        solve_ik_path(robot, pos, rot, q_start, limits, times=t)
    assert exc.value.index == 150
    assert exc.value.position_error > 0.5
    assert "pose 150" in str(exc.value)
