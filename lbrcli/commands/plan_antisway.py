"""`lbr plan anti-sway`: carry a ball on a string through turning points and stop with no swing left.

The pivot path comes from ``planners.antisway`` (thesis baseline ``accel`` or the input shapers); IK with the
flange pointing straight down, the limit check of ``lbr check``, and the predicted sway of the nonlinear
spherical pendulum driven by the pivot path that the joint CSV really produces (FK of the written joints).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Callable, Optional, Sequence

import typer

from ..options import DEFAULT_FLANGE, FlangeOpt, JsonOpt, LimitsOpt, ToolOpt

DEFAULT_DT = 0.005  # [s] the FRI send period the thesis used (§5.3); 0.001 for a 1 ms FRI session
ANTISWAY_Q0 = "0,0.6,0,-1.4,0,1.14,0"  # [rad] elbow up, A4 negative, flange down over x ≈ 0.59 m, y = 0
SETTLE_PERIODS = 3.0  # simulated rest after the last stop [periods]
DEFAULT_POINTS_TEXT = "0.40,-0.30;0.62,-0.30;0.62,0.05;0.45,0.05;0.45,0.30"  # = planners.antisway.DEFAULT_LAYOUT
PREDICTION_COLUMNS = ("t", "theta", "phi", "theta_x", "theta_y")


def flange_down_rotation():
    """Flange z along −base z, flange x along −base x (the iiwa's natural wrist pose over +x)."""
    import numpy as np

    return np.diag([-1.0, 1.0, -1.0])


@dataclass(frozen=True)
class AntiSwayResult:
    """Everything a plan produced: pivot plan, joints, IK errors, check report, predicted sway."""

    plan: Any  # planners.antisway.AntiSwayPlan
    joints: Any  # trajectories.trajectory.JointTrajectory
    ik_error: float  # max TCP position error [m]
    report: Any  # trajectories.check.CheckReport
    run: Any  # planners.pendulum.PendulumRun of the prediction
    stop_time: float  # [s]
    baseline_duration: float  # [s] moving time of the thesis baseline on the same layout and dt
    timings: dict  # compute times [s]

    def figures(self) -> dict:
        """The JSON figures of the plan."""
        import numpy as np

        from planners.pendulum import natural_period

        after = self.run.t >= self.stop_time - 1e-12
        theta = self.run.theta
        ratios = self.report.ratios()
        plan = self.plan
        return {
            "duration_s": float(self.joints.duration),
            "motion_s": float(self.stop_time),
            "baseline_motion_s": self.baseline_duration,
            "peak_sway_deg": math.degrees(float(theta.max())),
            "residual_sway_deg": math.degrees(float(theta[after].max())),
            "max_ik_error_m": self.ik_error,
            "limits_ok": bool(self.report.ok),
            "jerk_ratio": float(ratios["jerk"].max()),
            "jerk_enforced": bool(self.report.jerk_enforced),
            "max_ratio": {k: float(v.max()) for k, v in ratios.items()},
            "shaper": plan.shaper,
            "string_length_m": plan.string_length,
            "period_s": natural_period(plan.string_length),
            "a_max_m_s2": plan.a_max,
            "peak_pivot_accel_m_s2": float(np.linalg.norm(plan.acceleration(), axis=1).max()),
            "samples": len(self.joints),
            "dt_s": plan.dt,
            "segments": [
                {
                    "index": s.index,
                    "from": [float(x) for x in s.start],
                    "to": [float(x) for x in s.end],
                    "length_m": s.length,
                    "design": s.design,
                    "period_s": s.period,
                    "accel_m_s2": s.accel,
                    "duration_s": s.duration,
                }
                for s in plan.segments
            ],
            "violations": [v.describe() for v in self.report.failing],
            "compute_s": self.timings,
        }


def _joints_of(plan, robot, q0, lim, progress=None):
    """IK of the pivot plan with the flange pointing down → (JointTrajectory, max position error [m])."""
    import numpy as np

    from trajectories.ik import solve_ik_path
    from trajectories.trajectory import JointTrajectory

    rot = np.broadcast_to(flange_down_rotation(), (len(plan.t), 3, 3))
    res = solve_ik_path(robot, plan.position, rot, q0, lim, times=plan.t, progress=progress)
    return JointTrajectory(t=plan.t, q=res.q), res.max_position_error


def predict_sway(joints, robot, string_length: float, stop_time: float, settle_periods: float = SETTLE_PERIODS):
    """Nonlinear spherical pendulum driven by the TCP path that the joint trajectory produces (FK)."""
    from planners.antisway import simulate_path

    pos, _ = robot.fk_path(joints.q)
    return simulate_path(joints.t, pos, string_length, stop_time, settle_periods)


def _failing_segments(plan, report) -> list[int]:
    return sorted({plan.segment_of(v.t) for v in report.failing})


def _largest_fitting_accel(points, length, accels, z, dt, options, segment, robot, q0, lim, margin, jerk):
    """Bisection on the a_max of one segment (others unchanged) until its samples pass the check [m/s²]."""
    import numpy as np

    from planners.antisway import plan_layout
    from trajectories.errors import IkError

    from .check import run_check

    def fits(a: float) -> bool:
        acc = np.array(accels, dtype=float)
        acc[segment - 1] = a
        plan = plan_layout(points, length, acc, z, dt, options)
        try:
            joints, _ = _joints_of(plan, robot, q0, lim)
        except IkError:
            return False
        rep = run_check(joints, lim, margin, jerk, False, robot)
        return segment not in _failing_segments(plan, rep)

    hi = float(accels[segment - 1])
    lo = 0.02 * hi
    if not fits(lo):
        return 0.0
    while hi - lo > 0.005 * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if fits(mid) else (lo, mid)
    return lo


def plan_anti_sway(
    points: Sequence[Sequence[float]],
    length: float,
    a_max: float,
    z: float | None = None,
    shaper: str = "auto",
    dt: float = DEFAULT_DT,
    *,
    flange: str = DEFAULT_FLANGE,
    tool: str | None = None,
    q0: Sequence[float] | None = None,
    limits=None,
    margin: float = 0.0,
    jerk: bool = False,
    j_max: float | None = None,
    v_max: float = math.inf,
    length_tolerance: float = 0.0,
    tune: bool = True,
    progress: Callable[[int], None] | None = None,
) -> AntiSwayResult:
    """Plan, solve IK, check and predict an anti-sway move; raise PlanningError if a_max does not fit.

    points (n, 2) [m] in the base frame: start then turning points; length [m] from the pivot (flange origin
    + tool) to the ball centre; a_max [m/s²]; z [m] flange height; dt [s] joint sample step.
    """
    import numpy as np

    from planners.antisway import DEFAULT_Z, AntiSwayOptions, plan_layout
    from trajectories.errors import OptionError, PlanningError
    from trajectories.limits import load_limits

    from ..options import make_robot
    from ..parsing import parse_joint_vector
    from .check import run_check

    pts = np.asarray(points, dtype=float)
    z = DEFAULT_Z if z is None else float(z)
    _validate(pts, length, a_max, dt, shaper, length_tolerance, margin)
    options = AntiSwayOptions(
        shaper=shaper, j_max=None if j_max is None else float(j_max), v_max=float(v_max),
        length_tolerance=float(length_tolerance), tune=tune,
    )
    lim = limits if limits is not None else load_limits(None)
    robot = make_robot(flange, tool)
    q_ref = parse_joint_vector(ANTISWAY_Q0, "--q0") if q0 is None else np.asarray(q0, dtype=float)
    if q_ref.shape != (7,):
        raise OptionError("--q0: expected 7 joint angles")

    timings = {}
    t0 = time.perf_counter()
    plan = plan_layout(pts, length, a_max, z, dt, options)
    timings["plan"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    joints, ik_error = _joints_of(plan, robot, q_ref, lim, progress)
    timings["ik"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    report = run_check(joints, lim, margin, jerk, False, robot)
    timings["check"] = time.perf_counter() - t0
    if not report.ok:
        failing = _failing_segments(plan, report)
        seg = failing[0]
        accels = [a_max] * len(plan.segments)
        best = _largest_fitting_accel(pts, length, accels, z, dt, options, seg, robot, q_ref, lim, margin, jerk)
        s = plan.segments[seg - 1]
        first = next(v for v in report.failing if plan.segment_of(v.t) == seg)
        fit = (
            f"the largest a_max that fits is {math.floor(best * 100) / 100:.2f} m/s²"
            if best > 0
            else "no a_max fits (the segment is outside the joint limits at any acceleration)"
        )
        others = f" (segments {', '.join(map(str, failing))} exceed the limits)" if len(failing) > 1 else ""
        raise PlanningError(
            f"a_max = {a_max:g} m/s² does not fit the joint limits at segment {seg}{others} "
            f"({s.start[0]:.3f},{s.start[1]:.3f})→({s.end[0]:.3f},{s.end[1]:.3f}): {first.describe()}; {fit} "
            f"(an anti-sway plan is never re-timed)"
        )
    t0 = time.perf_counter()
    run = predict_sway(joints, robot, length, plan.stop_time)
    timings["prediction"] = time.perf_counter() - t0
    baseline = plan_layout(pts, length, a_max, z, dt, AntiSwayOptions(shaper="accel")).stop_time
    return AntiSwayResult(plan, joints, ik_error, report, run, plan.stop_time, baseline, timings)


def _validate(pts, length, a_max, dt, shaper, tol, margin) -> None:
    import numpy as np

    from planners.antisway import SHAPERS
    from trajectories.errors import OptionError

    from ..options import check_margin

    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 2:
        raise OptionError("--points: need a start and at least one turning point 'x0,y0;x1,y1;...'")
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    if np.any(seg < 1e-6):
        k = int(np.argmin(seg)) + 1
        raise OptionError(f"--points: segment {k} has zero length (points {k - 1} and {k} coincide)")
    if not (math.isfinite(length) and 0.01 <= length <= 3.0):
        raise OptionError(f"--length must be a string length in [0.01, 3] m, got {length:g}")
    if not (math.isfinite(a_max) and 0 < a_max <= 20.0):
        raise OptionError(f"--a-max must be in (0, 20] m/s², got {a_max:g}")
    if not (math.isfinite(dt) and 1e-4 <= dt <= 0.05):
        raise OptionError(f"--dt must be in [0.0001, 0.05] s, got {dt:g}")
    if shaper not in SHAPERS:
        raise OptionError(f"--shaper: unknown {shaper!r}; choose one of {', '.join(SHAPERS)}")
    if not (0.0 <= tol < 0.9):
        raise OptionError(f"--length-tolerance must be in [0, 0.9), got {tol:g}")
    check_margin(margin)


def write_outputs(result: AntiSwayResult, out: Path, task_out: Path | None = None, prediction: Path | None = None,
                  plot: Path | None = None) -> None:
    """Joint CSV, and optionally the pivot path (task CSV), the predicted sway CSV and the PNG."""
    import numpy as np

    from trajectories.csvio import write_joint_csv, write_table, write_task_csv
    from trajectories.poses import quaternions_from_matrices
    from trajectories.trajectory import TaskTrajectory

    write_joint_csv(out, result.joints)
    if task_out is not None:
        plan = result.plan
        quat = quaternions_from_matrices(np.broadcast_to(flange_down_rotation(), (len(plan.t), 3, 3)))
        write_task_csv(task_out, TaskTrajectory(t=plan.t, position=plan.position, quaternion=quat))
    if prediction is not None:
        r = result.run
        data = np.column_stack([r.t, r.theta, r.phi, r.theta_x, r.theta_y])
        write_table(prediction, PREDICTION_COLUMNS, data, fmt=["%.6f"] + ["%.9g"] * 4)
    if plot is not None:
        from ..plots.antisway import plot_antisway

        plot_antisway(result, plot)


def plan_anti_sway_files(
    points: Sequence[Sequence[float]],
    length: float,
    a_max: float,
    z: float | None,
    shaper: str,
    dt: float,
    out: Path,
    task_out: Path | None = None,
    prediction: Path | None = None,
    plot: Path | None = None,
    **kwargs: Any,
) -> dict:
    """In-process `lbr plan anti-sway`: plan, write the files, return the JSON figures."""
    result = plan_anti_sway(points, length, a_max, z, shaper, dt, **kwargs)
    write_outputs(result, Path(out), task_out, prediction, plot)
    figs = result.figures()
    figs.update({"out": str(out), "task_out": str(task_out) if task_out else None,
                 "prediction": str(prediction) if prediction else None, "plot": str(plot) if plot else None})
    return figs


def plan_anti_sway_command(
    out: Annotated[Path, typer.Option("-o", "--out", help="Joint trajectory to write: t,q1..q7 \\[s, rad].")],
    length: Annotated[float, typer.Option("--length", help="String length from the pivot (flange + --tool) to the ball centre \\[m].")],
    a_max: Annotated[float, typer.Option("--a-max", help="Maximum pivot acceleration \\[m/s²].")],
    points: Annotated[
        str,
        typer.Option("--points", help="Start and turning points 'x0,y0;x1,y1;...' in the base frame \\[m]; default: a thesis-like layout."),
    ] = DEFAULT_POINTS_TEXT,
    z: Annotated[Optional[float], typer.Option("--z", help="Flange (pivot) height \\[m]; default 0.45.")] = None,
    shaper: Annotated[
        str,
        typer.Option("--shaper", help="accel (thesis baseline), auto (default: fastest zero-sway per segment), box, zv, zvd, zvdd, mzv, ei, ei2, box-zv, box-zvd, box-ei."),
    ] = "auto",
    dt: Annotated[float, typer.Option("--dt", help="Joint sample step \\[s] (thesis FRI period 0.005).")] = DEFAULT_DT,
    length_tolerance: Annotated[
        float, typer.Option("--length-tolerance", help="Relative string-length uncertainty (0.2 = ±20 %): auto picks robust shapers.")
    ] = 0.0,
    j_max: Annotated[Optional[float], typer.Option("--j-max", help="Pivot jerk limit of the shaped profiles \\[m/s³]; default a_max/(0.04·T): jerk ramps of 4 % of the period.")] = None,
    v_max: Annotated[Optional[float], typer.Option("--v-max", help="Pivot speed limit \\[m/s]; default none.")] = None,
    no_tune: Annotated[bool, typer.Option("--no-tune", help="Skip the per-segment nonlinear tuning of the period.")] = False,
    task_out: Annotated[Optional[Path], typer.Option("--task-out", help="Planned pivot path t,x,y,z,qw,qx,qy,qz \\[s, m].")] = None,
    prediction: Annotated[Optional[Path], typer.Option("--prediction", help="Predicted sway t,theta,phi,theta_x,theta_y \\[s, rad].")] = None,
    plot: Annotated[Optional[Path], typer.Option("--plot", help="PNG: top view, pivot acceleration, predicted sway.")] = None,
    q0: Annotated[Optional[str], typer.Option("--q0", help=f"IK reference configuration (7 angles, deg/rad); default {ANTISWAY_Q0}.")] = None,
    margin: Annotated[float, typer.Option("--margin", help="Check against the limits × (1 − margin).")] = 0.0,
    jerk: Annotated[bool, typer.Option("--jerk", help="Fail on joint jerk too (always reported).")] = False,
    flange: FlangeOpt = DEFAULT_FLANGE,
    tool: ToolOpt = None,
    limits: LimitsOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Anti-sway crane move through turning points, stopping at each with no swing left.

    The flange points straight down at height --z; the ball hangs --length below the pivot. Exit 1 naming the
    segment and the largest a_max that fits if the joint limits are exceeded (the plan is never re-timed).
    """
    from ..console import Reporter
    from ..options import limits_from
    from ..parsing import parse_joint_vector, parse_points

    rep = Reporter(json_out)
    pts = parse_points(points, "--points")
    q_ref = parse_joint_vector(q0, "--q0") if q0 is not None else None
    lim = limits_from(limits)
    with rep.progress("IK", None) as update:
        figs = plan_anti_sway_files(
            pts, length, a_max, z, shaper, dt, out, task_out, prediction, plot, flange=flange, tool=tool, q0=q_ref,
            limits=lim, margin=margin, jerk=jerk, j_max=j_max, v_max=math.inf if v_max is None else v_max,
            length_tolerance=length_tolerance, tune=not no_tune, progress=update,
        )
    designs = ", ".join(f"{s['index']}:{s['design']}" for s in figs["segments"])
    rep.print(
        f"wrote {out}: {figs['samples']} samples, {figs['duration_s']:.3f} s (moving {figs['motion_s']:.3f} s; "
        f"thesis baseline {figs['baseline_motion_s']:.3f} s); shaper {figs['shaper']} [{designs}]"
    )
    rep.print(
        f"predicted sway: peak {figs['peak_sway_deg']:.2f}°, residual after the last stop "
        f"{figs['residual_sway_deg']:.3f}°; max IK error {figs['max_ik_error_m']:.1e} m"
    )
    jr = figs["jerk_ratio"]
    rep.print(
        f"limits: {'OK' if figs['limits_ok'] else 'FAILED'}; peak joint jerk {jr * 100:.0f} % of the limit"
        + ("" if jr <= 1 or jerk else " (not enforced; --jerk to fail on it)")
    )
    for name in ("task_out", "prediction", "plot"):
        if figs[name] is not None:
            rep.print(f"{name.replace('_', ' ')}: {figs[name]}")
    rep.emit(figs)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    groups["plan"].command("anti-sway")(plan_anti_sway_command)
