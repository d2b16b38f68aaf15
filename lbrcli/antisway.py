"""The anti-sway pipeline behind `lbr plan anti-sway`: carry a ball on a string through turning points and stop with no
swing left.

The pivot path comes from ``planners.antisway`` (thesis baseline ``accel`` or the input shapers); IK with the
flange pointing straight down, the limit check of ``lbr check``, and the predicted sway of the nonlinear
spherical pendulum driven by the pivot path that the joint CSV really produces (FK of the written joints). The
command (:mod:`lbrcli.commands.plan_antisway`) parses options and prints; this module plans and writes the files.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

from .options import DEFAULT_FLANGE

DEFAULT_DT = 0.005  # [s] the FRI send period the thesis used (§5.3); 0.001 for a 1 ms FRI session
ANTISWAY_Q0 = "0,0.6,0,-1.4,0,1.14,0"  # [rad] elbow up, A4 negative, flange down over x ≈ 0.59 m, y = 0
SETTLE_PERIODS = 3.0  # simulated rest after the last stop [periods]
DEFAULT_POINTS_TEXT = "0.40,-0.30;0.62,-0.30;0.62,0.05;0.45,0.05;0.45,0.30"  # = planners.antisway.DEFAULT_LAYOUT
PREDICTION_COLUMNS = ("t", "theta", "phi", "theta_x", "theta_y")


def flange_down_rotation():
    """Flange z along −base z, flange x along −base x (the iiwa's natural wrist pose over +x)."""
    import numpy as np

    return np.diag([-1.0, 1.0, -1.0])


FALLBACK_DESIGNS = ("robust-slow", "robust-gentle", "box-zvd", "zvd", "ei", "accel")  # tried by auto
GENTLE_STEP, GENTLE_TRIES = 0.85, 6  # robust-gentle: a_max × 0.85 on the failing segments only, up to 6 times
FALLBACK_RESIDUAL = math.radians(0.5)  # a fallback must leave at most this swing across the length band [rad]
DEFAULT_BALL_RADIUS = 0.02  # [m]
Z_RANGE = (-0.5, 1.5)  # [m] flange heights worth planning at (the arm reaches about −0.4..1.3 m)
SETTINGS = "plan_anti_sway"  # the owner of its SettingErrors: ``plan_anti_sway.FIELD`` (a parameter of it)


@dataclass(frozen=True)
class BandPrediction:
    """Predicted swing for string lengths across the tolerance band: runs and their figures [rad]."""

    lengths: tuple[float, ...]  # [m]
    runs: tuple[Any, ...]  # planners.pendulum.PendulumRun per length
    residual: tuple[float, ...]  # largest tilt after the last stop [rad]
    peak: tuple[float, ...]  # largest tilt [rad]
    peak_time: tuple[float, ...]  # [s]
    ball_paths: tuple[Any, ...]  # (n, 3) ball centres [m] per length
    clearance: Any = None  # planners.obstacles.Clearance or None
    dense_lengths: tuple[float, ...] = ()  # [m] a dense sweep across the band (residual and peak only)
    dense_residual: tuple[float, ...] = ()  # [rad]
    dense_peak: tuple[float, ...] = ()  # [rad]

    @property
    def worst_residual(self) -> tuple[float, float]:
        """The largest residual over the band [rad] and its string length [m] (the dense sweep included)."""
        pairs = list(zip(self.residual, self.lengths)) + list(zip(self.dense_residual, self.dense_lengths))
        return max(pairs)

    @property
    def worst_peak(self) -> float:
        """The largest tilt during the move over the band [rad] (the dense sweep included)."""
        return max((*self.peak, *self.dense_peak))


@dataclass(frozen=True)
class AntiSwayResult:
    """Everything a plan produced: pivot plan, joints, IK errors, check report, predicted sway."""

    plan: Any  # planners.antisway.AntiSwayPlan
    joints: Any  # trajectories.trajectory.JointTrajectory
    ik_error: float  # max TCP position error [m]
    report: Any  # trajectories.check.CheckReport
    run: Any  # planners.pendulum.PendulumRun of the prediction at the nominal length
    stop_time: float  # [s]
    baseline_duration: float  # [s] moving time of the thesis baseline on the same layout and dt
    timings: dict  # compute times [s]
    band: BandPrediction | None = None
    obstacles: tuple = ()
    max_sway: float | None = None  # [rad]
    failure: str | None = None  # why the plan cannot be used (limits, sway, obstacle), None if it can
    fallback: dict | None = None  # {"from", "to", "reason"} when another design replaced the requested one

    def figures(self) -> dict:
        """The JSON figures of the plan."""
        import numpy as np

        from planners.pendulum import natural_period

        after = self.run.t >= self.stop_time - 1e-12
        theta = self.run.theta
        ratios = self.report.ratios()
        plan = self.plan
        band = self.band
        figs = {
            "duration_s": float(self.joints.duration),
            "motion_s": float(self.stop_time),
            "baseline_motion_s": self.baseline_duration,
            "time_ratio_to_baseline": float(self.stop_time / self.baseline_duration),
            "peak_sway_deg": math.degrees(float(theta.max())),
            "residual_sway_deg": math.degrees(float(theta[after].max())),
            "length_tolerance": plan.options.length_tolerance,
            "band_lengths_m": list(band.lengths),
            "band_residual_sway_deg": [math.degrees(x) for x in band.residual],
            "band_peak_sway_deg": [math.degrees(x) for x in band.peak],
            "worst_residual_sway_deg": math.degrees(band.worst_residual[0]),
            "worst_residual_length_m": band.worst_residual[1],
            "worst_peak_sway_deg": math.degrees(band.worst_peak),
            "band_dense_lengths": len(band.dense_lengths),
            "max_sway_deg": None if self.max_sway is None else math.degrees(self.max_sway),
            "max_ik_error_m": self.ik_error,
            "limits_ok": bool(self.report.ok),
            "jerk_ratio": float(ratios["jerk"].max()),
            "jerk_enforced": bool(self.report.jerk_enforced),
            "max_ratio": {k: float(v.max()) for k, v in ratios.items()},
            "shaper": plan.shaper,
            "fallback": self.fallback,
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
        c = band.clearance
        figs["obstacles"] = [o.name for o in self.obstacles]
        figs["min_clearance_m"] = None if c is None else c.clearance
        figs["nearest_obstacle"] = (
            None
            if c is None
            else {
                "name": c.obstacle,
                "t_s": c.time,
                "string_length_m": c.length,
                "ball_m": list(c.position),
            }
        )
        return figs


def _joints_of(plan, robot, q0, lim, progress=None):
    """IK of the pivot plan with the flange pointing down → (JointTrajectory, max position error [m]). The plan
    starts and ends at rest, so does the redundancy (the IK brings the self-motion to rest with the pivot)."""
    import numpy as np

    from trajectories.ik import solve_ik_path
    from trajectories.trajectory import JointTrajectory

    t, pos = plan.t, plan.position
    res = solve_ik_path(robot, pos, np.broadcast_to(flange_down_rotation(), (len(t), 3, 3)), q0, lim, times=t,
                        progress=progress)  # fmt: skip
    return JointTrajectory(t=t, q=res.q), res.max_position_error


REACH_STEP = 0.001  # [m] spacing of the layout's check before planning


def check_reach(points, z: float, robot, limits) -> None:
    """Raise PlanningError naming the first turning point or place on a straight segment between them (1 mm
    apart) that the flange cannot reach pointing down at height z [m] inside the joint limits: out of reach, or
    beyond a joint's limit at every arm angle (:mod:`trajectories.ik_reach`)."""
    import numpy as np

    from trajectories.arm_angle import ArmGeometry
    from trajectories.errors import PlanningError
    from trajectories.ik_reach import first_unreachable

    pts = np.asarray(points, dtype=float)
    places, where = [pts[:1]], [(0, 0.0)]  # (segment, fraction along it); segment 0: the start point
    for k in range(1, len(pts)):
        m = max(1, int(np.ceil(np.linalg.norm(pts[k] - pts[k - 1]) / REACH_STEP)))
        s = np.arange(1, m + 1) / m
        places.append(pts[k - 1] + s[:, None] * (pts[k] - pts[k - 1]))
        where += [(k, float(f)) for f in s]
    xy = np.concatenate(places)
    pos = np.column_stack([xy, np.full(len(xy), z)])
    rot = np.broadcast_to(flange_down_rotation(), (len(xy), 3, 3))
    fact = first_unreachable(ArmGeometry.of(robot), pos, rot, None, limits, speed=False)
    if fact is None:
        return
    seg, frac = where[fact.index]
    x, y = xy[fact.index]
    if frac in (0.0, 1.0):
        place = f"point {seg} ({x:.3f}, {y:.3f})"
    else:
        place = (
            f"first at ({x:.3f}, {y:.3f}) on segment {seg} from point {seg - 1} ({pts[seg - 1][0]:.3f}, "
            f"{pts[seg - 1][1]:.3f}) to point {seg} ({pts[seg][0]:.3f}, {pts[seg][1]:.3f})"
        )
    raise PlanningError(
        f"the layout is out of reach at z = {z:g} m with the flange pointing down: {place}: {fact.describe()}; "
        f"move the points or change the flange height z"
    )


def predict_sway(joints, robot, string_length: float, stop_time: float, settle_periods: float = SETTLE_PERIODS):
    """Nonlinear spherical pendulum driven by the TCP path that the joint trajectory produces (FK)."""
    from planners.antisway import simulate_path

    pos, _ = robot.fk_path(joints.q)
    return simulate_path(joints.t, pos, string_length, stop_time, settle_periods)


def predict_band(joints, robot, lengths, stop_time: float, obstacles=(), ball_radius: float = 0.0) -> BandPrediction:
    """Swing for each string length [m] on the FK pivot path, the ball's swept paths and their clearance."""
    import numpy as np

    from planners.obstacles import ball_path, clearance
    from planners.pendulum import natural_period
    from planners.sway_prediction import simulate_sampled

    pos, _ = robot.fk_path(joints.q)
    end = max(float(joints.t[-1]), stop_time + SETTLE_PERIODS * natural_period(float(max(lengths))))
    runs, res, peak, tpk, paths = [], [], [], [], []
    for ln in lengths:
        run = simulate_sampled(joints.t, pos, float(ln), end)
        th = run.theta
        k = int(np.argmax(th))
        runs.append(run)
        res.append(float(th[run.t >= stop_time - 1e-12].max()))
        peak.append(float(th[k]))
        tpk.append(float(run.t[k]))
        pivot = pos[np.minimum(np.arange(len(run.t)), len(pos) - 1)]
        paths.append(ball_path(pivot, run.s, float(ln)))
    clear = (
        clearance(runs[0].t, dict(zip(map(float, lengths), paths)), tuple(obstacles), ball_radius)
        if obstacles
        else None
    )
    dense = ()
    dres = dpeak = np.empty(0)
    if len(lengths) > 1:  # the residual swings between the simulated lengths: judge the band densely
        from planners.antisway import DENSE_LENGTHS
        from planners.sway_prediction import band_sweep

        dense = np.linspace(float(min(lengths)), float(max(lengths)), DENSE_LENGTHS)
        dres, dpeak = band_sweep(joints.t, pos, dense, stop_time, end, substep=0.0025)
    return BandPrediction(
        tuple(map(float, lengths)),
        tuple(runs),
        tuple(res),
        tuple(peak),
        tuple(tpk),
        tuple(paths),
        clear,
        tuple(map(float, dense)),
        tuple(map(float, dres)),
        tuple(map(float, dpeak)),
    )


def _failing_segments(plan, report) -> list[int]:
    return sorted({plan.segment_of(v.t) for v in report.failing})


@dataclass(frozen=True)
class _Setup:
    """What every attempt shares: layout, string, robot, limits and the checks asked for."""

    points: Any
    length: float
    z: float
    dt: float
    robot: Any
    q0: Any
    limits: Any
    margin: float
    jerk: bool
    max_sway: float | None
    obstacles: tuple
    ball_radius: float


def _accel_text(a_max) -> str:
    """One a_max [m/s²], or one per segment."""
    import numpy as np

    a = np.atleast_1d(np.asarray(a_max, dtype=float))
    return f"{a[0]:g}" if len(a) == 1 or np.all(a == a[0]) else "/".join(f"{v:.3g}" for v in a)


def _gentle(setup: _Setup, a_max: float, options, failed: AntiSwayResult) -> tuple[AntiSwayResult, tuple] | None:
    """The failed design again with a_max lowered step by step on the segments that break a joint limit only (the
    others keep the user's a_max); the first that plans (and its a_max per segment), or None."""
    import numpy as np

    res = failed
    accels = np.full(len(failed.plan.segments), float(a_max))
    for _ in range(GENTLE_TRIES):
        segs = _failing_segments(res.plan, res.report) if not res.report.ok else []
        if not segs:
            return None  # it failed on something a lower acceleration does not cure here
        accels[[k - 1 for k in segs]] *= GENTLE_STEP
        res = _attempt(setup, tuple(accels), options, trial=True)
        if res.failure is None:
            return res, tuple(accels)
    return None


def _limits_failure(plan, report, a_max) -> str:
    """Why a plan that breaks a joint limit cannot be used: the first failing segment and the check's violation."""
    failing = _failing_segments(plan, report)
    seg = plan.segments[failing[0] - 1]
    first = next(v for v in report.failing if plan.segment_of(v.t) == failing[0])
    others = f" (segments {', '.join(map(str, failing))} exceed the limits)" if len(failing) > 1 else ""
    return (
        f"a_max = {_accel_text(a_max)} m/s² does not fit the joint limits at segment {failing[0]}{others} "
        f"({seg.start[0]:.3f},{seg.start[1]:.3f})→({seg.end[0]:.3f},{seg.end[1]:.3f}): {first.describe()}"
    )


def _attempt(setup: _Setup, a_max, options, progress=None, trial: bool = False) -> AntiSwayResult:
    """Plan, IK, check, predict across the band; ``failure`` says why the plan cannot be used (or None).
    ``trial``: one of several tried (a fallback, a lower a_max) — one that breaks a joint limit is not simulated
    (its ``run``, ``band`` None, its baseline NaN): it is discarded."""
    from planners.antisway import band_lengths, plan_layout

    from .commands.check import run_check

    timings = {}
    t0 = time.perf_counter()
    plan = plan_layout(setup.points, setup.length, a_max, setup.z, setup.dt, options)
    timings["plan"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    joints, ik_error = _joints_of(plan, setup.robot, setup.q0, setup.limits, progress)
    timings["ik"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    report = run_check(joints, setup.limits, setup.margin, setup.jerk, False, setup.robot)
    timings["check"] = time.perf_counter() - t0
    if trial and not report.ok:
        failure = _limits_failure(plan, report, a_max)
        return AntiSwayResult(plan, joints, ik_error, report, None, plan.stop_time, math.nan, timings, None,  # type: ignore[arg-type]
                              setup.obstacles, setup.max_sway, failure)  # fmt: skip
    t0 = time.perf_counter()
    tol = options.length_tolerance
    lengths = band_lengths(setup.length, tol)
    band = predict_band(joints, setup.robot, lengths, plan.stop_time, setup.obstacles, setup.ball_radius)
    run = (
        band.runs[list(lengths).index(setup.length)]
        if setup.length in list(lengths)
        else predict_sway(joints, setup.robot, setup.length, plan.stop_time)
    )
    timings["prediction"] = time.perf_counter() - t0
    baseline = plan_layout(
        setup.points, setup.length, a_max, setup.z, setup.dt, type(options)(shaper="accel")
    ).stop_time
    failure = None
    if not report.ok:
        failure = _limits_failure(plan, report, a_max)
    elif setup.max_sway is not None and band.worst_peak > setup.max_sway and max(band.peak) <= setup.max_sway:
        failure = (
            f"predicted sway {math.degrees(band.worst_peak):.2f}° for a string length between the simulated ones "
            f"exceeds the sway limit (max sway) {math.degrees(setup.max_sway):.2f}°"
        )
    elif setup.max_sway is not None and max(band.peak) > setup.max_sway:
        k = max(range(len(band.peak)), key=lambda i: band.peak[i])
        failure = (
            f"predicted sway {math.degrees(band.peak[k]):.2f}° at t = {band.peak_time[k]:.3f} s (string "
            f"{band.lengths[k]:.3f} m, segment {plan.segment_of(band.peak_time[k])}) exceeds the sway limit (max sway) "
            f"{math.degrees(setup.max_sway):.2f}°"
        )
    elif band.clearance is not None and band.clearance.touches:
        c = band.clearance
        failure = (
            f"the ball touches obstacle {c.obstacle!r} at t = {c.time:.3f} s (segment {plan.segment_of(c.time)}, "
            f"string {c.length:.3f} m, ball centre ({c.position[0]:.3f},{c.position[1]:.3f},{c.position[2]:.3f}) m, "
            f"ball radius {setup.ball_radius:g} m)"
        )
    return AntiSwayResult(
        plan,
        joints,
        ik_error,
        report,
        run,
        plan.stop_time,
        baseline,
        timings,
        band,
        setup.obstacles,
        setup.max_sway,
        failure,
    )


def _largest_fitting_accel(setup: _Setup, a_max: float, options) -> float:
    """Largest single a_max [m/s²] (2 decimals, ≤ a_max) at which the same options plan; 0.0 if none found.

    Halving until a plan succeeds, then bisection; the printed (rounded-down) value is re-planned before it is
    returned, and lowered in 3 % steps until it plans, because feasibility need not be monotone in a_max.
    """

    def fits(a: float) -> bool:
        return a > 0 and _attempt(setup, a, options, trial=True).failure is None

    hi, lo = a_max, a_max
    for _ in range(6):
        lo *= 0.5
        if fits(lo):
            break
        hi = lo
    else:
        return 0.0
    while hi - lo > 0.03 * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if fits(mid) else (lo, mid)
    best = math.floor(lo * 100) / 100
    for _ in range(8):
        if best >= 0.01 and (best == lo or fits(best)):
            return best
        best = math.floor(best * 0.97 * 100) / 100
    return 0.0


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
    length_tolerance: float | None = None,
    tune: bool = True,
    max_sway: float | None = None,
    obstacles: Sequence = (),
    ball_radius: float = DEFAULT_BALL_RADIUS,
    fallback: bool = True,
    suggest: bool = True,
    progress: Callable[[int], None] | None = None,
) -> AntiSwayResult:
    """Plan, solve IK, check and predict an anti-sway move; raise PlanningError if it cannot be used.

    points (n, 2) [m] in the base frame: start then turning points; length [m] from the pivot (flange origin
    + tool) to the ball centre; a_max [m/s²]; z [m] flange height; dt [s] joint sample step; length_tolerance
    relative (None: the planner's default ±10 %); max_sway [rad] during the move (across the band);
    obstacles (planners.obstacles.Obstacle) checked against the ball of ``ball_radius`` [m] swept for the
    string lengths across the band. With ``shaper="auto"`` and ``fallback`` other designs are tried at the
    same a_max before giving up; with ``suggest`` the message names the largest a_max that plans (verified).
    """
    import numpy as np

    from planners.antisway import DEFAULT_LENGTH_TOLERANCE, DEFAULT_Z, AntiSwayOptions
    from trajectories.errors import PlanningError
    from trajectories.limits import load_limits

    from .options import make_robot

    pts = np.asarray(points, dtype=float)
    z = DEFAULT_Z if z is None else float(z)
    tol = DEFAULT_LENGTH_TOLERANCE if length_tolerance is None else float(length_tolerance)
    _validate(pts, length, a_max, dt, shaper, tol, margin, z, max_sway, ball_radius)
    options = AntiSwayOptions(
        shaper=shaper,
        j_max=None if j_max is None else float(j_max),
        v_max=float(v_max),
        length_tolerance=tol,
        tune=tune,
        max_sway=max_sway,
    )
    lim = limits if limits is not None else load_limits(None)
    robot = make_robot(flange, tool)
    q_ref = _start_pose(q0)
    check_reach(pts, z, robot, lim)
    setup = _Setup(
        pts,
        float(length),
        z,
        float(dt),
        robot,
        q_ref,
        lim,
        margin,
        jerk,
        max_sway,
        tuple(obstacles),
        float(ball_radius),
    )
    result = _attempt(setup, a_max, options, progress)
    if result.failure is None:
        return result
    if fallback and shaper == "auto":
        alt = _fallback(setup, a_max, options, result)
        if alt is not None:
            return alt
    raise PlanningError(_failure_text(setup, a_max, options, result, fallback and shaper == "auto", suggest))


def _fallback(setup: _Setup, a_max: float, options, result: AntiSwayResult) -> AntiSwayResult | None:
    """The quickest of the other designs (``FALLBACK_DESIGNS``) that plans at ``a_max`` [m/s²] where the shaper
    ``auto`` failed (``result``), with at most ``FALLBACK_RESIDUAL`` residual across the length band; None if none."""
    from dataclasses import replace

    import numpy as np

    tol = options.length_tolerance
    tried = []
    peak_speed = float(np.abs(np.diff(result.plan.position, axis=0)).max() / setup.dt) * math.sqrt(2)
    for design in FALLBACK_DESIGNS:
        # robust-slow: the robust design with the pivot speed capped at 3/4 of the failed plan's peak;
        # robust-gentle: the robust design at a lower a_max (a joint's acceleration limit is often what fails,
        # and the robust design stays quicker than the baseline at a little less acceleration)
        if design == "robust-gentle":
            found = _gentle(setup, a_max, options, result)
            if found is not None and (tol == 0 or found[0].band.worst_residual[0] <= FALLBACK_RESIDUAL):
                alt = replace(found[0], baseline_duration=result.baseline_duration)  # at the user's a_max
                tried.append((alt, f" (a_max {_accel_text(found[1])} m/s² per segment)"))
            continue
        alt_opts = (
            replace(options, shaper="robust", v_max=min(options.v_max, 0.75 * peak_speed))
            if design == "robust-slow"
            else replace(options, shaper=design)
        )
        alt = _attempt(setup, a_max, alt_opts, trial=True)
        if alt.failure is None and (tol == 0 or alt.band.worst_residual[0] <= FALLBACK_RESIDUAL):
            tried.append((alt, ""))
    if not tried:
        return None
    alt, note = min(tried, key=lambda r: r[0].stop_time)
    to = (
        alt.plan.shaper
        if math.isinf(alt.plan.options.v_max)
        else (f"{alt.plan.shaper} (pivot speed ≤ {alt.plan.options.v_max:.2f} m/s)")
    )
    return replace(alt, fallback={"from": options.shaper, "to": to + note, "reason": result.failure})


def _failure_text(setup: _Setup, a_max: float, options, result: AntiSwayResult, fell_back: bool, suggest: bool) -> str:
    """Why no plan: the failure, that no fallback design planned either, and (``suggest``) the largest a_max
    [m/s²] that plans."""
    msg = result.failure
    if fell_back:
        msg += (
            f"; no fallback design ({', '.join(FALLBACK_DESIGNS)}) plans either with ≤ "
            f"{math.degrees(FALLBACK_RESIDUAL):g}° residual across the length band"
        )
    if suggest and result.failure.startswith("a_max") or (suggest and "sway" in result.failure):
        best = _largest_fitting_accel(setup, a_max, options)
        msg += (
            f"; the largest a_max that plans is {best:.2f} m/s² (re-planned with that single a_max)"
            if best > 0
            else "; no a_max plans (the layout is outside the joint limits at any acceleration)"
        )
    return msg + " (an anti-sway plan is never re-timed)"


def _start_pose(q0: Sequence[float] | None):
    """The IK's reference pose (7,) [rad]: ``q0``, else the anti-sway start pose."""
    import numpy as np

    from trajectories.errors import SettingError

    from .parsing import parse_joint_vector

    q_ref = parse_joint_vector(ANTISWAY_Q0, "ANTISWAY_Q0") if q0 is None else np.asarray(q0, dtype=float)
    if q_ref.shape != (7,):
        raise SettingError(SETTINGS, "q0", "expected 7 joint angles")
    return q_ref


def _validate(pts, length, a_max, dt, shaper, tol, margin, z, max_sway, ball_radius) -> None:
    """Every setting of :func:`plan_anti_sway` in its range (SettingError ``plan_anti_sway.FIELD`` naming the first
    one that is not; the command maps it to its option)."""
    import numpy as np

    from planners.antisway import SHAPERS
    from trajectories.errors import SettingError

    def bad(field: str, message: str) -> SettingError:
        return SettingError(SETTINGS, field, message)

    if not (math.isfinite(z) and Z_RANGE[0] <= z <= Z_RANGE[1]):
        raise bad("z", f"must be a flange height in [{Z_RANGE[0]:g}, {Z_RANGE[1]:g}] m, got {z:g}")
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 2:
        raise bad("points", "need a start and at least one turning point 'x0,y0;x1,y1;...'")
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    if np.any(seg < 1e-6):
        k = int(np.argmin(seg)) + 1
        raise bad("points", f"segment {k} has zero length (points {k - 1} and {k} coincide)")
    if not (math.isfinite(length) and 0.01 <= length <= 3.0):
        raise bad("length", f"must be a string length in [0.01, 3] m, got {length:g}")
    if not (math.isfinite(a_max) and 0 < a_max <= 20.0):
        raise bad("a_max", f"must be in (0, 20] m/s², got {a_max:g}")
    if not (math.isfinite(dt) and 1e-4 <= dt <= 0.05):
        raise bad("dt", f"must be in [0.0001, 0.05] s, got {dt:g}")
    if shaper not in SHAPERS:
        raise bad("shaper", f"unknown {shaper!r}; choose one of {', '.join(SHAPERS)}")
    if not (0.0 <= tol < 0.9):
        raise bad("length_tolerance", f"must be in [0, 0.9), got {tol:g}")
    if not (math.isfinite(margin) and 0 <= margin < 1):
        raise bad("margin", f"must be in [0, 1), got {margin:g}")
    if max_sway is not None and not (0 < max_sway < math.pi / 2):
        raise bad("max_sway", f"must be in (0, 90) deg, got {math.degrees(max_sway):g} deg")
    if not (math.isfinite(ball_radius) and 0 <= ball_radius < 1):
        raise bad("ball_radius", f"must be in [0, 1) m, got {ball_radius:g}")


def write_outputs(
    result: AntiSwayResult,
    out: Path,
    task_out: Path | None = None,
    prediction: Path | None = None,
    plot: Path | None = None,
) -> None:
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
        from .plots.antisway import plot_antisway

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
    figs.update(
        {
            "out": str(out),
            "task_out": str(task_out) if task_out else None,
            "prediction": str(prediction) if prediction else None,
            "plot": str(plot) if plot else None,
        }
    )
    return figs
