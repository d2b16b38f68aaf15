"""Path IK on the suite of `trajectories.ik_paths` (FK-built joint paths through singularities and near limits,
Cartesian lines, circles and figure-eights with tilt and yaw; 1 and 5 ms), as `lbr ik` runs it: the start chosen
by the solver, joint speeds bounded. Side by side with pink (pip `pin-pink`, QP solver `daqp`) on the same paths
in the same run; pink is skipped (figures reported as −1) when it is not installed.

A path counts as solved when the joint path reproduces every pose to ≤ 1e-6 m and ≤ 1e-5 rad with positions and
speeds (backward differences) inside the limits. "Reachable" paths: FK-built ones (reachable by construction)
plus any Cartesian path that some solver in this run solved (a verified witness).
"""

from __future__ import annotations

import time

import numpy as np
from trajectories.start_poses import THESIS_START

PINK_ITERATIONS = 10  # QP steps per pose at most
TIMING_REPEATS = 3  # lbr's timing over the suite: best and median of this many runs
DEBUG = False
POSITION_TOL, ROTATION_TOL = 1e-6, 1e-5  # [m], [rad]


def _pink_solver(robot, limits):
    """A function (path, q_start) → joint path (n, 7) or None, running pink's differential IK per pose."""
    try:
        import pink
        from pink.limits import ConfigurationLimit, VelocityLimit
        from pink.tasks import FrameTask, PostureTask
    except ImportError:
        return None
    import pinocchio as pin

    model = robot.model.copy()
    model.upperPositionLimit = limits.position.copy()
    model.lowerPositionLimit = -limits.position
    model.velocityLimit = limits.velocity.copy()
    pink_limits = [ConfigurationLimit(model), VelocityLimit(model)]

    def solve(path, q_start):
        config = pink.Configuration(model, model.createData(), np.clip(q_start, -limits.position, limits.position))
        task = FrameTask("tcp", position_cost=1.0, orientation_cost=1.0)
        posture = PostureTask(cost=1e-6)  # small: a larger posture cost biases the pose by ~1e-6 m
        posture.set_target(config.q.copy())
        out = np.empty((len(path.t), 7))
        dt = path.dt
        for k in range(len(path.t)):
            target = pin.SE3(path.rotation[k], path.position[k])
            task.set_target(target)
            for _ in range(PINK_ITERATIONS if k else 50 * PINK_ITERATIONS):  # the first pose from afar
                err = target.actInv(config.get_transform_frame_to_world("tcp"))
                if (
                    np.linalg.norm(err.translation) <= POSITION_TOL * 0.1
                    and np.linalg.norm(pin.log3(err.rotation)) <= ROTATION_TOL * 0.1
                ):
                    break
                step, v = (dt if k else 0.05), None  # [s] the first pose is a plain IK: no need to creep
                for _ in range(4):  # daqp sometimes reports an infeasible step: retry with shorter ones
                    try:
                        v = pink.solve_ik(config, [task, posture], step, solver="daqp", limits=pink_limits)
                        break
                    except Exception as exc:  # pink's NoSolutionFound
                        if DEBUG:
                            print(k, repr(exc))
                        step *= 0.5
                if v is None:
                    return None
                config.integrate_inplace(v, step)
            err = target.actInv(config.get_transform_frame_to_world("tcp"))
            if np.linalg.norm(err.translation) > 1e-3:  # lost the path: stop early
                return None
            out[k] = config.q
        return out

    return solve


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    """The suite pinned to one core (the issue's goal is per core), the process's cores restored afterwards."""
    import os

    cores = os.sched_getaffinity(0) if hasattr(os, "sched_getaffinity") else None
    if cores:
        os.sched_setaffinity(0, {min(cores)})
    try:
        return _run(quick)
    finally:
        if cores:
            os.sched_setaffinity(0, cores)


def _run(quick: bool) -> list[tuple[str, float, str]]:
    from dataclasses import replace

    from trajectories.errors import IkError
    from trajectories.ik import IkOptions, solve_ik_path
    from trajectories.ik_paths import build_suite, verify_joint_path
    from trajectories.limits import default_limits
    from trajectories.robot import Robot

    robot = Robot()
    limits = default_limits()
    suite = build_suite(robot, limits, quick=quick)
    options = IkOptions(nullspace_gain=None, speed_limits=True)
    pink_solve = _pink_solver(robot, limits)
    ok_lbr, ok_pink, witness, lbr_paths = [], [], [], []
    lbr_time = lbr_poses = pink_time = pink_poses = 0.0
    lbr_over_speed = pink_over_speed = lbr_over_acc = pink_over_acc = 0
    worst_p = worst_r = 0.0
    failures = []
    for path in suite:
        t0 = time.perf_counter()
        try:
            res = solve_ik_path(robot, path.position, path.rotation, None, limits, options, times=path.t)
            q_lbr = res.q
        except IkError as exc:
            q_lbr = None
            failures.append(f"{path.name}: {exc}")
        lbr_time += time.perf_counter() - t0
        lbr_paths.append(q_lbr)
        lbr_poses += len(path.t)
        good = False
        if q_lbr is not None:
            check = verify_joint_path(robot, path, q_lbr, limits)
            good = check.ok(POSITION_TOL, ROTATION_TOL)
            lbr_over_speed += check.velocity_ratio > 1.0 + 1e-6
            lbr_over_acc += good and check.acceleration_ratio > 1.0 + 1e-6
            worst_p, worst_r = max(worst_p, check.position_error), max(worst_r, check.rotation_error)
        ok_lbr.append(good)
        pink_good = False
        if pink_solve is not None:
            if path.witness is not None:
                start = path.witness[0]
            elif q_lbr is not None:
                start = q_lbr[0]
            else:
                start = np.array(THESIS_START)
            t0 = time.perf_counter()
            q_pink = pink_solve(path, start)
            pink_time += time.perf_counter() - t0
            pink_poses += len(path.t)
            if q_pink is not None:
                check = verify_joint_path(robot, path, q_pink, limits)
                pink_good = check.ok(POSITION_TOL, ROTATION_TOL)
                pink_over_speed += check.velocity_ratio > 1.0 + 1e-6
                pink_over_acc += pink_good and check.acceleration_ratio > 1.0 + 1e-6
        ok_pink.append(pink_good)
        witness.append(path.witness is not None or good or pink_good)
    # `lbr ik --smooth` on the solved paths above the acceleration limit: the peak acceleration ratio before → after
    smooth = replace(options, smooth=True)
    smoothed = []
    for path, q in zip(suite, lbr_paths):
        if q is None:
            continue
        before = verify_joint_path(robot, path, q, limits)
        if not before.ok(POSITION_TOL, ROTATION_TOL) or before.acceleration_ratio <= 1.0 + 1e-6:
            continue
        res = solve_ik_path(robot, path.position, path.rotation, None, limits, smooth, times=path.t)
        after = verify_joint_path(robot, path, res.q, limits)
        assert after.ok(POSITION_TOL, ROTATION_TOL)
        smoothed.append((before.acceleration_ratio, after.acceleration_ratio))
    if not quick:
        for b, a in smoothed:
            print(f"   --smooth: peak acceleration {b:.2f} → {a:.2f} of the limit")
    # the suite's timing again (results already checked above): machine noise on a shared VM is ±10 %
    runs = [lbr_time]
    for _ in range(0 if quick else TIMING_REPEATS - 1):
        t0 = time.perf_counter()
        for path in suite:
            try:
                solve_ik_path(robot, path.position, path.rotation, None, limits, options, times=path.t)
            except IkError:
                pass
        runs.append(time.perf_counter() - t0)
    reachable = int(sum(witness))
    if not quick:
        for line in failures:
            print("   lbr ik failed:", line)
    has_pink = pink_solve is not None
    return [
        ("IK suite: paths", len(suite), "paths"),
        ("IK suite: reachable (FK-built or a verified witness)", reachable, "paths"),
        ("IK suite: lbr ik solved (≤1e-6 m, ≤1e-5 rad, speeds in limits)", int(sum(ok_lbr)), "paths"),
        ("IK suite: lbr ik solved of the reachable", int(sum(o for o, w in zip(ok_lbr, witness) if w)), "paths"),
        ("IK suite: lbr ik outputs above the speed limit", lbr_over_speed, "paths"),
        ("IK suite: lbr ik solved paths above the acceleration limit", lbr_over_acc, "paths"),
        ("IK suite: lbr ik throughput on one core, best run (auto start included)", lbr_poses / min(runs), "poses/s"),
        ("IK suite: lbr ik throughput on one core, median run", lbr_poses / float(np.median(runs)), "poses/s"),
        ("IK suite: lbr ik worst position error", worst_p, "m"),
        ("IK suite: lbr ik worst rotation error", worst_r, "rad"),
        ("IK suite: --smooth, paths above the acceleration limit retried", len(smoothed), "paths"),
        (
            "IK suite: --smooth, of those with a lower peak acceleration",
            sum(a < b - 1e-9 for b, a in smoothed),
            "paths",
        ),
        ("IK suite: pink solved", int(sum(ok_pink)) if has_pink else -1, "paths"),
        ("IK suite: pink outputs above the speed limit", pink_over_speed if has_pink else -1, "paths"),
        ("IK suite: pink solved paths above the acceleration limit", pink_over_acc if has_pink else -1, "paths"),
        ("IK suite: pink throughput on one core", pink_poses / pink_time if has_pink and pink_time else -1, "poses/s"),
    ]
