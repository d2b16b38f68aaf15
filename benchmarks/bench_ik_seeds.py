"""Path IK on the FK-built paths of five more suites (`build_suite(seed=1…5)`: other random joint paths, other
centres for the singular and limit paths; 50 each, 250 in all), as `lbr ik` runs them. Every one is reachable
within the position and speed limits by construction, so each failure is lbr's. Counts a path solved as
`ik_paths` does (≤ 1e-6 m, ≤ 1e-5 rad, speeds inside the limits) and lists the failures.
"""

from __future__ import annotations

import time

SEEDS = (1, 2, 3, 4, 5)


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    from trajectories.errors import IkError
    from trajectories.ik import IkOptions, solve_ik_path
    from trajectories.ik_paths import build_suite, verify_joint_path
    from trajectories.limits import default_limits
    from trajectories.robot import Robot

    robot = Robot()
    limits = default_limits()
    options = IkOptions(nullspace_gain=None, speed_limits=True)
    solved = total = over_acc = 0
    poses = elapsed = 0.0
    failures = []
    for seed in SEEDS[:1] if quick else SEEDS:
        paths = [p for p in build_suite(robot, limits, seed=seed) if p.witness is not None]
        for path in paths[::4] if quick else paths:
            total += 1
            t0 = time.perf_counter()
            try:
                res = solve_ik_path(robot, path.position, path.rotation, None, limits, options, times=path.t)
            except IkError as exc:
                failures.append(f"{path.name} (seed {seed}): {exc}")
                continue
            finally:
                elapsed += time.perf_counter() - t0
                poses += len(path.t)
            check = verify_joint_path(robot, path, res.q, limits)
            if check.ok(1e-6, 1e-5):
                solved += 1
                over_acc += check.acceleration_ratio > 1.0 + 1e-6
            else:
                failures.append(f"{path.name} (seed {seed}): returned a path off tolerance or limits")
    for line in failures:
        print("   lbr ik failed:", line)
    return [
        ("IK, 5 more suites: FK-built (reachable) paths", total, "paths"),
        ("IK, 5 more suites: solved (≤1e-6 m, ≤1e-5 rad, speeds in limits)", solved, "paths"),
        ("IK, 5 more suites: solved paths above the acceleration limit", over_acc, "paths"),
        ("IK, 5 more suites: throughput (arm-angle plans included)", poses / elapsed if elapsed else 0.0, "poses/s"),
    ]
