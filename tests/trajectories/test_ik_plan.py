"""The whole-path arm-angle plan: plans along fast paths, and the fallback that solves fast FK-built paths the local
redundancy resolution could not."""

import numpy as np
import pytest

from trajectories.arm_angle import ArmGeometry
from trajectories.ik import IkOptions, solve_ik_path
from trajectories.ik_paths import build_suite, verify_joint_path
from trajectories.ik_plan import PlanTargets, best_plan

BOUNDED = IkOptions(nullspace_gain=None, speed_limits=True)


@pytest.mark.heavy
def test_plan_along_a_fast_joint_path_is_exact_and_inside_the_limits(robot, limits):
    path = next(p for p in build_suite(robot, limits, seed=2) if p.name == "joint-c0-v0.9-1ms")
    plan = best_plan(PlanTargets(ArmGeometry.of(robot), path.position, path.rotation, path.t, limits))
    assert plan is not None
    pos, rot = robot.fk_path(plan.q)
    assert np.abs(pos - path.position[plan.indices]).max() < 1e-9
    assert np.abs(rot - path.rotation[plan.indices]).max() < 1e-9
    assert (np.abs(plan.q) <= limits.position).all()
    assert plan.peak_speed <= 1.0


@pytest.mark.slow
def test_fast_paths_the_local_redundancy_could_not_follow_are_solved_through_the_plan(robot, limits):
    """Three FK-built paths (reachable within the limits by construction) on which every start candidate stalled
    on a speed limit ("the path needs A3 at 2.37 rad/s") before the plan existed; the third only through the
    plan's own path, its accelerations 3.5 % above the limit and reported."""
    suites = {seed: {p.name: p for p in build_suite(robot, limits, seed=seed)} for seed in (1, 2, 5)}
    for seed, name in ((1, "singular-wrist-0-5ms"), (2, "joint-c0-v0.9-1ms"), (5, "joint-c5-v0.9-1ms")):
        path = suites[seed][name]
        res = solve_ik_path(robot, path.position, path.rotation, None, limits, BOUNDED, times=path.t)
        check = verify_joint_path(robot, path, res.q, limits)
        assert check.ok(1e-6, 1e-5), name
        assert "arm-angle plan" in res.start
        # accelerations above the limit are never passed off as inside it (the CLI warns on them)
        assert (res.acceleration_relaxed > 0) == (check.acceleration_ratio > 1.0 + 1e-9), name
