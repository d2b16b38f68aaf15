"""Swing-up planning time (energy shaping, thesis example; fast method, 115° with l = 0.25 m) and outcomes."""

from __future__ import annotations

import math
import time


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    from planners.swingup import SwingUpRequest, plan_swing_up
    from planners.swingup_energy import EnergyParams, plan_energy
    from planners.swingup_fast import FastParams, FastProblem, evaluate
    from planners.swingup_plan import TaskBounds
    from trajectories.limits import default_limits
    from trajectories.robot import Robot

    robot, limits = Robot(), default_limits()
    out: list[tuple[str, float, str]] = []
    td = math.radians(115)

    t0 = time.perf_counter()
    plan_energy(EnergyParams(0.25, 0.0139, td, theta0=0.1), TaskBounds(0.16, 0.55, 15.0))
    out.append(("energy: thesis law integration (47 s of swing)", time.perf_counter() - t0, "s"))

    problem = FastProblem(0.25, td, TaskBounds(0.95, 4.7, 98.0))
    n = 20 if quick else 100
    t0 = time.perf_counter()
    for _ in range(n):
        evaluate(problem, FastParams())
    out.append(("fast: one candidate (policy simulation, 5 ms step)", (time.perf_counter() - t0) / n * 1e3, "ms"))

    cases = [("energy", 0.005, 0.1)] + ([] if quick else [("fast", 0.005, 0.0), ("fast", 0.001, 0.0)])
    if quick:
        cases.append(("fast", 0.005, 0.0))
    for method, dt, theta0 in cases:
        t0 = time.perf_counter()
        res = plan_swing_up(SwingUpRequest(0.25, 0.0139, td, method=method, dt=dt, theta0=theta0), robot, limits)
        elapsed = time.perf_counter() - t0
        f = res.figures()
        tag = f"{method} dt={dt * 1e3:g} ms"
        out += [
            (f"{tag}: plan + IK + check + verification", elapsed, "s"),
            (f"{tag}: verified max θ", f["max_theta_deg"], "deg"),
            (f"{tag}: claimed − verified max θ", f["claimed"]["max_theta_deg"] - f["max_theta_deg"], "deg"),
            (f"{tag}: time to θ_d (verified)", f["t_theta_d_s"] if f["t_theta_d_s"] is not None else math.nan, "s"),
            (f"{tag}: time to θ_d − tolerance (verified)", f["t_reach_s"] if f["t_reach_s"] else math.nan, "s"),
            (f"{tag}: min tension / mass", f["min_tension_margin"], "m/s^2"),
            (f"{tag}: peak joint velocity / limit", f["max_ratio"]["velocity"], "-"),
            (f"{tag}: peak joint acceleration / limit", f["max_ratio"]["acceleration"], "-"),
            (f"{tag}: peak joint jerk / limit", f["max_ratio"]["jerk"], "-"),
        ]
    return out


if __name__ == "__main__":
    for name, value, unit in run():
        print(f"{name:60s} {value:12.4g} {unit}")
