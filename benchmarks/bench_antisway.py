"""Anti-sway planning speed: the 4-segment default layout, plan + IK + check, and the nonlinear prediction.

``auto tol 0.1`` is the default (robust to ±10 % string length), ``tol 0`` the nominal-length design."""

from __future__ import annotations

import time

import numpy as np


def _best(fn, repeats: int) -> tuple[float, object]:
    best, out = np.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    from lbrcli.commands.check import run_check
    from lbrcli.antisway import ANTISWAY_Q0, _joints_of, predict_sway
    from lbrcli.parsing import parse_joint_vector
    from planners.antisway import DEFAULT_LAYOUT, DEFAULT_Z, AntiSwayOptions, plan_layout
    from trajectories.limits import default_limits
    from trajectories.robot import Robot

    robot, lim = Robot(), default_limits()
    q0 = parse_joint_vector(ANTISWAY_Q0, "--q0")
    pts = np.array(DEFAULT_LAYOUT)
    repeats = 1 if quick else 3
    rows = []
    plan_layout(pts, 0.25, 2.0, DEFAULT_Z, 0.005, AntiSwayOptions())  # warm-up (scipy imports)
    configs = (
        ("auto", 0.1, 0.005),
        ("auto", 0.0, 0.005),
        ("auto", 0.2, 0.005),
        ("accel", 0.0, 0.005),
        ("auto", 0.1, 0.001),
    )
    for shaper, tol, dt in configs:
        opts = AntiSwayOptions(shaper=shaper, length_tolerance=tol)
        label = f"{shaper}{f' tol {tol:g}' if shaper != 'accel' else ''} dt {dt * 1e3:g} ms"

        def pipeline():
            plan = plan_layout(pts, 0.25, 2.0, DEFAULT_Z, dt, opts)
            joints, _ = _joints_of(plan, robot, q0, lim)
            report = run_check(joints, lim, 0.0, False, False, robot)
            return plan, joints, report

        t_plan, _ = _best(lambda: plan_layout(pts, 0.25, 2.0, DEFAULT_Z, dt, opts), repeats)
        t_all, (plan, joints, report) = _best(pipeline, repeats)
        t_pred, run_ = _best(lambda: predict_sway(joints, robot, 0.25, plan.stop_time), repeats)
        residual = {  # [deg] after the last stop, for the string e % off
            e: float(np.degrees(r.theta[r.t >= plan.stop_time].max()))
            for e, r in ((e, predict_sway(joints, robot, 0.25 * (1 + e), plan.stop_time))
                         for e in (-0.1, -0.05, 0.0, 0.05, 0.1))
        }  # fmt: skip
        worst = max(residual[-0.1], residual[0.1])
        rows += [
            (f"anti-sway {label}: plan (4 segments)", t_plan, "s"),
            (f"anti-sway {label}: plan + IK + check ({len(joints)} samples)", t_all, "s"),
            (f"anti-sway {label}: nonlinear prediction", t_pred, "s"),
            (f"anti-sway {label}: moving time", plan.stop_time, "s"),
            (
                f"anti-sway {label}: predicted residual sway",
                float(np.degrees(run_.theta[run_.t >= plan.stop_time].max())),
                "deg",
            ),
            (f"anti-sway {label}: residual with the string 10 % off (worst)", worst, "deg"),
            (
                f"anti-sway {label}: worst residual over the string ±10 % (−10, −5, 0, +5, +10 %)",
                max(residual.values()),
                "deg",
            ),
        ]
        assert report.ok
    return rows


if __name__ == "__main__":
    for name, value, unit in run():
        print(f"{name}: {value:.4g} {unit}")
