"""The whole cup-and-ball game on the arm: swing the ball up, let it go, catch it in the cup, and stop.

``plan_catch`` is what `lbr plan cup-and-ball` calls:

1. Swing-up (``catch_swing``): fast energy pumping along base y with the tension governor (taut while the pivot
   accelerates), chosen by differential evolution for an early release and a small spread of the landing points
   over the string-length band, within ``max_time``. Each variant (``swing_variants``: the pivot ending cruising or
   at rest, pumping over one or two horizons) is searched on its own.
2. Release: the pivot ends at a constant velocity (cruising toward where the ball will come down, or at rest) and the
   ball's free swing goes slack by itself; every length of the band is stepped to the moment all have been released
   (``catch_move.prepare_band``).
3. Catch move (``catch_move``): a jerk-limited move in the base y–z plane to a position and velocity at a chosen
   time, a coast at that velocity for a chosen while (the band's balls come down over some 30 ms and bounce in the
   cup: a cup braking under them can throw them out), then a brake to rest; a grid (every variant) and a
   Nelder–Mead search (the REFINED variants the grid puts first) maximise the share of the band caught (entry margin
   and relative entry speed as tie-breakers), the band (5 lengths × the cup one period early, on time, late, the
   ball's mass rotating over them: ``search_members``) stepped with ``string_stepper`` — each ball only until it
   passes outside the rim, where the search counts it as missed (most of the planning time is this search).
4. The joint path (IK per sample, ``swingup_robot``), the limit check (jerk included), and the verdict from the
   nonlinear model driven by the TCP path the joints realise: the event-driven ``string_sim`` for the prediction,
   the stepper for every member of the robustness band (length × mass × timing of the cup after the release). The
   variant whose verdict ranks first (``_rank``: valid; without a max_time, then the goals met — in the cup within
   QUICK_TIME, min_success of the band caught —; then the share of the band caught) is the plan.
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from trajectories.check import CheckReport, check_trajectory
from trajectories.errors import PlanningError
from trajectories.limits import JointLimits
from trajectories.robot import Robot
from trajectories.trajectory import JointTrajectory

from .catch_move import (
    BandMember,
    CatchMove,
    band_members,
    band_score,
    cup_path,
    judge_band,
    pivot_motion,
    prepare_band,
)
from .catch_outcome import CatchOutcome, outcome
from .catch_swing import ReleaseGoal, release_score
from .pendulum import natural_period
from .string_model import RESTING, StringModel
from .string_sim import BallRun, PivotMotion, simulate_string
from .string_stepper import step_path
from .swingup_fast import FastProblem, SearchSettings, optimise, simulate_fast
from .swingup import THESIS_Q_START
from .swingup_plan import PivotPlan, TaskBounds
from .swingup_robot import ArmSetup, axis_bounds, joint_path

FLIGHT_ALLOWANCE = 0.3  # [s] the release must come this much before max_time (the ball's flight into the cup)
SETTLE = 0.6  # [s] the pivot rests this long at the end (the ball settles in the cup)
MAX_AXIS_TILT = math.radians(25.0)  # the cup must open upward within this angle of base +z at the start pose
MOVE_SHARE = 0.75  # the catch move's y and z each get this share of their own bounds (they add up on the joints)
SWING_JERK_SHARE = 0.8  # the swing-up's jerk bound: this share of the first-order one
SEARCH_LENGTHS = 5  # string lengths across the band the catch-move search judges each candidate on (× 3 timings)
BAND_LENGTHS = 9  # string lengths across the band of the verdict (× 3 masses × 3 timings)
SPREAD_SHARE = 0.85  # the swing-up aims at landings of the band spread over at most this share of the opening
LATERAL_SHARE = 0.5  # the band lands flying over the ground at most this share of the catch move's speed bound
SWING_HORIZONS = (4.0, 6.0)  # [s] longest pumping from rest without a max_time (with one: max_time + 1 s)
FALLBACK_HORIZONS = (3.5, 5.0, 8.0)  # [s] and, when no plan of those catches enough of the band, these long, in turn
QUICK_TIME = 3.0  # [s] without a max_time, the cruising release is searched as for a plan within this
GOAL_MISSED = 100.0  # a swing-up search cost from this on missed the release goal (``catch_swing.release_score``)
MAX_COAST = 0.25  # [s] longest coast of the catch move at its target velocity before it brakes
COAST_EXTRA = 0.05  # [s] the grid's coast: from the catch to the band's last landing, and this much more
REFINED = 2  # swing-up variants whose catch move is refined and judged on the whole band (best catch grid first)
QUICK_GRID = 0.5  # a catch move whose grid scores below this is refined only as its stage's best (never if quick)


@dataclass(frozen=True)
class SwingVariant:
    """One way to swing up: the pivot ends cruising at a constant velocity the search chooses (else at rest), and
    the longest pumping [s]. The search over each is its own (a differential evolution finds different optima for
    each), the verdict on the band picks among them."""

    cruise: bool
    horizon: float  # [s]
    slack: float = 0.0  # [s] the swing-up search's release deadline later by this (the plan must still be in time)
    quick: float | None = None  # [s] without a max_time: search the swing-up as for a plan within this

    def describe(self) -> str:
        slack = f", release deadline {self.slack:g} s later" if self.slack else ""
        quick = f", searched as for {self.quick:g} s" if self.quick is not None else ""
        return f"{'cruising' if self.cruise else 'rest'} release, pumping up to {self.horizon:g} s{slack}{quick}"

    def deadline(self, max_time: float | None) -> float:
        """The swing-up search's release deadline [s] (inf: none)."""
        budget = max_time if max_time is not None else self.quick
        return math.inf if budget is None else budget - FLIGHT_ALLOWANCE + self.slack


def swing_variants(max_time: float | None) -> tuple[SwingVariant, ...]:
    """The swing-ups a plan tries: the cruising release (quick; it often lets short strings' bands land close
    together) and the release from rest (slower, often more robust for long strings). With a max_time the rest
    release pumps up to max_time + 1 s; the cruising one up to max_time + 1.25 s with the search's release deadline
    a quarter second later than the time asked allows — its optimum depends on both, and what it finds mostly still
    enters the cup in time (a plan that does not is not valid: ``_rank``). With a max_time of 3 s that lifted the band
    caught from 90 to 99 % at 0.25 m and from 42 to 94 % at 0.3 m, entering at 1.9-2.2 s; 0.15 and 0.2 m kept their
    plans. Without a max_time: from rest up to 4 s and up to 6 s, and the cruising release searched as for a plan
    within QUICK_TIME (with no deadline, over 4 s, it had caught 85 % of the band at 0.3 m, as for 3 s 95 %;
    cruising over 6 s found worse plans: 0.25 m caught 46 % of the band, 0.35 m none)."""
    if max_time is not None:
        return (SwingVariant(True, max_time + 1.25, 0.25), SwingVariant(False, max_time + 1.0))
    short, long = SWING_HORIZONS
    return (
        SwingVariant(True, QUICK_TIME + 1.25, 0.25, quick=QUICK_TIME),
        SwingVariant(False, short),
        SwingVariant(False, long),
    )


@dataclass(frozen=True)
class CatchRequest:
    """Everything a cup-and-ball plan depends on (SI units, angles in rad)."""

    model: StringModel  # string length, ball, cup, coefficients
    q_start: tuple[float, ...] = THESIS_Q_START
    dt: float = 0.005  # [s] FRI period of the joint file
    max_time: float | None = None  # [s] from rest to the ball entering the cup (None: as soon as the band allows)
    release_apex: float = math.radians(150.0)  # [rad] where the search starts looking for the release energy
    length_tol: float = 0.03  # robustness band: string length ± this share
    mass_tol: float = 0.2  # ball mass ± this share
    timing: bool = True  # and the cup's motion after the release one period early or late
    travel: float = 0.3  # [m] the pivot stays within ± this along base y
    z_travel: float = 0.08  # [m] and within ± this along base z
    limit_margin: float = 0.1  # the bounds keep joints within (1 − margin)·limits
    min_success: float = 0.95  # share of the band that must be caught
    search: SearchSettings = SearchSettings(popsize=6, maxiter=14)
    catch_evaluations: int = 60  # Nelder–Mead evaluations of the catch move


@dataclass(frozen=True)
class BandResult:
    """The robustness band judged on the written joint path: each member and what happened to its ball."""

    members: tuple[BandMember, ...]
    outcomes: tuple[CatchOutcome, ...]

    @property
    def success(self) -> float:
        return float(np.mean([o.caught for o in self.outcomes])) if self.outcomes else 0.0

    def worst(self) -> tuple[BandMember, CatchOutcome]:
        """The member caught with the least margin, or (when some are missed) the one missed by the most."""

        def key(i):
            o = self.outcomes[i]
            return (o.caught, o.margin if o.margin is not None else -1.0)

        i = min(range(len(self.outcomes)), key=key)
        return self.members[i], self.outcomes[i]


@dataclass(frozen=True)
class CatchResult:
    """Plan, joint path, check, prediction and band figures of a cup-and-ball plan."""

    request: CatchRequest
    swing: PivotPlan
    move: CatchMove
    path: np.ndarray  # (n, 2) pivot displacements along base y, z [m]
    trajectory: JointTrajectory
    check: CheckReport
    prediction: BallRun
    nominal: CatchOutcome
    band: BandResult
    bounds: tuple[TaskBounds, TaskBounds, TaskBounds]  # swing-up along y, catch move along y, along z
    max_ik_error: float  # [m]
    planning_time: float  # [s]
    notes: tuple[str, ...] = field(default=())
    variant: SwingVariant | None = None  # the swing-up variant chosen

    def failure(self) -> str | None:
        """Why the plan fails: the nominal ball is not caught, joint limits, or too little of the band caught."""
        r = self.request
        reasons = []
        if not self.nominal.caught:
            reasons.append(f"no catch: {self.nominal.failure}")
        if not self.check.ok:
            reasons.append("joint limits violated: " + "; ".join(v.describe() for v in self.check.failing[:3]))
        if self.nominal.caught and self.band.success < r.min_success:
            member, o = self.band.worst()
            reasons.append(
                f"catches {100 * self.band.success:.0f} % of the band (string ±{100 * r.length_tol:g} %, mass "
                f"±{100 * r.mass_tol:g} %{', timing ±1 period' if r.timing else ''}), fewer than "
                f"{100 * r.min_success:g} %; worst: l = {member.length:.4f} m, m = {1e3 * member.mass:.1f} g, "
                f"timing {1e3 * member.shift:+.0f} ms: {o.failure or 'caught'}"
            )
        if r.max_time is not None and self.nominal.t_entry is not None and self.nominal.t_entry > r.max_time:
            reasons.append(
                f"the ball enters the cup at {self.nominal.t_entry:.2f} s, after CatchRequest.max_time {r.max_time:g} s"
            )
        return "; ".join(reasons) or None

    def figures(self) -> dict:
        r, m, n = self.request, self.request.model, self.nominal
        member, worst = self.band.worst()
        cup = m.cup
        return {
            "caught": n.caught,
            "catch_time_s": n.t_entry,
            "rest_in_cup_s": n.t_rest,
            "release_time_s": n.t_release,
            "entry_margin_m": n.margin,
            "relative_entry_speed_m_s": n.relative_speed,
            "relative_lateral_speed_m_s": n.lateral_speed,
            "contacts": n.contacts,
            "failure": self.failure(),
            "nominal_failure": n.failure,
            "robustness": {
                "success_fraction": self.band.success,
                "members": len(self.band.members),
                "length_tolerance": r.length_tol,
                "mass_tolerance": r.mass_tol,
                "timing_error_s": r.dt if r.timing else 0.0,
                "min_success": r.min_success,
                "worst": {
                    "length_m": member.length,
                    "mass_kg": member.mass,
                    "timing_s": member.shift,
                    **worst.figures(),
                },
                "min_entry_margin_m": min(
                    (o.margin for o in self.band.outcomes if o.caught and o.margin is not None), default=None
                ),
                "max_relative_entry_speed_m_s": max(
                    (o.relative_speed for o in self.band.outcomes if o.caught and o.relative_speed is not None),
                    default=None,
                ),
            },
            "length_m": m.length,
            "mass_kg": m.ball.mass,
            "ball_radius_m": m.ball.radius,
            "cup": {
                "inner_radius_m": cup.inner_radius,
                "depth_m": cup.depth,
                "rim_height_m": cup.rim_height,
                "wall_m": cup.wall,
                "axis": list(cup.axis),
            },
            "restitution": m.restitution,
            "retension": m.retension,
            "drag_coefficient": m.ball.drag_coefficient,
            **self.check.plan_figures(self.trajectory),
            "max_time_s": r.max_time,
            "swing_up_rest_s": self.swing.t_rest,
            "swing_up": {
                "release": None if self.variant is None else ("cruising" if self.variant.cruise else "rest"),
                "horizon_s": None if self.variant is None else self.variant.horizon,
                "release_deadline_s": None if self.variant is None else _finite(self.variant.deadline(r.max_time)),
                "cruise_m_s": float(self.swing.v[-1]),
            },
            "catch_move": {
                "t_start_s": self.move.t_start,
                "t_catch_s": self.move.t_catch,
                "y_m": self.move.y,
                "z_m": self.move.z,
                "vy_m_s": self.move.vy,
                "vz_m_s": self.move.vz,
                "coast_s": self.move.coast,
            },
            "max_travel_m": {"y": float(np.max(np.abs(self.path[:, 0]))), "z": float(np.max(np.abs(self.path[:, 1])))},
            "bounds": {
                axis: {"v_max_m_s": b.v_max, "a_max_m_s2": b.a_max, "j_max_m_s3": b.j_max}
                for axis, b in zip(("swing_y", "move_y", "move_z"), self.bounds)
            },
            "max_ik_error_m": self.max_ik_error,
            "planning_time_s": self.planning_time,
            "notes": list(self.notes),
        }


def _finite(x: float) -> float | None:
    return x if math.isfinite(x) else None


def cup_axis_at_start(robot: Robot, model: StringModel, q_start) -> np.ndarray:
    """The cup's opening direction in the base frame at q_start (unit)."""
    rot = robot.fk(np.asarray(q_start, dtype=float)).rotation
    return rot @ np.asarray(model.axis_flange)


def _swing_up(r: CatchRequest, bounds: TaskBounds, move: TaskBounds, variant: SwingVariant) -> tuple[PivotPlan, float]:
    """The variant's swing-up chosen by differential evolution (``catch_swing.release_score``), and its cost (≥ 100:
    the search could not meet the release goal)."""
    m = r.model
    window = 2.0 * (m.cup.inner_radius - m.ball.radius)  # lateral width of the opening the ball centre fits through
    deadline = variant.deadline(r.max_time)
    goal = ReleaseGoal(
        height=m.cup.rim_height,
        reach=0.06,
        spread_target=SPREAD_SHARE * window,
        deadline=deadline,
        lateral_speed=LATERAL_SHARE * move.v_max if variant.cruise else math.inf,
    )
    problem = FastProblem(
        length=m.length,
        theta_d=r.release_apex,
        bounds=bounds,
        travel=r.travel,
        dt=r.dt,
        horizon=variant.horizon,
        release=True,
        cruise=variant.cruise,
        band=(1.0 - r.length_tol, 1.0 + r.length_tol) if r.length_tol > 0 else (),
        scorer=release_score,
        goal=goal,
    )
    params, scored = optimise(problem, r.search)
    return simulate_fast(problem, params), scored.cost


@dataclass(frozen=True)
class Release:
    """The swing-up continued at the pivot's final constant velocity (at rest or cruising), sampled every dt [s]
    along base y: displacement x [m], velocity v [m/s], acceleration u [m/s²]; its anchor motion, and the time [s]
    every length of the band has been released (the catch move starts then)."""

    x: np.ndarray
    v: np.ndarray
    u: np.ndarray
    pivot: PivotMotion
    t_start: float


def _releases(r: CatchRequest, swing: PivotPlan, p0: np.ndarray, axis: np.ndarray) -> Release:
    """The swing-up path continued at its final velocity, and the time all lengths of the band have been released."""
    hold = int(round(natural_period(r.model.length * (1 + r.length_tol)) / r.dt))
    v_end = float(swing.v[-1])
    x = np.concatenate([swing.x, swing.x[-1] + v_end * r.dt * np.arange(1, hold + 1)])
    v = np.concatenate([swing.v, np.full(hold, v_end)])
    u = np.concatenate([swing.u, np.zeros(hold)])
    t = np.arange(len(x)) * r.dt
    pivot = pivot_motion(t, p0, np.column_stack([x, np.zeros_like(x)]), axis)
    last = swing.t_rest
    for f in (1.0 - r.length_tol, 1.0, 1.0 + r.length_tol):
        st, _ = step_path(replace(r.model, length=r.model.length * f), pivot, float(t[-1]))
        slack = [e.t for e in st.events if e.kind == "slack"]
        if not slack:
            raise PlanningError(f"the swing-up does not release the ball on a {r.model.length * f:.4f} m string")
        last = max(last, slack[0])
    return Release(x, v, u, pivot, r.dt * math.ceil(last / r.dt + 1e-9) + r.dt)


def band_landings(model: StringModel, pivot: PivotMotion, lengths) -> list[tuple[float, float, float]]:
    """(time [s], y [m] from the start pose, vy [m/s]) where each length's ball comes down through the rim height
    above the anchor's height at the end (no cup in the way)."""
    out = []
    for ln in lengths:
        st, rec = step_path(replace(model, length=ln, cup=None), pivot, pivot.t_end, record=True)
        t, b = np.array(rec[0]), np.array(rec[1])
        rel_z = b[:, 2] - pivot.x[-1, 2]
        top = int(np.argmax(rel_z))
        down = np.flatnonzero((rel_z[top:-1] >= model.cup.rim_height) & (rel_z[top + 1 :] < model.cup.rim_height))
        if down.size:
            i = top + int(down[0])
            w = (rel_z[i] - model.cup.rim_height) / (rel_z[i] - rel_z[i + 1])
            y = b[i, 1] + w * (b[i + 1, 1] - b[i, 1]) - pivot.x[0, 1]
            out.append(
                (float(t[i] + w * (t[i + 1] - t[i])), float(y), float((b[i + 1, 1] - b[i, 1]) / (t[i + 1] - t[i])))
            )
    return out


def search_members(r: CatchRequest) -> tuple[BandMember, ...]:
    """The band the catch search judges each candidate on: SEARCH_LENGTHS lengths across the band, each with the cup
    one period early, on time and late, the ball's mass rotating over those timings — every length is judged with
    every mass (the drag moves the landing by a few millimetres, which decides a ball grazing the rim) at no more
    members."""
    m = r.model
    lengths = m.length * (1 + r.length_tol * np.linspace(-1.0, 1.0, SEARCH_LENGTHS)) if r.length_tol else [m.length]
    shifts = (-r.dt, 0.0, r.dt) if r.timing else (0.0,)
    masses = m.ball.mass * (1.0 + r.mass_tol * np.array([0.0, -1.0, 1.0]))
    return tuple(
        BandMember(float(ln), float(masses[(i + j) % 3]), s)
        for i, ln in enumerate(lengths)
        for j, s in enumerate(shifts)
    )


class CatchSearch:
    """The catch move's search for one release: a grid over the move's time, position, velocity and coast
    (``grid``), then Nelder–Mead from its best point (``refine``); each candidate judged on the search band
    (``search_members``) stepped from the release on (``band_score``)."""

    def __init__(
        self, r: CatchRequest, rel: Release, p0: np.ndarray, axis: np.ndarray, by: TaskBounds, bz: TaskBounds
    ) -> None:
        m = r.model
        members = search_members(r)
        lengths = tuple(sorted({b.length for b in members}))
        self.r, self.rel, self.p0, self.axis, self.by, self.bz = r, rel, p0, axis, by, bz
        self.band = prepare_band(m, members, rel.pivot, rel.t_start)
        self.lands = band_landings(m, rel.pivot, lengths)
        if not self.lands:
            raise PlanningError("the released ball never comes down through the height of the rim")
        self.cache: dict[tuple, float] = {}
        self.best: tuple[float, np.ndarray] | None = None  # (score, point) of the grid

    def move_of(self, x) -> CatchMove:
        r, t_start = self.r, self.rel.t_start
        return CatchMove(
            t_start,
            max(float(x[0]), t_start + r.dt),
            float(np.clip(x[1], -r.travel, r.travel)),
            float(np.clip(x[2], -r.z_travel, r.z_travel)),
            float(x[3]),
            float(x[4]),
            float(np.clip(x[5], 0.0, MAX_COAST)),
        )

    def score(self, x) -> float:
        """band_score of the move at x = (t_catch, y, z, vy, vz, coast) (memoised; −10 when ruckig cannot plan
        it)."""
        key = tuple(np.round(x, 5))
        if key not in self.cache:
            r, rel = self.r, self.rel
            try:
                path, _ = cup_path(rel.x, rel.v, rel.u, r.dt, self.move_of(x), self.by, self.bz, settle=0.3)
            except PlanningError:
                self.cache[key] = -10.0
                return self.cache[key]
            t = np.arange(len(path)) * r.dt
            pivot = pivot_motion(t, self.p0, path, self.axis)
            outs = judge_band(r.model, self.band, pivot, float(t[-1]), until_missed=True)
            self.cache[key] = band_score(outs, r.model.cup.inner_radius - r.model.ball.radius)
        return self.cache[key]

    def grid(self) -> float:
        """Score the grid around where the band lands (a little before, moving between the pivot's and the balls'
        lateral speed, level or going down, braking at once or coasting over the later landings); the best score."""
        lands = self.lands
        t_land = float(np.mean([x[0] for x in lands]))
        t_last = max(x[0] for x in lands)
        y_land = 0.5 * (min(x[1] for x in lands) + max(x[1] for x in lands))
        vy_ball = float(np.mean([x[2] for x in lands]))
        for dtc in (-0.05, -0.025, 0.0):
            for kappa in (0.0, 0.5, 1.0):
                # braking at once, or coasting until the band's last ball is in (the search refines it)
                coasts = (0.0, float(np.clip(t_last - (t_land + dtc) + COAST_EXTRA, 0.0, MAX_COAST)))
                for (z, vz), coast in itertools.product(((0.0, 0.0), (-0.02, -0.5 * self.bz.v_max)), coasts):
                    vy = kappa * vy_ball + (1.0 - kappa) * float(self.rel.v[-1])
                    x = np.array([t_land + dtc, y_land + vy * dtc, z, vy, vz, coast])
                    s = self.score(x)
                    if self.best is None or s > self.best[0]:
                        self.best = (s, x)
        return self.best[0]

    def refine(self) -> CatchMove:
        """Nelder–Mead from the grid's best point; the better of the two."""
        from scipy.optimize import minimize

        if self.best is None:
            self.grid()
        s0, x0 = self.best
        simplex = [x0] + [x0 + d for d in np.diag([0.02, 0.01, 0.01, 0.2, 0.1, 0.04])]
        res = minimize(
            lambda x: -self.score(x),
            x0,
            method="Nelder-Mead",
            options={"maxfev": self.r.catch_evaluations, "initial_simplex": simplex, "xatol": 1e-3, "fatol": 1e-3},
        )
        return self.move_of(res.x if -res.fun >= s0 else x0)


def _split_ratios(traj: JointTrajectory, limits: JointLimits, k: int) -> tuple[dict[str, float], dict[str, float]]:
    """Peak |joint rate| / limit of velocity, acceleration and jerk before sample k and from it on."""
    from trajectories.differences import derivatives

    rates = dict(zip(("velocity", "acceleration", "jerk"), derivatives(traj.q, traj.dt, 3)))
    lim = {"velocity": limits.velocity, "acceleration": limits.acceleration, "jerk": limits.jerk}
    ratio = {q: np.abs(v) / lim[q] for q, v in rates.items()}
    return ({q: float(v[:k].max()) for q, v in ratio.items()}, {q: float(v[k:].max()) for q, v in ratio.items()})


def _rescaled(bounds: TaskBounds, peaks: dict[str, float], target: float) -> TaskBounds:
    """Bounds with each of speed, acceleration and jerk scaled by target / its joint peak ratio (never up)."""
    f = {q: min(1.0, 0.97 * target / max(v, 1e-9)) for q, v in peaks.items()}
    return TaskBounds(bounds.v_max * f["velocity"], bounds.a_max * f["acceleration"], bounds.j_max * f["jerk"])


def judge_path(
    r: CatchRequest, traj: JointTrajectory, robot: Robot, t_start: float, members: tuple[BandMember, ...] | None = None
) -> tuple[BallRun, CatchOutcome, BandResult]:
    """The verdict on a joint path: the event-driven prediction of the nominal ball under the TCP path the joints
    realise, and every band member stepped along the same path (from ``t_start`` on they share nothing)."""
    pos, rot = robot.fk_path(traj.q)
    axes = rot @ np.asarray(r.model.axis_flange)
    pivot = PivotMotion(traj.t, pos, axes)
    end = float(traj.t[-1])
    run = simulate_string(r.model, pivot, end)
    nominal = outcome(run.events, run.final_phase == RESTING, run.final_inside)
    members = members or band_members(
        r.model.length,
        r.model.ball.mass,
        r.dt,
        r.length_tol,
        r.mass_tol,
        n_length=BAND_LENGTHS if r.length_tol else 1,
        n_mass=3 if r.mass_tol else 1,
        timing=r.timing,
    )
    band = prepare_band(r.model, members, pivot, min(t_start, end))
    return run, nominal, BandResult(members, tuple(judge_band(r.model, band, pivot, end)))


@dataclass(frozen=True)
class _Arm:
    """What every variant of a plan shares: the robot, its limits, the arm setup, the anchor's start [m], the cup
    axis at the start pose (unit), and the first bounds of the swing-up along y and of the catch move along y, z."""

    robot: Robot
    limits: JointLimits
    setup: ArmSetup
    p0: np.ndarray
    axis: np.ndarray
    bounds: tuple[TaskBounds, TaskBounds, TaskBounds]


def _arm(r: CatchRequest, robot: Robot, limits: JointLimits) -> _Arm:
    """Validate the request's model and start pose; the bounds the joint limits allow the pivot there."""
    r.model.validate()
    if r.model.cup is None:
        raise PlanningError("the cup-and-ball plan needs a cup")
    axis = cup_axis_at_start(robot, r.model, r.q_start)
    tilt = math.acos(max(-1.0, min(1.0, float(axis[2]))))
    if tilt > MAX_AXIS_TILT:
        raise PlanningError(
            f"the cup opens {math.degrees(tilt):.0f}° away from straight up at the start pose; the "
            f"catch needs it within {math.degrees(MAX_AXIS_TILT):.0f}° (Cup.axis, CatchRequest.q_start)"
        )
    setup = ArmSetup(q_start=tuple(float(v) for v in r.q_start), orientation="follow")
    p0 = robot.fk(np.asarray(r.q_start, dtype=float)).translation
    try:
        # first-order bounds for the swing-up, its jerk lowered by what the second-order terms usually add (a swing-up
        # re-planned after a limit violation is another swing-up: better to fit the first time)
        by = axis_bounds(robot, setup, limits, r.travel, r.limit_margin, first_order=True)
        by = TaskBounds(by.v_max, by.a_max, SWING_JERK_SHARE * by.j_max)
        # the catch move runs along y and z at once: each gets conservative (second-order) bounds, shared
        my = axis_bounds(robot, setup, limits, r.travel, r.limit_margin).scaled(MOVE_SHARE)
        bz = axis_bounds(robot, setup, limits, r.z_travel, r.limit_margin, axis="z").scaled(MOVE_SHARE)
    except ValueError as exc:
        raise PlanningError(str(exc)) from None
    return _Arm(robot, limits, setup, p0, axis, (by, my, bz))


@dataclass
class _Candidate:
    """A swing-up variant's swing-up and its DE cost, the catch search on its release, the grid's best score."""

    variant: SwingVariant
    swing: PivotPlan
    cost: float
    search: CatchSearch
    grid: float = -math.inf


def _plan_variant(r: CatchRequest, arm: _Arm, c: _Candidate, progress=None) -> CatchResult:
    """A candidate's catch move refined, mapped onto the arm and judged; a limit violation rescales the bounds of the
    part that broke it and plans again (up to 3 attempts)."""
    by, my, bz = arm.bounds
    notes: list[str] = []
    target = 1.0 - r.limit_margin
    swing, search, last = c.swing, c.search, None
    for attempt in range(1, 4):
        try:
            if swing is None:
                swing, _ = _swing_up(r, by, my, c.variant)
            if search is None:
                search = CatchSearch(r, _releases(r, swing, arm.p0, arm.axis), arm.p0, arm.axis, my, bz)
            rel, move = search.rel, search.refine()
        except PlanningError as exc:
            if last is None:
                raise
            notes.append(f"attempt {attempt} with bounds scaled down: {exc}; the previous attempt is kept")
            break
        path, _ = cup_path(rel.x, rel.v, rel.u, r.dt, move, my, bz, settle=SETTLE)
        t = np.arange(len(path)) * r.dt
        traj, ik_err = joint_path(arm.robot, arm.setup, t, path, arm.limits, progress)
        report = check_trajectory(traj, arm.limits, jerk=True)
        last = (swing, move, path, traj, ik_err, report, rel.t_start, (by, my, bz))
        ratios = {q: report.ratios()[q] for q in ("velocity", "acceleration", "jerk")}
        notes.append(f"attempt {attempt}: peak ratios " + ", ".join(f"{q} {v.max():.2f}" for q, v in ratios.items()))
        if report.ok:
            break
        swing_peak, move_peak = _split_ratios(traj, arm.limits, int(round(rel.t_start / r.dt)))
        search = None
        if max(swing_peak.values()) > target:  # the swing-up breaks a limit: pump with tighter bounds, search again
            by, swing = _rescaled(by, swing_peak, target), None
        else:  # only the catch move does: move within tighter bounds
            my, bz = _rescaled(my, move_peak, target), _rescaled(bz, move_peak, target)
    swing, move, path, traj, ik_err, report, t_start, bounds = last
    run, nominal, band = judge_path(r, traj, arm.robot, t_start)
    return CatchResult(
        r, swing, move, path, traj, report, run, nominal, band, bounds, ik_err, 0.0, tuple(notes), variant=c.variant
    )


def _rank(res: CatchResult) -> tuple:
    """What the choice among variants maximises: a valid plan (the nominal ball caught within the joint limits and
    the time asked), then — without a max_time — one that meets the goals (enters the cup within QUICK_TIME and
    catches at least min_success of the band), then the share of the band caught, then the earlier entry."""
    n, r = res.nominal, res.request
    in_time = r.max_time is None or (n.t_entry is not None and n.t_entry <= r.max_time)
    valid = n.caught and res.check.ok and in_time
    return (valid, valid and _quick(res), res.band.success, -(n.t_entry if n.t_entry is not None else math.inf))


def _quick(res: CatchResult) -> bool:
    """Without a max_time: the plan enters the cup within QUICK_TIME and catches enough of the band."""
    n, r = res.nominal, res.request
    return (
        r.max_time is None and n.t_entry is not None and n.t_entry <= QUICK_TIME and res.band.success >= r.min_success
    )


def fallback_variants(max_time: float | None) -> tuple[SwingVariant, ...]:
    """The swing-ups tried, one at a time, only while no plan so far catches enough of the band: without a max_time,
    from rest pumping up to each of FALLBACK_HORIZONS — the swing-up search's optimum moves with its horizon, and
    the band a plan catches with it, in ways no rule foretells (with the command's search settings, at 0.26 m: up to
    3.5 s 74 %, 4 s 93 %, 5 s 96 %; a 0.28 m string in a 26 mm cup: 3.5 s 99 %, 4 s 70 %; a 0.33 m string: 75 %
    from the first three, 100 % pumping up to 8 s).
    With a max_time, the cruising release searched with the release deadline the time asked allows, no later
    (longer pumping is too late). With a max_time of 3 s, at lengths between the benchmark's: 0.22 m 76 -> 99 % of
    the band, 0.32 m 56 % entering 0.3 s late -> 78 % in time, 0.27 m none better (38 % against the others' 52 %)."""
    if max_time is not None:
        return (SwingVariant(True, max_time + 1.25, 0.0),)
    return tuple(SwingVariant(False, h) for h in FALLBACK_HORIZONS)


QUICK_FALLBACK = SwingVariant(True, QUICK_TIME + 1.25, 0.0, quick=QUICK_TIME)  # without the deadline's slack


def stages(max_time: float | None) -> tuple[tuple[tuple[SwingVariant, ...], str], ...]:
    """The swing-ups planned, stage by stage, each stage (variants, kind). With a max_time: the ``swing_variants``
    together ("main"), then each fallback while no plan catches enough of the band ("fallback"). Without one, first
    the quick variants one at a time ("quick": the cruising release searched as for QUICK_TIME, with the deadline's
    slack, then without it — at 0.2 m the first caught 98 % of the band, at 0.16 m the second 100 % where the first
    had no plan), the planning ending at the first plan that meets the goals; then the rest release's variants
    together ("main") and its fallbacks as with a max_time."""
    if max_time is not None:
        return ((swing_variants(max_time), "main"), *(((v,), "fallback") for v in fallback_variants(max_time)))
    first = tuple(v for v in swing_variants(None) if v.quick is not None)
    rest = tuple(v for v in swing_variants(None) if v.quick is None)
    quick = tuple(((v,), "quick") for v in (*first, QUICK_FALLBACK))
    return (*quick, (rest, "main"), *(((v,), "fallback") for v in fallback_variants(None)))


def _refined(kind: str, candidates: list) -> list:
    """The candidates of a stage (best catch grid first) whose catch move is refined: the REFINED best, those after
    the first only when their grid scores at least QUICK_GRID; in a quick stage the candidate only then. No grid
    under it has refined to a plan that catches enough of the band (with a max_time of 3 s: 0.37 to 44 % and 0.27
    to none at 0.35 m, 0.29 to 44 % at 0.25 m, -0.21 to none at 0.16 m; the most, 0.30 to 63 % at 0.27 m)."""
    if kind == "quick":
        return [c for c in candidates if c.grid >= QUICK_GRID]
    top = list(candidates[:REFINED])
    return top[:1] + [c for c in top[1:] if c.grid >= QUICK_GRID]


def _candidates(r: CatchRequest, arm: _Arm, notes: list[str], variants: tuple[SwingVariant, ...]) -> list[_Candidate]:
    """Each variant's swing-up and the catch grid on its release, best grid score first (a swing-up search that
    missed its release goal by a little can still catch most of the band); what failed goes to ``notes``."""
    by, my, bz = arm.bounds
    out = []
    for variant in variants:
        try:
            swing, cost = _swing_up(r, by, my, variant)
            search = CatchSearch(r, _releases(r, swing, arm.p0, arm.axis), arm.p0, arm.axis, my, bz)
        except PlanningError as exc:
            notes.append(f"{variant.describe()}: {exc}")
            continue
        out.append(_Candidate(variant, swing, cost, search))
    if not out:
        return out
    for c in out:
        c.grid = c.search.grid()
        missed = " (missed its release goal)" if c.cost >= GOAL_MISSED else ""
        notes.append(f"{c.variant.describe()}: swing-up cost {c.cost:.2f}{missed}, catch grid score {c.grid:.3f}")
    return sorted(out, key=lambda c: -c.grid)


def plan_catch(r: CatchRequest, robot: Robot, limits: JointLimits, progress=None) -> CatchResult:
    """Plan, map onto the arm, check and judge a cup-and-ball catch, stage by stage (``stages``): each stage's
    swing-ups with the catch grid on their releases, then the catch move refined and judged on the whole band for
    those ``_refined`` picks (stopping early at a valid plan that meets the goals or catches the whole band); the plan
    ``_rank`` puts first. Raises PlanningError if no plan can be made."""
    start = time.perf_counter()
    arm = _arm(r, robot, limits)
    notes: list[str] = []
    best = None
    for variants, kind in stages(r.max_time):
        if best is not None and (_rank(best)[:2] == (True, True) or kind == "fallback" and best.failure() is None):
            break  # the goals met, or (for a fallback) a plan that catches enough of the band
        for c in _refined(kind, _candidates(r, arm, notes, variants)):
            try:
                res = _plan_variant(r, arm, c, progress)
            except PlanningError as exc:
                notes.append(f"{c.variant.describe()}: {exc}")
                continue
            notes.append(f"{c.variant.describe()}: catches {100 * res.band.success:.0f} % of the band")
            if best is None or _rank(res) > _rank(best):
                best = res
            if _rank(best)[:2] == (True, True) or _rank(best)[:3] == (True, False, 1.0):
                break  # the goals met (the quick plan), or the whole band caught
    if best is None:
        raise PlanningError("; ".join(notes))
    return replace(best, planning_time=time.perf_counter() - start, notes=(*best.notes, *notes))
