"""Swing-up on the arm: plan the pivot (energy shaping or fast pumping), IK, limit check, verification.

``plan_swing_up`` is what `lbr plan swing-up` and the demo call. It derives the pivot's speed, acceleration
and jerk bounds along base y from the joint limits (``swingup_robot.axis_bounds``), plans, solves IK per
sample, checks the joint path and drives the nonlinear ball simulation with it. For the fast method a joint
path that still breaks a limit makes the bounds tighter by the observed ratio and the plan is redone.
With ``taut`` the string must stay taut until θ_d is reached: the plan then aims at the highest angle reachable that
way (the fast method; a pivot that rests afterwards leaves a swing above 90° that goes slack at its next apex).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from trajectories.check import CheckReport, check_trajectory
from trajectories.errors import PlanningError
from trajectories.limits import JointLimits
from trajectories.robot import Robot
from trajectories.start_poses import THESIS_START
from trajectories.trajectory import JointTrajectory

from .swingup_energy import EnergyParams, plan_energy
from .swingup_fast import FastProblem, SearchSettings, optimise, simulate_fast
from .swingup_plan import PivotPlan, TaskBounds, first_reach, mirrored, reach_side
from .swingup_robot import ArmSetup, Verification, axis_bounds, joint_path, verify
from .tension import slack_report

THESIS_Q_START = THESIS_START  # [rad], thesis §5.3.2
METHODS = ("energy", "fast")


@dataclass(frozen=True)
class SwingUpRequest:
    """Everything a swing-up plan depends on (SI units, angles in rad)."""

    length: float  # [m]
    mass: float  # [kg]
    theta_d: float  # [rad]
    method: str = "energy"
    q_start: tuple[float, ...] = THESIS_Q_START
    orientation: str | None = None  # "fixed" | "follow"; None: fixed for energy (thesis), follow for fast
    travel: float = 0.3  # [m] band |y − y_start| the pivot must stay in (the bounds are derived over it)
    dt: float = 0.005  # [s] FRI period
    duration: float | None = None  # [s] pumping horizon; None: 60 (energy), 10 (fast)
    tolerance: float = math.radians(2.0)  # [rad]
    theta0: float = 0.0  # [rad]
    push: float = 0.0  # [m/s²] energy: start push
    k_e: float = 1.7
    k_p: float = 0.05
    k_d: float = 0.05
    taut: bool = False
    min_tension: float = 0.5  # [m/s²] margin required when ``taut``
    side: int = 0  # +1 / −1: reach θ_d toward +y / −y (the plan is mirrored if needed); 0: either side
    limit_margin: float = 0.1  # the bounds keep joints within (1 − margin)·limits
    search: SearchSettings = SearchSettings()

    @property
    def pivot_orientation(self) -> str:
        return self.orientation or ("fixed" if self.method == "energy" else "follow")


@dataclass(frozen=True)
class SwingUpResult:
    """Plan, joint path, limit report, verification and the figures the command reports."""

    request: SwingUpRequest
    plan: PivotPlan
    trajectory: JointTrajectory
    check: CheckReport
    verification: Verification
    bounds: TaskBounds
    max_ik_error: float  # [m]
    planning_time: float  # [s]
    highest_taut_theta: float | None = None  # [rad], with ``taut`` when θ_d is not reachable taut
    attempts: int = 1
    notes: tuple[str, ...] = field(default=())

    @property
    def t_reach(self) -> float | None:
        """First time the verified |θ| reaches θ_d − tolerance [s]."""
        return first_reach(self.verification.t, self.verification.theta, self.request.theta_d - self.request.tolerance)

    @property
    def reached(self) -> bool:
        return self.t_reach is not None

    @property
    def taut_until_reach(self) -> bool:
        """The verified string stays taut until θ_d is reached (taut throughout when it is not)."""
        slack = self.verification.first_slack
        if self.request.method == "energy":
            return slack is None
        return slack is None or (self.t_reach is not None and slack >= self.t_reach)

    def figures(self) -> dict:
        """JSON figures: those of the verification simulation, the plan's own claim under ``claimed``."""
        r, ver, plan = self.request, self.verification, self.plan
        slack = slack_report(ver.t, ver.tension)
        claimed_slack = slack_report(plan.t, plan.tension)
        n = min(len(plan.theta), len(ver.theta))
        if ver.first_slack is not None:  # after the string goes slack the planar claim no longer applies
            n = min(n, max(1, int(np.searchsorted(ver.t, ver.first_slack))))
        diff = np.abs(plan.theta[:n] - ver.theta[:n])
        figures = {
            "method": plan.method,
            "orientation": r.pivot_orientation,
            "length_m": r.length,
            "mass_kg": r.mass,
            "theta_d_deg": math.degrees(r.theta_d),
            "max_theta_deg": math.degrees(ver.max_theta),
            "max_taut_theta_deg": math.degrees(ver.max_taut_theta),
            "t_reach_s": self.t_reach,
            "t_theta_d_s": first_reach(ver.t, ver.theta, r.theta_d),
            "reached": self.reached,
            "tolerance_deg": math.degrees(r.tolerance),
            "taut": slack.taut,
            "taut_until_reach": self.taut_until_reach,
            "min_tension_margin": slack.min_margin,  # [m/s²] tension / ball mass
            "min_tension_n": slack.min_margin * r.mass,
            "first_slack_s": slack.t_first_slack,
            **self.check.plan_figures(self.trajectory),
            "t_rest_s": plan.t_rest,
            "max_travel_m": float(np.max(np.abs(plan.x))),
            "bounds": {
                "v_max_m_s": self.bounds.v_max,
                "a_max_m_s2": self.bounds.a_max,
                "j_max_m_s3": self.bounds.j_max,
            },
            "max_ik_error_m": self.max_ik_error,
            "planning_time_s": self.planning_time,
            "claimed": {
                "max_theta_deg": math.degrees(plan.max_theta),
                "t_reach_s": plan.t_reach,
                "min_tension_margin": claimed_slack.min_margin,
                "taut": claimed_slack.taut,
                "max_theta_difference_deg": float(np.degrees(diff.max())),
                "rms_theta_difference_deg": float(np.degrees(np.sqrt(np.mean(diff**2)))),
            },
        }
        if r.taut:
            figures["highest_taut_theta_deg"] = (
                math.degrees(self.highest_taut_theta) if self.highest_taut_theta is not None else None
            )
        if plan.method == "fast":
            p = plan.info["params"]
            figures["fast_params"] = {
                "speed": p.speed,
                "first_speed": p.first_speed,
                "centring": p.centring,
                "apex_offset_deg": math.degrees(p.apex_offset),
            }
            figures["attempts"] = self.attempts
        if self.notes:
            figures["notes"] = list(self.notes)
        return figures

    def failure(self) -> str | None:
        """Why the plan fails (θ_d not reached, limits violated, slack with ``taut``), None if it does not."""
        reasons = []
        if not self.reached:
            reasons.append(
                f"θ_d = {math.degrees(self.request.theta_d):.1f}° not reached (max {math.degrees(self.verification.max_theta):.1f}°"
                + (f", highest taut {math.degrees(self.highest_taut_theta):.1f}°" if self.highest_taut_theta else "")
                + ")"
            )
        if not self.check.ok:
            reasons.append("joint limits violated: " + "; ".join(v.describe() for v in self.check.failing[:3]))
        if self.request.taut and not self.taut_until_reach:
            reasons.append(
                f"the string goes slack at {self.verification.first_slack:.3f} s, "
                f"{math.degrees(self.verification.max_taut_theta):.1f}° high, before θ_d"
            )
        return "; ".join(reasons) or None


def _energy_params(r: SwingUpRequest, theta_d: float) -> EnergyParams:
    return EnergyParams(
        length=r.length,
        mass=r.mass,
        theta_d=theta_d,
        k_e=r.k_e,
        k_p=r.k_p,
        k_d=r.k_d,
        theta0=r.theta0,
        push=r.push,
        duration=r.duration or 60.0,
        dt=r.dt,
        tolerance=r.tolerance,
    )


def _fast_problem(r: SwingUpRequest, bounds: TaskBounds) -> FastProblem:
    return FastProblem(
        length=r.length,
        theta_d=r.theta_d,
        bounds=bounds,
        travel=r.travel,
        dt=r.dt,
        horizon=r.duration or 10.0,
        tolerance=r.tolerance,
        theta0=r.theta0,
        taut=r.taut,
        min_tension=r.min_tension,
    )


def _highest_taut_energy(r: SwingUpRequest, bounds: TaskBounds) -> tuple[PivotPlan, float | None]:
    """Energy plan for θ_d if it stays taut, else for the highest θ_d' that does (bisection, 0.5°)."""
    plan = plan_energy(_energy_params(r, r.theta_d), bounds)
    if plan.tension.min() >= r.min_tension:
        return plan, None
    lo, hi, best = max(r.tolerance * 2, abs(r.theta0)), r.theta_d, None
    while hi - lo > math.radians(0.5):
        mid = 0.5 * (lo + hi)
        cand = plan_energy(_energy_params(r, mid), bounds)
        if cand.tension.min() >= r.min_tension:
            lo, best = mid, cand
        else:
            hi = mid
    if best is None:
        raise PlanningError("no energy-shaping plan keeps the string taut; lower SwingUpRequest.theta_d")
    return best, best.max_theta


def _fast_on_arm(
    r: SwingUpRequest,
    robot: Robot,
    setup: ArmSetup,
    limits: JointLimits,
    bounds: TaskBounds,
    notes: list[str],
    progress=None,
    max_attempts: int = 4,
    governor: bool = False,
):
    """Fast plan whose joint path passes the check (jerk included), with the bounds fitted to the arm.

    The first bounds come from the Jacobian over the band (first order, optimistic); while the joint path breaks
    a limit (or uses none of them up to 85 % of 1 − margin) every bound is rescaled by target/peak ratio of its
    joint quantity and the search is rerun from the previous best. The soonest plan that passes is kept.
    """
    target = 1.0 - r.limit_margin
    best = None
    params = None
    last = None
    for attempt in range(1, max_attempts + 1):
        problem = replace(_fast_problem(r, bounds), governor=governor)
        settings = r.search if attempt == 1 else replace(r.search, maxiter=max(5, r.search.maxiter // 2))
        params, _ = optimise(problem, settings, start=params)
        plan = _on_side(r, simulate_fast(problem, params), notes if attempt == 1 else [])
        traj, ik_err = joint_path(robot, setup, plan.t, plan.x, limits, progress)
        report = check_trajectory(traj, limits, jerk=True)
        last = (plan, traj, ik_err, report, bounds, attempt)
        ratios = {q: float(report.ratios()[q].max()) for q in ("velocity", "acceleration", "jerk")}
        if report.ok and (best is None or _reach_key(plan) < _reach_key(best[0])):
            best = last
        factor = {q: min(1.5, target / max(v, 1e-6)) for q, v in ratios.items()}
        if not report.ok:
            factor = {q: min(1.0, f) for q, f in factor.items()}
        notes.append(
            f"attempt {attempt}: reach {_fmt(plan.t_reach)}, limits {'ok' if report.ok else 'violated'}, "
            "peak ratios " + ", ".join(f"{q} {v:.2f}" for q, v in ratios.items())
        )
        if report.ok and max(ratios.values()) >= 0.85 * target:
            break  # within the limits and one of them nearly used: the bounds fit the arm
        bounds = TaskBounds(
            bounds.v_max * factor["velocity"], bounds.a_max * factor["acceleration"], bounds.j_max * factor["jerk"]
        )
    return best if best is not None else last


def _on_side(r: SwingUpRequest, plan: PivotPlan, notes: list[str]) -> PivotPlan:
    """Mirror the plan if it reaches θ_d on the side opposite to ``r.side`` (possible when it starts centred)."""
    side = reach_side(plan)
    if r.side == 0 or side in (0, r.side):
        return plan
    if r.theta0 != 0.0:
        notes.append("θ_d is reached on the other side; a plan from θ0 ≠ 0 cannot be mirrored (flip its sign)")
        return plan
    return mirrored(plan)


def _reach_key(plan: PivotPlan) -> float:
    """Sort key: the reach time [s], or (unreached) the higher the angle the better."""
    return plan.t_reach if plan.t_reach is not None else 1e9 - plan.max_theta


def _fmt(t: float | None) -> str:
    return "never" if t is None else f"{t:.3f} s"


def plan_swing_up(r: SwingUpRequest, robot: Robot, limits: JointLimits, progress=None) -> SwingUpResult:
    """Plan, map onto the arm, check and verify a swing-up. Raises PlanningError if no plan can be made."""
    start = time.perf_counter()
    if r.method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}")
    setup = ArmSetup(q_start=tuple(float(v) for v in r.q_start), orientation=r.pivot_orientation)
    try:
        bounds = axis_bounds(robot, setup, limits, r.travel, r.limit_margin, first_order=r.method == "fast")
    except ValueError as exc:
        raise PlanningError(str(exc)) from None
    notes: list[str] = []
    highest = None
    attempts = 1
    bounds0 = bounds
    if r.method == "energy":
        if r.taut:
            plan, highest = _highest_taut_energy(r, bounds)
        else:
            plan = plan_energy(_energy_params(r, r.theta_d), bounds)
        plan = _on_side(r, plan, notes)
        travel = float(np.max(np.abs(plan.x)))
        if travel > r.travel:
            raise PlanningError(
                f"the energy law moves the pivot {travel:.2f} m from its start, beyond the "
                f"±{r.travel:g} m band (SwingUpRequest.travel); raise SwingUpRequest.k_p/SwingUpRequest.k_d or lower "
                "SwingUpRequest.push"
            )
        traj, ik_err = joint_path(robot, setup, plan.t, plan.x, limits, progress)
        report = check_trajectory(traj, limits)
    else:
        plan, traj, ik_err, report, bounds, attempts = _fast_on_arm(r, robot, setup, limits, bounds, notes, progress)
        if not r.taut:  # the tension governor often pumps sooner within the joint limits: keep the quicker of both
            alt_notes: list[str] = []
            alt = _fast_on_arm(r, robot, setup, limits, bounds0, alt_notes, progress, governor=True)
            if alt[3].ok and (not report.ok or _reach_key(alt[0]) < _reach_key(plan)):
                plan, traj, ik_err, report, bounds, attempts = alt
                notes[:] = alt_notes + ["with the tension governor (quicker than without)"]
        if r.taut and plan.t_reach is None:
            highest = plan.max_theta  # replaced by the verified one below
    ver = verify(robot, traj, r.length, r.theta0, mass=r.mass)
    if r.taut and r.method == "fast":
        highest = ver.max_taut_theta  # what the string really holds taut, not the planar claim
    return SwingUpResult(
        request=r,
        plan=plan,
        trajectory=traj,
        check=report,
        verification=ver,
        bounds=bounds,
        max_ik_error=ik_err,
        planning_time=time.perf_counter() - start,
        highest_taut_theta=highest,
        attempts=attempts,
        notes=tuple(notes),
    )
