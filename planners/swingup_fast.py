"""Fast swing-up: Åström–Furuta energy pumping at the pivot's speed, acceleration and jerk bounds.

From the ball at rest the pivot pumps energy bang-bang: its velocity target flips to −V·sign(θ̇·cos θ)
(minus a centring term −k·x, inside ±v_max) whenever the swing's power sign changes, so the pivot accelerates
as hard as the bounds allow in the direction that feeds the swing (Ė = −u·m·l·θ̇·cos θ). Transitions are
time-optimal and jerk-limited (ruckig, velocity interface, run online at the sample period). The first
half-swing uses a smaller target V₁ so that the pivot oscillates about its start, a band governor brakes
before |x| would leave the travel band, and once the free-swing apex of the ball's energy reaches θ_d + δ
the pivot is brought to rest. (V, V₁, k, δ) are tuned by differential evolution (scipy) to reach θ_d
soonest, candidates evaluated in parallel processes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Callable

import numpy as np

from trajectories.errors import PlanningError

from .pendulum import G, natural_period
from .swingup_plan import PivotPlan, StopProfile, TaskBounds, first_reach
from .tension import tension_margin

try:  # the compiled step (setup.py builds it when a C compiler is present); else planar_rk4_py below
    from . import _planar
except ImportError:  # pragma: no cover - depends on the install
    _planar = None


@dataclass(frozen=True)
class FastProblem:
    """What the fast swing-up must do: string, target, bounds of the pivot, band and sampling."""

    length: float  # [m]
    theta_d: float  # [rad]
    bounds: TaskBounds
    travel: float = 0.3  # [m] half-width of the band the pivot must stay in
    dt: float = 0.005  # [s] sample step
    horizon: float = 10.0  # [s] longest pumping time
    tolerance: float = math.radians(2.0)  # [rad] θ_d counts as reached at θ_d − tolerance
    overshoot: float = math.radians(5.0)  # [rad] largest accepted apex above θ_d
    theta0: float = 0.0  # [rad]
    theta_dot0: float = 0.0  # [rad/s]
    taut: bool = False  # require positive tension (claimed) until θ_d is reached (or until the highest angle)
    min_tension: float = 0.5  # [m/s²] tension margin required with ``taut`` or ``release``
    release: bool = False  # cup-and-ball: taut while pumping, then the free swing of energy ≈ θ_d releases the ball
    cruise: bool = True  # ``release`` only: the pivot may end at a constant velocity (False: it ends at rest)
    governor_margin: float = 1.0  # [m/s²] the governor aims this far above min_tension (the jerk limit lags it)
    governor: bool = False  # cap the acceleration to keep the claimed tension even without ``taut`` (often quicker)
    band: tuple[float, ...] = ()  # string lengths (× length) also driven by the planned pivot path (info["band"])
    scorer: Callable[["FastProblem", PivotPlan], "FastOutcome"] | None = None  # replaces ``score`` (module-level)
    goal: object = None  # what ``scorer`` aims at (a picklable frozen dataclass of its own)

    @property
    def governed(self) -> bool:
        """The pumping acceleration is capped to keep the claimed tension (``taut`` or ``release``)."""
        return self.taut or self.release or self.governor


@dataclass(frozen=True)
class FastParams:
    """Tuning of the pumping: pumping speed V and first-swing speed V₁ as fractions of v_max, centring gain
    k [1/s], the energy at which pumping stops, as its free-swing apex offset δ from θ_d [rad], and (``release``
    only) the constant velocity the pivot ends at, as a signed fraction of v_max (0: at rest)."""

    speed: float = 0.8
    first_speed: float = 0.5
    centring: float = 1.0
    apex_offset: float = 0.0
    cruise: float = 0.0

    @classmethod
    def from_vector(cls, v) -> "FastParams":
        return cls(*(float(a) for a in v))


def param_ranges(problem: "FastProblem") -> tuple[tuple[float, float], ...]:
    """Search box of (speed, first_speed, centring, apex_offset). The apex offset may aim well below θ_d (a pump
    stopped early can still carry the ball to θ_d; with ``taut`` the highest taut swing aims near 90° whatever θ_d),
    ``release`` aims within ±0.3 rad of θ_d (the apex energy is what it asks for) and (with ``cruise``) ends at a
    cruise speed of up to 0.8 v_max either way (a pivot at constant velocity leaves the free swing as it is at rest:
    the cup is already on its way to where the ball will land)."""
    if problem.release:
        pumping = ((0.3, 1.0), (0.1, 1.0), (0.0, 6.0), (-0.3, 0.3))
        return (*pumping, (-0.8, 0.8)) if problem.cruise else pumping
    low = -max(0.4, min(problem.theta_d - 0.2, problem.theta_d - math.pi / 2 + 0.3))
    return ((0.3, 1.0), (0.1, 1.0), (0.0, 6.0), (low, 0.4))


@dataclass(frozen=True)
class FastOutcome:
    """Score of one candidate: claimed reach time [s] (None if not reached), peak |θ| [rad], peak |x| [m],
    min claimed tension margin [m/s²], and the scalar cost minimised by the search."""

    t_reach: float | None
    max_theta: float
    max_travel: float
    min_tension: float
    cost: float


def tension_window(
    theta: float, theta_dot: float, length: float, min_tension: float, a_max: float, lookahead: float
) -> tuple[float, float]:
    """Pivot accelerations (lo, hi) [m/s²] along the swing axis that keep l·θ̇² + g·cos θ − u·sin θ ≥ min_tension
    [m/s²] now and at the angle ``lookahead`` [s] ahead (the jerk limit makes a cap act late), within ±a_max. The
    window may exclude 0: near an apex above 90° the pivot must accelerate away from the ball."""
    lo, hi = -a_max, a_max
    base = length * theta_dot * theta_dot - min_tension
    for k, th in enumerate((theta, theta + theta_dot * lookahead)):
        c, sn = base + G * math.cos(th), math.sin(th)
        new_lo, new_hi = lo, hi
        if sn > 1e-3:
            new_hi = min(hi, c / sn)
        elif sn < -1e-3:
            new_lo = max(lo, c / sn)
        if k and new_lo > new_hi:  # the look-ahead contradicts the present: the present wins
            break
        lo, hi = new_lo, new_hi
    return max(lo, -a_max), min(hi, a_max)


def planar_rk4(th: float, om: float, a0: float, a1: float, h: float, length: float) -> tuple[float, float]:
    """One RK4 step h [s] of the planar pendulum (θ [rad], θ̇ [rad/s]) with the pivot acceleration going linearly
    from a0 to a1 [m/s²] (``cartpole.theta_ddot``); compiled (``_planar``) when built, equal to the last bit."""
    if _planar is not None:
        return _planar.rk4(th, om, a0, a1, h, length, G)
    return planar_rk4_py(th, om, a0, a1, h, length)


def planar_rk4_py(th: float, om: float, a0: float, a1: float, h: float, length: float) -> tuple[float, float]:
    """``planar_rk4`` in pure Python (the fallback without the compiled extension)."""
    il, gl = 1.0 / length, G / length
    am = 0.5 * (a0 + a1)
    k1t, k1o = om, -a0 * il * math.cos(th) - gl * math.sin(th)
    t2, o2 = th + 0.5 * h * k1t, om + 0.5 * h * k1o
    k2t, k2o = o2, -am * il * math.cos(t2) - gl * math.sin(t2)
    t3, o3 = th + 0.5 * h * k2t, om + 0.5 * h * k2o
    k3t, k3o = o3, -am * il * math.cos(t3) - gl * math.sin(t3)
    t4, o4 = th + h * k3t, om + h * k3o
    k4t, k4o = o4, -a1 * il * math.cos(t4) - gl * math.sin(t4)
    return th + h / 6.0 * (k1t + 2 * k2t + 2 * k3t + k4t), om + h / 6.0 * (k1o + 2 * k2o + 2 * k3o + k4o)


def _jerk_step(x: float, v: float, a: float, want: float, pb: TaskBounds, h: float) -> tuple[float, float, float]:
    """One step h [s] of the pivot turning its acceleration toward ``want`` [m/s²] at the jerk limit, the speed kept
    within v_max (the acceleration is released when the speed would pass it)."""
    a1 = a + max(-pb.j_max * h, min(pb.j_max * h, want - a))
    v1 = v + 0.5 * (a + a1) * h
    if abs(v1) > pb.v_max:
        a1 = a + max(-pb.j_max * h, min(pb.j_max * h, -a))
        v1 = v + 0.5 * (a + a1) * h
    return x + v * h + h * h * (2.0 * a + a1) / 6.0, v1, a1


@dataclass(frozen=True)
class _Policy:
    """The pumping policy's constants for one candidate: the energy at which pumping stops [J/kg], the target
    speeds [m/s] of the first half-swing, the pumping and the end (cruise or 0), the centring gain [1/s] and the
    string's natural period [s]."""

    e_stop: float
    v_first: float
    v_pump: float
    v_end: float
    centring: float
    t0: float

    @classmethod
    def of(cls, problem: FastProblem, params: FastParams) -> "_Policy":
        pb, l = problem.bounds, problem.length
        apex_stop = problem.theta_d + params.apex_offset
        return cls(
            e_stop=-G * l * math.cos(min(apex_stop, math.pi)),  # per unit mass [J/kg]
            v_first=params.first_speed * pb.v_max,
            v_pump=params.speed * pb.v_max,
            v_end=params.cruise * pb.v_max if problem.release else 0.0,  # [m/s] the pivot's final constant velocity
            centring=params.centring,
            t0=natural_period(l),
        )


def _velocity_generator(pb: TaskBounds, h: float):
    """A one-axis ruckig generator on the velocity interface at the pivot's bounds, from rest at 0; (otg, in, out)."""
    from ruckig import ControlInterface, InputParameter, OutputParameter, Ruckig

    otg = Ruckig(1, h)
    inp, out = InputParameter(1), OutputParameter(1)
    inp.control_interface = ControlInterface.Velocity
    inp.current_position, inp.current_velocity, inp.current_acceleration = [0.0], [0.0], [0.0]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [pb.v_max], [pb.a_max], [pb.j_max]
    inp.target_acceleration = [0.0]
    return otg, inp, out


def _next_phase(problem: FastProblem, pol: _Policy, phase: str, t: float, th: float, om: float) -> str:
    """The first half-swing turns to pumping once the swing feeds on the pivot's motion; pumping stops at the
    policy's energy or the horizon ("first", "pump", "stop", "rest")."""
    l = problem.length
    e = 0.5 * l * l * om * om - G * l * math.cos(th)
    if phase in ("first", "pump") and (e >= pol.e_stop or t >= problem.horizon):
        return "stop"
    if phase == "first" and t > 0.1 * pol.t0 and om * math.cos(th) > 0.0:
        return "pump"
    return phase


def _target_velocity(
    problem: FastProblem, pol: _Policy, phase: str, s: float, x: float, v: float, a: float, power_sign: float
) -> tuple[float, float]:
    """The pivot's velocity target [m/s] in this phase, and the sign of the swing's power (kept while it is 0): while
    pumping −V·sign(θ̇·cos θ) − k·x within ±v_max, 0 when a stop started now would leave the travel band."""
    if phase == "first":
        return pol.v_first, power_sign
    if phase != "pump":
        return pol.v_end, power_sign
    pb = problem.bounds
    if s != 0.0:
        power_sign = math.copysign(1.0, s)
    target = -power_sign * pol.v_pump - pol.centring * x
    target = max(-pb.v_max, min(pb.v_max, target))
    # band governor: brake if a stop started now would leave the band
    if abs(x) > problem.travel - (v * v / pb.a_max + abs(v) * pb.a_max / pb.j_max + 0.02) and v != 0.0:
        end = StopProfile(v, a, pb).distance + x  # [m] where a stop started now would rest
        if end > problem.travel if v > 0 else end < -problem.travel:
            target = 0.0
    return target, power_sign


def _pivot_step(problem: FastProblem, generator, phase: str, target: float, th: float, om: float, x, v, a):
    """One sample step of the pivot toward ``target`` [m/s]: (x, v, a) after it and ruckig's result. Governed, the
    acceleration stays within the tension window (or, when the window excludes 0, is forced away from the ball at
    the jerk limit) until the pivot rests."""
    from ruckig import Result

    otg, inp, out = generator
    pb, l, h = problem.bounds, problem.length, problem.dt
    forced = None
    if problem.governed and phase != "rest":
        lo, hi = tension_window(th, om, l, problem.min_tension + problem.governor_margin, pb.a_max, pb.a_max / pb.j_max)
        if lo > 0.0 or hi < 0.0:  # the pivot must accelerate away from the ball: as hard as the jerk allows
            forced = lo if lo > 0.0 else hi
        else:
            floor = 0.02 * pb.a_max
            inp.min_acceleration, inp.max_acceleration = [min(lo, -floor)], [max(hi, floor)]
    if forced is not None:
        x1, v1, a1 = _jerk_step(x, v, a, forced, pb, h)
        inp.current_position, inp.current_velocity, inp.current_acceleration = [x1], [v1], [a1]
        return x1, v1, a1, Result.Working
    inp.target_velocity = [target]
    res = otg.update(inp, out)
    if res not in (Result.Working, Result.Finished):
        raise PlanningError(f"ruckig failed during the fast swing-up: {res}")
    x1, v1, a1 = out.new_position[0], out.new_velocity[0], out.new_acceleration[0]
    out.pass_to_input(inp)
    return x1, v1, a1, res


def simulate_fast(problem: FastProblem, params: FastParams) -> PivotPlan:
    """Run the pumping policy with the planar model (RK4, pivot acceleration linear within a step).

    With ``problem.governed`` the acceleration is capped every step (``tension_window``) until the pivot rests, so
    that the claimed tension stays above ``min_tension`` while the pivot moves."""
    from ruckig import Result

    l, h = problem.length, problem.dt
    pol = _Policy.of(problem, params)
    generator = _velocity_generator(problem.bounds, h)
    band_l = [l * f for f in problem.band]
    band_y = [(problem.theta0, problem.theta_dot0) for _ in band_l]
    band_rec = [([problem.theta0], [problem.theta_dot0]) for _ in band_l]
    th, om = problem.theta0, problem.theta_dot0
    x = v = a = 0.0
    rec = ([0.0], [0.0], [0.0], [0.0], [th], [om])  # t, x, v, u, θ, θ̇
    phase, t, t_rest, t_stop, power_sign = "first", 0.0, None, None, 0.0
    rk4 = None if _planar is None else _planar.rk4  # (planar_rk4 without its call: three per step of every candidate)
    for _ in range(int((problem.horizon + 3.0 * pol.t0) / h) + 2):
        new_phase = _next_phase(problem, pol, phase, t, th, om)
        if new_phase == "stop" and phase != "stop":
            t_stop = t
        phase = new_phase
        target, power_sign = _target_velocity(problem, pol, phase, om * math.cos(th), x, v, a, power_sign)
        x1, v1, a1, res = _pivot_step(problem, generator, phase, target, th, om, x, v, a)
        if rk4 is None:
            th, om = planar_rk4_py(th, om, a, a1, h, l)
        else:
            th, om = rk4(th, om, a, a1, h, l, G)
        for i, lb in enumerate(band_l):  # the same pivot path on the other strings (open loop)
            band_y[i] = planar_rk4_py(*band_y[i], a, a1, h, lb) if rk4 is None else rk4(*band_y[i], a, a1, h, lb, G)
            band_rec[i][0].append(band_y[i][0]), band_rec[i][1].append(band_y[i][1])
        x, v, a = x1, v1, a1
        t += h
        for column, value in zip(rec, (t, x, v, a, th, om)):
            column.append(value)
        if phase == "stop" and res == Result.Finished and abs(v - pol.v_end) < 1e-12 and abs(a) < 1e-12:
            phase, t_rest = "rest", t
        if phase == "rest" and t >= t_rest + 0.5 * pol.t0:
            break
    return _fast_plan(problem, params, rec, band_l, band_rec, t if t_rest is None else t_rest, t_stop)


def _fast_plan(problem: FastProblem, params: FastParams, rec, band_l, band_rec, t_rest: float, t_stop) -> PivotPlan:
    """The PivotPlan of a simulated pumping: the recorded columns (t, x, v, u, θ, θ̇) on uniform times, the band's
    swings under the same pivot path in ``info["band"]``."""
    _, xs, vs, us, ths, oms = rec
    h, n = problem.dt, len(rec[0])
    tt = np.arange(n) * h  # uniform times (no accumulated rounding)
    theta, theta_dot, u = np.array(ths), np.array(oms), np.array(us)
    reach_angle = problem.theta_d - problem.tolerance
    return PivotPlan(
        method="fast",
        t=tt,
        x=np.array(xs),
        v=np.array(vs),
        u=u,
        theta=theta,
        theta_dot=theta_dot,
        tension=tension_margin(theta, theta_dot, u, 0.0, problem.length),
        theta_d=problem.theta_d,
        reach_angle=reach_angle,
        t_reach=first_reach(tt, theta, reach_angle),
        t_rest=float(t_rest),
        info={
            "params": params,
            "bounds": problem.bounds,
            "travel_m": problem.travel,
            "t_stop": t_stop if t_stop is not None else t_rest,
            "band": {
                "lengths": tuple(band_l),
                "theta": np.array([r[0] for r in band_rec]).reshape(len(band_l), n),
                "theta_dot": np.array([r[1] for r in band_rec]).reshape(len(band_l), n),
            },
        },
    )


def score(problem: FastProblem, plan: PivotPlan) -> FastOutcome:
    """Cost: the reach time if θ_d is reached inside the band, else a penalty > 100 (growing with the missing
    angle, so that a search that cannot reach θ_d finds the highest angle); slack with ``taut`` costs > 1000.
    A problem with its own ``scorer`` (a module-level function, picklable) is scored by it."""
    if problem.scorer is not None:
        return problem.scorer(problem, plan)
    max_theta = plan.max_theta
    max_travel = float(np.max(np.abs(plan.x)))
    # ``taut``: the string must hold until θ_d is reached (or, short of it, until the highest angle): a pivot that then
    # rests leaves a swing above 90° that goes slack at its next apex whatever the plan does
    until = plan.t_reach if plan.t_reach is not None else float(plan.t[int(np.argmax(np.abs(plan.theta)))])
    min_tension = float(np.min(plan.tension[plan.t <= until + 1e-9]))
    penalty = 0.0
    if plan.t_reach is None:
        penalty += 100.0 + 10.0 * (problem.theta_d - max_theta)
    over = max_theta - (problem.theta_d + problem.overshoot)
    if over > 0:
        penalty += 100.0 + 10.0 * over
    if max_travel > problem.travel:
        penalty += 100.0 + 100.0 * (max_travel - problem.travel)
    if problem.taut and min_tension < problem.min_tension:  # a hard constraint: worse than any miss
        penalty += 1000.0 + (problem.min_tension - min_tension)
    cost = penalty + (plan.t_reach if plan.t_reach is not None else problem.horizon)
    return FastOutcome(plan.t_reach, max_theta, max_travel, min_tension, cost)


def evaluate(problem: FastProblem, params: FastParams) -> FastOutcome:
    """Simulate and score one candidate (picklable: runs in worker processes)."""
    return score(problem, simulate_fast(problem, params))


def _cost(vector: np.ndarray, problem: FastProblem) -> float:
    return evaluate(problem, FastParams.from_vector(vector)).cost


def _ignore_sigint() -> None:
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)


def worker_pool(processes: int):
    """A process pool whose workers ignore SIGINT: Ctrl-C reaches only the parent, which terminates them
    (no traceback from every worker, no wait for the running candidates)."""
    import multiprocessing

    return multiprocessing.Pool(processes, initializer=_ignore_sigint)


@dataclass(frozen=True)
class SearchSettings:
    """Differential evolution settings: population multiplier, generations, seed, worker processes."""

    popsize: int = 6
    maxiter: int = 16
    seed: int = 1
    workers: int = 2
    coarse_dt: float = 0.005  # [s] step used while searching (the final plan uses the problem's dt)


def optimise(
    problem: FastProblem, settings: SearchSettings = SearchSettings(), start: FastParams | None = None
) -> tuple[FastParams, FastOutcome]:
    """Tune FastParams for the soonest reach (scipy differential evolution, parallel candidates).

    ``start`` seeds the population (e.g. the best of a previous search with other bounds).
    """
    from scipy.optimize import differential_evolution

    coarse = replace(problem, dt=max(problem.dt, settings.coarse_dt))
    ranges = param_ranges(problem)
    kwargs = dict(
        args=(coarse,),
        popsize=settings.popsize,
        maxiter=settings.maxiter,
        seed=settings.seed,
        polish=False,
        tol=1e-3,
        init="sobol",
        updating="deferred",
    )
    if start is not None:
        x0 = [start.speed, start.first_speed, start.centring, start.apex_offset, start.cruise][: len(ranges)]
        kwargs["x0"] = np.clip(x0, [r[0] for r in ranges], [r[1] for r in ranges])
    if settings.workers > 1:
        pool = worker_pool(settings.workers)
        try:
            res = differential_evolution(_cost, ranges, workers=pool.map, **kwargs)
            pool.close()
        except BaseException:  # Ctrl-C or an error: end the workers now, do not wait for their candidates
            pool.terminate()
            raise
        finally:
            pool.join()
    else:
        res = differential_evolution(_cost, ranges, **kwargs)
    best = FastParams.from_vector(res.x)
    return best, evaluate(problem, best)
