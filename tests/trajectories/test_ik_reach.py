"""What no redundancy can give, exact at every sample: poses beyond reach or the position limits at every arm angle
of every branch, and A4's speed (set by the poses alone) — judged against the closed form on dense grids."""

import numpy as np
import pytest

from trajectories.arm_angle import BRANCHES, ArmGeometry, inverse
from trajectories.errors import IkError
from trajectories.ik import IkOptions, solve_ik_path
from trajectories.ik_paths import build_suite
from trajectories.ik_reach import first_unreachable, pose_feasibility
from trajectories.robot import Flange, Robot, RobotConfig

BOUNDED = IkOptions(nullspace_gain=None, speed_limits=True)
MARGIN = 1e-4  # [rad] the IK's distance from the position limits


def _grid_feasible(geometry, pos, rot, bound, step_deg=0.05):
    """The judge: some configuration of the closed form on a grid of arm angles × 8 branches inside ``bound``, for
    one pose (pos (3,), rot (3, 3)) or several (pos (m, 3), rot (m, 3, 3))."""
    psi = np.radians(np.arange(-180.0, 180.0, step_deg))
    if pos.ndim == 1:
        q, reach = inverse(geometry, rot, pos, psi[None, :], BRANCHES[:, None, :])
        return bool((reach & (np.abs(q) <= bound).all(axis=-1)).any())
    q, reach = inverse(geometry, rot[:, None, None], pos[:, None, None], psi[None, None, :], BRANCHES[None, :, None, :])
    return (reach & (np.abs(q) <= bound).all(axis=-1)).any(axis=(1, 2))


@pytest.mark.heavy
@pytest.mark.parametrize("config", [RobotConfig(), RobotConfig(flange=Flange.STANDARD, tool=(0.02, -0.01, 0.12))])
def test_feasibility_of_random_poses_agrees_with_a_dense_grid(config, limits):
    """Poses of configurations up to 1.25× the limits (about a third beyond them at every arm angle)."""
    robot = Robot(config)
    geometry = ArmGeometry.of(robot)
    q = np.random.default_rng(11).uniform(-1.25, 1.25, (96, 7)) * limits.position
    pos, rot = robot.fk_path(q)
    bound = limits.position - MARGIN
    ok, _, _ = pose_feasibility(geometry, pos, rot, bound)
    judge = np.concatenate([_grid_feasible(geometry, pos[i : i + 16], rot[i : i + 16], bound, 0.25)
                            for i in range(0, len(q), 16)])  # fmt: skip
    assert 0.3 < ok.mean() < 0.9
    assert (ok == judge).all()


@pytest.mark.heavy
def test_the_first_pose_beyond_a_limit_is_exact(robot, limits):
    """A suite circle whose tilted poses leave the reach of A6: the first sample that fits no arm angle is found
    at every sample (the judge agrees on it and on the one before), refused by the IK at that index."""
    geometry = ArmGeometry.of(robot)
    path = next(p for p in build_suite(robot, limits) if p.name == "circle-xy-tilt45-yaw60-smooth-5ms")
    fact = first_unreachable(geometry, path.position, path.rotation, path.t, limits, MARGIN)
    assert fact is not None and fact.reason == "position limit"
    k, bound = fact.index, limits.position - MARGIN
    assert not _grid_feasible(geometry, path.position[k], path.rotation[k], bound, 0.01)
    assert _grid_feasible(geometry, path.position[k - 1], path.rotation[k - 1], bound, 0.01)
    with pytest.raises(IkError) as exc:
        solve_ik_path(robot, path.position, path.rotation, None, limits, BOUNDED, times=path.t)
    assert exc.value.index == k and exc.value.kind == "pose" and exc.value.reason == "position limit"
    assert "at every arm angle of every branch" in str(exc.value)


def test_a4_speed_is_a_fact_of_the_path(robot, limits, q_start):
    """The wrist pulled toward the shoulder faster than A4 can fold: no arm angle helps; refused at the sample
    where the speed A4 needs first exceeds its limit, with or without a start given."""
    dt = 0.005
    t = np.arange(0.0, 1.0 + dt / 2, dt)
    q = np.tile(q_start, (len(t), 1))
    q[:, 3] = q_start[3] - 0.8 * np.clip((t - 0.3) / 0.5, 0.0, 1.0) ** 2  # A4 speeds up to 3.2 rad/s
    pos, rot = robot.fk_path(q)
    speed = np.abs(np.diff(q[:, 3])) / dt
    first = int(np.argmax(speed > limits.velocity[3])) + 1
    for q0 in (None, q_start):
        with pytest.raises(IkError) as exc:
            solve_ik_path(robot, pos, rot, q0, limits, BOUNDED, times=t)
        err = exc.value
        assert (err.index, err.reason, err.joint, err.kind) == (first, "velocity limit", 3, "path")
        assert err.needed == pytest.approx(speed[first - 1], rel=1e-6)


@pytest.mark.heavy
def test_a_short_excursion_missed_by_the_coarse_check_is_found_when_the_solver_stalls(robot, limits):
    """Three samples (3 ms) of a pose beyond A6's limit at every arm angle inside a path that is otherwise easy: the
    check before solving looks at the arm angles every 20 ms and misses them; the solver stalls there and the
    check at every sample names the first of them."""
    geometry = ArmGeometry.of(robot)
    good = robot.fk(np.array([0.0, 0.5, 0.0, -1.3, 0.0, 1.0, 0.0]))
    bad = next(p for p in build_suite(robot, limits) if p.name == "circle-xy-tilt45-yaw60-smooth-1ms")
    t = np.arange(100) * 0.001
    pos = np.tile(good.translation, (100, 1))
    rot = np.tile(good.rotation, (100, 1, 1))
    pos[41:44], rot[41:44] = bad.position[1200], bad.rotation[1200]  # unreachable (its first is pose 1086)
    assert not pose_feasibility(geometry, pos[41:42], rot[41:42], limits.position - MARGIN)[0][0]
    assert first_unreachable(geometry, pos, rot, t, limits, MARGIN, speed=False, stride=20) is None
    assert first_unreachable(geometry, pos, rot, t, limits, MARGIN, speed=False).index == 41
    with pytest.raises(IkError) as exc:
        solve_ik_path(robot, pos, rot, None, limits, IkOptions(nullspace_gain=None), times=t)
    assert exc.value.index == 41 and exc.value.kind == "pose"
