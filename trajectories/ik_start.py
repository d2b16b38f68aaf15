"""Choosing the start configuration of a path IK when none is given.

Candidates are the inverse solutions of the first pose reached from a few seed configurations, closed under
the iiwa's configuration flips — shoulder (A1 ± π, −A2, A3 ± π), elbow (A3 ± π, −A4, A5 ± π) and wrist
(A5 ± π, −A6, A7 ± π), which leave the flange pose unchanged. Each candidate is scored by a quick sequential
pass over the path sampled every ``SCORE_DT``: how far it gets, then the smallest distance to a position
limit along the way. The best candidates are tried on the full path in order.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from .arm_angle import ArmGeometry
from .errors import IkError
from .ik import IkResult, PathSolver, _Stall
from .ik_plan import PlanTargets, best_plan
from .resample import spaced_indices
from .start_poses import THESIS_START

SCORE_DT = 0.1  # [s] sample spacing of the scoring pass
DISTINCT = 0.05  # [rad] candidates closer than this (all joints) count as one
EXTRA_TRIES = 24  # further candidates tried (coarse pass) when the best-scored ones stall
PER_CLASS = 1  # candidates scored per configuration class (signs of A2, A4, A6), most comfortable first
SEEDS = (
    THESIS_START,
    (0.0, 0.6, 0.0, -1.2, 0.0, 0.9, 0.0),
    (0.0, -0.6, 0.0, 1.2, 0.0, -0.9, 0.0),
    (0.0, 0.6, 1.2, -1.2, -1.2, 0.9, 0.0),
    (0.0, 0.6, -1.2, -1.2, 1.2, 0.9, 0.0),
)
FLIPS = (
    ((0, 1.0), (1, -1.0), (2, 1.0)),  # shoulder: A1 + π, −A2, A3 + π
    ((2, 1.0), (3, -1.0), (4, 1.0)),  # elbow: A3 + π, −A4, A5 + π
    ((4, 1.0), (5, -1.0), (6, 1.0)),  # wrist: A5 + π, −A6, A7 + π
)


def _flipped(q: np.ndarray, flip: tuple[tuple[int, float], ...], limits: np.ndarray) -> list[np.ndarray]:
    """The configurations a flip maps q to (both ±π choices of each turned joint that fit the limits)."""
    out = [q.copy()]
    for j, kind in flip:
        nxt = []
        for c in out:
            if kind < 0:
                c = c.copy()
                c[j] = -c[j]
                nxt.append(c)
            else:
                for turn in (math.pi, -math.pi):
                    d = c.copy()
                    d[j] += turn
                    if abs(d[j]) <= limits[j]:
                        nxt.append(d)
        out = nxt
    return out


def start_candidates(solver: PathSolver, seeds=SEEDS) -> list[np.ndarray]:
    """Distinct inverse solutions of the first pose inside the position limits, [rad]."""
    opt = solver.options
    found: list[np.ndarray] = []

    def add(q: np.ndarray, q_ref: np.ndarray, gain: float) -> np.ndarray | None:
        q, ep, er, _ = solver.track(0, q, solver.lower, solver.upper, q_ref, gain, opt.max_iterations_first, gain > 0)
        if ep > max(opt.position_tolerance, 1e-7) or er > max(opt.rotation_tolerance, 1e-6):
            return None
        if all(np.abs(q - f).max() > DISTINCT for f in found):
            found.append(q)
            return q
        return None

    # seeds turned toward the target about the base axis
    yaw = math.atan2(solver.positions[0][1], solver.positions[0][0])
    for seed in seeds:
        for a1 in {0.0, yaw}:
            s = np.array(seed, dtype=float)
            s[0] += a1
            s = np.clip(s, solver.lower, solver.upper)
            add(s, s, 1.0)
    # the flips are exact (same flange pose), so their combinations need no Newton steps
    for q in list(found):
        variants = [q]
        for flip in FLIPS:
            variants += [f for v in variants for f in _flipped(v, flip, solver.upper)]
        for v in variants[1:]:
            if all(np.abs(v - f).max() > DISTINCT for f in found):
                found.append(v)
    return found


def _score(solver: PathSolver, q: np.ndarray, floor: float | None) -> tuple[float, float]:
    """(fraction of the path solved in the scoring pass, smallest position-limit margin [rad]); the pass stops
    early once the margin drops below ``floor`` (such a candidate cannot win)."""
    idx = np.arange(solver.n) if solver.times is None or solver.n < 2 else spaced_indices(solver.times, SCORE_DT)
    try:
        out, *_ = solver.sequential(idx, q, q, margin_floor=floor, loose=True)
    except _Stall as stall:
        return float(stall.k) / solver.n, float((solver.limits.position - np.abs(stall.q)).min())
    return 1.0, float((solver.limits.position[None] - np.abs(out)).min())


def score_candidates(solver: PathSolver, candidates: list[np.ndarray]) -> list[tuple[float, float]]:
    """Scores of :func:`_score`, best-first search: the most comfortable first poses are scored first and the
    others stop as soon as they cannot beat the best complete candidate."""
    margins = [float((solver.limits.position - np.abs(q)).min()) for q in candidates]
    scores: list[tuple[float, float]] = [(0.0, -np.inf)] * len(candidates)
    best: float | None = None
    per_class: dict[tuple[bool, ...], int] = {}  # configuration class: signs of A2, A4, A6
    for i in sorted(range(len(candidates)), key=lambda i: margins[i], reverse=True):
        cls = tuple(bool(v) for v in candidates[i][[1, 3, 5]] > 0)
        per_class[cls] = per_class.get(cls, 0) + 1
        if (best is not None and margins[i] <= best) or per_class[cls] > PER_CLASS:
            scores[i] = (0.0, margins[i])  # already closer to a limit than the best whole path
            continue
        scores[i] = _score(solver, candidates[i], best)
        if scores[i][0] == 1.0:
            best = scores[i][1] if best is None else max(best, scores[i][1])
    return scores


def solve_with_auto_start(solver: PathSolver, progress: Callable[[int], None] | None = None) -> IkResult:
    """Solve the path from the best-scored start candidate, trying the next ones if it stalls; with
    ``options.smooth``, a result above the acceleration limit is compared with the arm-angle plan's path."""
    res = _solve_with_auto_start(solver, progress)
    if not (solver.options.smooth and solver.speed and res.acceleration_ratio > 1.0 and "arm-angle" not in res.start):
        return res
    from dataclasses import replace

    plan = best_plan(_targets(solver))
    alt = solver.through(plan.indices, plan.q, 1, any_acceleration=True) if plan is not None else None
    if alt is None or alt.velocity_ratio > 1.0 or alt.acceleration_ratio >= res.acceleration_ratio:
        return res
    label = (
        f"auto (arm-angle plan: peak acceleration {alt.acceleration_ratio:.2f} of the limit instead of "
        f"{res.acceleration_ratio:.2f} from the start chosen first)"
    )
    return replace(alt, start=label, candidates=res.candidates)


def _solve_with_auto_start(solver: PathSolver, progress: Callable[[int], None] | None = None) -> IkResult:
    from dataclasses import replace

    candidates = start_candidates(solver)
    if not candidates:  # the first pose itself is unreachable: explain it from the thesis start
        q = np.clip(np.array(SEEDS[0]), solver.lower, solver.upper)
        q, ep, er, _ = solver.track(0, q, solver.lower, solver.upper, q, 0.0, solver.options.max_iterations_first)
        raise solver.diagnose(_Stall(0, q, None, 0.0, ep, er), "from the seed configurations lbr starts from")
    scores = score_candidates(solver, candidates)
    order = sorted(range(len(candidates)), key=lambda i: scores[i], reverse=True)
    notes = tuple(
        f"[{', '.join(f'{math.degrees(v):.1f}' for v in candidates[i])}]° reached {scores[i][0] * 100:.0f} %, "
        f"margin {math.degrees(scores[i][1]):.1f}°"
        for i in order
    )
    first: _Stall | None = None  # the furthest stall of a pass on every sample (its index is exact)
    coarse: _Stall | None = None  # the furthest stall of a coarse pass (its index is on the coarse grid)
    tries = order[: solver.options.start_attempts]
    # the coarse pass of each candidate first — the best-scored ones, then the others (the scoring pass is coarser
    # still and cannot tell apart starts on one self-motion manifold whose speeds differ along the path); the
    # (slower) pass on every sample only for the best two. Every pose is reachable inside the position limits
    # (checked before, :mod:`.ik_reach`): a stall is where the redundancy led, not a fact of the pose.
    more = order[solver.options.start_attempts : solver.options.start_attempts + EXTRA_TRIES]
    for fallback, ranks in ((False, tries), (False, more), (True, tries[:2])):
        for i in ranks:
            try:
                res = solver.solve(candidates[i], candidates[i], progress, fallback=fallback)
            except _Stall as stall:
                fact = solver.fact()  # checked at every sample now (the coarse check can miss a short excursion)
                if fact is not None and fact.index <= stall.k:
                    raise solver.fact_error(fact) from None
                if fallback and (first is None or stall.k > first.k):
                    first = stall
                elif not fallback and (coarse is None or stall.k > coarse.k):
                    coarse = stall
                continue
            rank = order.index(i) + 1
            label = f"auto (candidate {rank} of {len(candidates)}, margin {math.degrees(scores[i][1]):.1f}°)"
            return replace(res, start=label, candidates=notes)
    first = first or coarse
    assert first is not None
    # the redundancy led every start into a part of the self-motion too fast somewhere: plan the arm angle over
    # the whole path and follow that plan
    plan = best_plan(_targets(solver)) if solver.speed else None
    if plan is not None:
        label = f"auto (arm-angle plan, peak {plan.peak_speed:.2f} of the speed limits between its stages)"
        # the plan's configurations are exact solutions: through them directly, else follow it from its start
        res = solver.through(plan.indices, plan.q, int(solver.rates(plan.q, plan.indices)[1] > 1.0))
        if res is not None:
            return replace(res, start=label, candidates=notes)
        try:
            res = solver.solve(plan.q[0], plan.reference(solver.times), progress)
        except _Stall as stall:
            if stall.k > first.k:  # a pass on every sample (solve's fallback): exact
                first = stall
        else:
            return replace(res, start=label, candidates=notes)
        # last: the plan's path if it keeps the speed limits, its accelerations reported (warned) as elsewhere
        res = solver.through(plan.indices, plan.q, 1, any_acceleration=True)
        if res is not None:
            return replace(res, start=label, candidates=notes)
    error = solver.diagnose(first, "from every start lbr tried")
    if plan is not None and error.reason == "velocity limit":
        j = plan.peak_joint
        raise _noted(
            error,
            f" (from where the redundancy led: lbr's whole-path arm-angle search found none below "
            f"×{plan.peak_speed:.2f} of A{j + 1}'s speed limit, at t = {solver.time(plan.indices[plan.peak_stage]):.2f} s)"
            if plan.peak_speed > 1.0
            else " (from where the redundancy led; lbr's whole-path arm-angle plan stays inside the speed limits "
            "between its stages but its interpolation was not)",
        )
    raise error


def _noted(error: IkError, note: str) -> IkError:
    """The same error with ``note`` appended to its message."""
    return IkError(
        str(error) + note,
        index=error.index,
        t=error.t,
        position_error=error.position_error,
        rotation_error=error.rotation_error,
        reason=error.reason,
        joint=error.joint,
        needed=error.needed,
        kind=error.kind,
    )


def _targets(solver: PathSolver) -> PlanTargets:
    """What the arm-angle check and plan need of the solver's path (their stage grid is computed once)."""
    return PlanTargets(ArmGeometry.of(solver.robot), solver.positions, solver.rotations, solver.times, solver.limits)
