"""The cup-and-ball swing-up: pump the swing (taut), end the pivot's acceleration, and let the free swing release the ball.

The pumping is the fast method's (``swingup_fast``: bang-bang energy pumping, jerk-limited by ruckig) with the
tension governor on, so that the string stays taut while the pivot accelerates and the planar model is exact there.
The pivot then moves at a constant velocity (``FastParams.cruise``; 0: at rest), and the ball's free swing goes
slack by itself where l·θ̇² + g·cos θ = 0, i.e. at cos θ_s = −2E/(3·g·l) for the swing energy
E = ½·l²·θ̇² − g·l·cos θ (per unit mass): in the pivot's frame — inertial, at constant velocity — the whole flight
that follows depends on E and l only, not on when the ball gets there. Cruising toward where the ball comes down lets
the release be low (θ_s nearer the horizontal, where the landing point hardly depends on E: the strings of the band,
pumped by the same pivot path, end with energies some per cent apart) while the cup is already on its way under it.
The search (differential evolution over the pumping's tuning and the cruise) minimises the release time plus the
spread of the landing points over the string-length band — the same pivot path drives every length of the band
(``FastProblem.band``) — so that one cup position catches them all.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .pendulum import G
from .swingup_fast import FastOutcome, FastProblem
from .swingup_plan import PivotPlan
from .tension import tension_margin


@dataclass(frozen=True)
class ReleaseGoal:
    """What the release must give: the height [m] above the anchor where landings are measured (the ball centre at
    the rim plane), how far [m] the cup may travel after the release to meet them, the landing spread over the band
    the cup can take [m], and what exceeding it costs [s/m]."""

    height: float
    reach: float = 0.05  # [m]
    spread_target: float = 0.0  # [m] a spread up to this costs nothing
    spread_weight: float = 1000.0  # [s/m]: each mm beyond the target costs as much as 1 s of swing-up
    deadline: float = math.inf  # [s] a release later than this costs 1000 per second late (a hard limit)
    min_apex_clearance: float = 0.03  # [m] the flight's apex must clear the landing height by this
    lateral_speed: float = math.inf  # [m/s] the balls' mean lateral speed over the ground at the landing height


@dataclass(frozen=True)
class Landing:
    """A free flight from the release (pivot at rest): release angle [rad] (signed: the side), the crossing of the
    landing height going down relative to the anchor: lateral position y [m], velocity (vy, vz) [m/s], time after
    the release [s], and the flight's apex height [m]."""

    theta: float
    y: float
    vy: float
    vz: float
    t: float
    apex: float


def free_swing_landing(theta: float, theta_dot: float, length: float, height: float) -> Landing | None:
    """Where the ball of a free swing (anchor at rest; state θ [rad], θ̇ [rad/s] while taut) lands at ``height`` [m]
    above the anchor after it goes slack; None if it never goes slack (E ≤ 0 or a taut loop) or flies lower."""
    e = 0.5 * length * theta_dot * theta_dot - G * math.cos(theta)  # [J/kg]/l: energy per unit mass and length
    c = -2.0 * e / (3.0 * G)
    if not -1.0 < c < 0.0:
        return None
    side = math.copysign(1.0, theta_dot if theta_dot != 0.0 else theta)
    ts = math.acos(c)
    v = math.sqrt(-G * length * c)
    y0, z0 = side * length * math.sin(ts), -length * c
    vy, vz = side * v * c, v * math.sin(ts)
    apex = z0 + vz * vz / (2.0 * G)
    if apex < height:
        return None
    t = (vz + math.sqrt(vz * vz - 2.0 * G * (height - z0))) / G
    return Landing(side * ts, y0 + vy * t, vy, vz - G * t, t, apex)


def _release_time(t: np.ndarray, tension: np.ndarray) -> float | None:
    """First time [s] the tension margin crosses zero (linear between samples), None if it never does."""
    after = np.flatnonzero(tension <= 0.0)
    if not after.size:
        return None
    i = int(after[0])
    if i == 0:
        return float(t[0])
    w = tension[i - 1] / (tension[i - 1] - tension[i])
    return float(t[i - 1] + w * (t[i] - t[i - 1]))


@dataclass(frozen=True)
class GroundLanding:
    """A band string's release [s] and its landing over the ground: time [s], y [m] in the swing-up's frame (0 at the
    start), lateral velocity vy [m/s], and the free flight in the pivot's frame it comes from."""

    t_release: float
    t: float
    y: float
    vy: float
    flight: Landing


def ground_landings(problem: FastProblem, plan: PivotPlan, height: float) -> list[GroundLanding | None]:
    """Nominal string first, then ``problem.band``: where each ball lands at ``height`` [m] above the anchor once
    the pivot's acceleration has ended (at rest or cruising at its final velocity: in the pivot's frame the free
    swing is the same). The release time comes from the sampled tension (interpolated), the flight in closed form
    (``free_swing_landing``, no drag). None for a string that is not released or does not reach ``height``."""
    k = min(int(np.searchsorted(plan.t, plan.t_rest - 1e-9)), len(plan.t) - 1)
    band = plan.info["band"]
    lengths = (problem.length, *band["lengths"])
    thetas = np.vstack([plan.theta[None, :], band["theta"]])
    rates = np.vstack([plan.theta_dot[None, :], band["theta_dot"]])
    x_rest, v_end, t_rest = float(plan.x[k]), float(plan.v[k]), float(plan.t[k])
    out: list[GroundLanding | None] = []
    for ln, th, om in zip(lengths, thetas, rates):
        t_rel = _release_time(plan.t[k:], tension_margin(th[k:], om[k:], plan.u[k:], 0.0, ln))
        land = free_swing_landing(float(th[k]), float(om[k]), ln, height)
        if t_rel is None or land is None:
            out.append(None)
            continue
        t_land = t_rel + land.t
        out.append(GroundLanding(t_rel, t_land, x_rest + v_end * (t_land - t_rest) + land.y, v_end + land.vy, land))
    return out


def release_score(problem: FastProblem, plan: PivotPlan) -> FastOutcome:
    """``FastProblem.scorer`` of the cup-and-ball swing-up (``goal``: a ReleaseGoal). Cost: the nominal release time
    [s] + spread_weight × the landing spread over the band beyond the target [m], + 1000 per second past the deadline,
    + 100 and more when the landings' centre is beyond the cup's reach of the pivot (cruising at its final constant
    velocity) when they land, when they fly over the ground faster than ``lateral_speed`` there (the cup could not
    move with them), when the pivot would leave its travel by then, when a string of the band does not fly
    high enough, +1000 and more when the claimed tension drops below ``min_tension`` while the pivot accelerates
    (``ground_landings`` gives the flights)."""
    goal: ReleaseGoal = problem.goal  # type: ignore[assignment]
    k = min(int(np.searchsorted(plan.t, plan.t_rest - 1e-9)), len(plan.t) - 1)
    band = plan.info["band"]
    lengths = (problem.length, *band["lengths"])
    thetas = np.vstack([plan.theta[None, :], band["theta"]])
    rates = np.vstack([plan.theta_dot[None, :], band["theta_dot"]])
    moving = plan.t <= plan.t_rest + 1e-9
    min_tension = min(
        float(tension_margin(th[moving], om[moving], plan.u[moving], 0.0, ln).min())
        for ln, th, om in zip(lengths, thetas, rates)
    )
    penalty = 0.0
    landed = []
    for ln, g in zip(lengths, ground_landings(problem, plan, goal.height)):
        if g is None or g.flight.apex < goal.height + goal.min_apex_clearance:
            penalty += 100.0 + 10.0 * (goal.height + goal.min_apex_clearance - (g.flight.apex if g else -ln))
            continue
        landed.append(g)
    if min_tension < problem.min_tension:
        penalty += 1000.0 + (problem.min_tension - min_tension)
    ys = [g.y for g in landed]
    spread = float(np.ptp(ys)) if len(ys) > 1 else 0.0
    x_rest, v_end, t_rest = float(plan.x[k]), float(plan.v[k]), float(plan.t[k])
    t_land = float(np.mean([g.t for g in landed])) if landed else t_rest
    anchor = x_rest + v_end * (t_land - t_rest)  # [m] where the cruising pivot is when the band lands
    centre = float(np.mean(ys)) if ys else anchor
    if abs(centre - anchor) > goal.reach:
        penalty += 100.0 + 100.0 * (abs(centre - anchor) - goal.reach)
    lateral = abs(float(np.mean([g.vy for g in landed]))) if landed else 0.0
    if lateral > goal.lateral_speed:  # the cup could not move with the ball: a slanted entry into a moving cup
        penalty += 100.0 + 100.0 * (lateral - goal.lateral_speed)
    max_travel = max(float(np.max(np.abs(plan.x[: k + 1]))), abs(anchor))
    if max_travel > problem.travel:
        penalty += 100.0 + 100.0 * (max_travel - problem.travel)
    t_release = landed[0].t_release if landed else problem.horizon + 3.0
    cost = (
        penalty
        + t_release
        + goal.spread_weight * max(0.0, spread - goal.spread_target)
        + 1000.0 * max(0.0, t_release - goal.deadline)
    )
    return FastOutcome(landed[0].t_release if landed else None, spread, max_travel, min_tension, cost)
