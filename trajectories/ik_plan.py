"""A whole-path plan of the redundancy: the arm angle chosen by dynamic programming.

The local path IK follows its redundancy where a null-space pull leads it; on fast paths that can end in a
part of the self-motion from which a later pose needs a joint faster than its limit, although another
arm-angle history would have stayed inside. This plans that history globally: the path sampled every
``PLAN_DT``, each stage's configurations on a grid of arm angles × the 8 branches (closed form,
:mod:`.arm_angle`) inside the position limits, and the sequence of grid states minimising Σ (peak joint
speed / limit)^``PEAK_POWER`` over the stage transitions — close to minimising the path's peak speed ratio,
and smooth where there is room. The plan is a reference for the local solver to follow, and its peak tells
how fast the path must be at best (to the grid's resolution).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .arm_angle import BRANCHES, ArmGeometry, arm_angle, inverse
from .limits import JointLimits
from .resample import spaced_indices

PLAN_DT = 0.1  # [s] stage spacing of the grid search
FINE_DT = 0.02  # [s] stage spacing of the final refinement
N_PSI = 72  # arm-angle grid: 5° apart (the plans are refined off the grid)
PEAK_POWER = 8  # exponent of the speed ratio in the cost: large → the peak dominates
# predecessors of each branch: itself and the three branches one sign away (one singularity crossed)
PRED = np.array([np.flatnonzero(np.abs(BRANCHES - b).sum(axis=-1) <= 2.0) for b in BRANCHES])  # (8, 4)
ACCELERATION_WEIGHT = 1.0  # of the acceleration terms against the speed terms
COARSE_ITERATIONS = 60  # L-BFGS iterations refining each grid plan at the grid's stages
FINE_PLANS = 2  # the best coarse-refined plans refined again at FINE_DT
PEAK_GOAL = 0.9  # a refined plan this far inside the speed limits is taken without trying the others
MARGIN = np.radians(1.0)  # [rad] grid states closer than this to a position limit are left out


@dataclass(frozen=True)
class PlanTargets:
    """What a plan is for: the arm, TCP targets (n, 3) [m] and (n, 3, 3) at ``times`` (n,) [s], the limits."""

    geometry: ArmGeometry
    positions: np.ndarray
    rotations: np.ndarray
    times: np.ndarray
    limits: JointLimits

    @cached_property
    def stages(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The grid search's stages every ``PLAN_DT``: indices (K,), arm angles (N_PSI,) [rad], configurations
        (K, 8, N_PSI, 7) [rad] of every branch and arm angle, and whether each is within reach."""
        idx = spaced_indices(self.times, PLAN_DT)
        psi = np.linspace(-np.pi, np.pi, N_PSI, endpoint=False)
        q, reach = self.configurations(idx[:, None, None], psi[None, None, :], BRANCHES[None, :, None, :])
        return idx, psi, q, reach

    def configurations(self, idx, psi: np.ndarray, branch: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Closed-form configurations [rad] of the samples ``idx`` at arm angles ``psi`` [rad] and branches,
        and whether each pose is within reach (shapes broadcast as in :func:`.arm_angle.inverse`)."""
        return inverse(self.geometry, self.rotations[idx], self.positions[idx], psi, branch)


@dataclass(frozen=True)
class ArmAnglePlan:
    """Configurations (K, 7) [rad] at path samples ``indices`` (K,), their arm angles [rad] and branches, and the
    plan's peak stage-to-stage speed ratio with the joint and stage where it occurs."""

    indices: np.ndarray
    q: np.ndarray
    psi: np.ndarray
    branch: np.ndarray  # (K, 3) signs of A2, A4, A6
    peak_speed: float  # max over stages and joints of |Δq| / Δt / limit
    peak_joint: int
    peak_stage: int

    def reference(self, times: np.ndarray) -> np.ndarray:
        """The plan interpolated linearly in joint space at every path time (n,) [s] → (n, 7) [rad]."""
        t = times[self.indices]
        return np.stack([np.interp(times, t, self.q[:, j]) for j in range(7)], axis=1)


def plan_arm_angle(path: PlanTargets) -> list[ArmAnglePlan]:
    """Plans of the arm angle and branch along TCP targets (n, 3) [m], (n, 3, 3) at ``times`` (n,) [s] on the
    grid (``path.stages``) — the best ending in each branch, best first; none when some stage has no configuration
    inside the position limits (the pose is out of reach or beyond a limit for every arm angle and branch)."""
    times, limits = path.times, path.limits
    idx, psi, q, reach = path.stages  # (K, 8, M, 7) configurations of every stage, branch and arm angle
    valid = reach & (np.abs(q) <= limits.position - MARGIN).all(axis=-1)
    if not valid.any(axis=(1, 2)).all():
        return []
    K, B, M = valid.shape
    vmax = limits.velocity
    shifts = np.arange(-(M // 2), M - M // 2)  # every ψ step: near a straight elbow ψ turns fast
    cost = np.where(valid[0], 0.0, np.inf)  # (B, M)
    back = np.zeros((K, B, M, 2), dtype=np.int32)  # predecessor (branch, ψ index) of each state
    S = len(shifts)
    for k in range(1, K):
        dt = float(times[idx[k]] - times[idx[k - 1]])
        # predecessors of target branch b': the branches at most one singularity away (PRED[b']), at ψ index m − s
        rolled = np.stack([np.roll(q[k - 1], s, axis=1) for s in shifts], axis=1)[PRED]  # (B', P, S, M, 7)
        rolled_cost = np.stack([np.roll(cost, s, axis=1) for s in shifts], axis=1)[PRED]  # (B', P, S, M)
        ratio = (np.abs(q[k][:, None, None] - rolled) / (vmax * dt)).max(axis=-1)  # (B', P, S, M)
        total = (rolled_cost + ratio**PEAK_POWER).reshape(B, -1, M)
        best = total.argmin(axis=1)  # (B', M) over (predecessor, shift)
        new_cost = np.take_along_axis(total, best[:, None], axis=1)[:, 0]
        pp, ps = np.divmod(best, S)
        back[k, ..., 0] = PRED[np.arange(B)[:, None], pp]
        back[k, ..., 1] = (np.arange(M)[None, :] - shifts[ps]) % M
        cost = np.where(valid[k], new_cost, np.inf)
    plans = []
    for end in np.argsort(cost.min(axis=1)):  # the best end state of each branch, best first
        if not np.isfinite(cost[end]).any():
            break
        b, m = int(end), int(np.argmin(cost[end]))
        states = [(b, m)]
        for k in range(K - 1, 0, -1):
            b, m = back[k, b, m]
            states.append((int(b), int(m)))
        states.reverse()
        bs = np.array([s[0] for s in states])
        ms = np.array([s[1] for s in states])
        plans.append(_plan(path, idx, q[np.arange(K), bs, ms], psi[ms], BRANCHES[bs]))
    return plans


def _plan(path: PlanTargets, idx: np.ndarray, q: np.ndarray, psi: np.ndarray, branch: np.ndarray) -> ArmAnglePlan:
    speed = np.abs(np.diff(q, axis=0)) / (np.diff(path.times[idx])[:, None] * path.limits.velocity)
    stage, joint = np.unravel_index(int(np.argmax(speed)), speed.shape) if len(speed) else (0, 0)
    return ArmAnglePlan(
        indices=idx,
        q=q,
        psi=psi,
        branch=branch,
        peak_speed=float(speed.max()) if len(speed) else 0.0,
        peak_joint=int(joint),
        peak_stage=int(stage) + 1,
    )


def _terms(q: np.ndarray, dt: np.ndarray, limits: JointLimits) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cost terms of configurations q (..., K, 7): per transition (..., K−1) Σ_j (speed ratio)^PEAK_POWER, per
    inner stage (..., K−2) the same of the acceleration ratio (× ACCELERATION_WEIGHT), per stage (..., K) a
    penalty for coming closer than ``MARGIN`` to a position limit."""
    vel = np.diff(q, axis=-2) / dt[:, None]
    speed = ((np.abs(vel) / limits.velocity) ** PEAK_POWER).sum(axis=-1)
    acc = np.diff(vel, axis=-2) / (0.5 * (dt[1:] + dt[:-1]))[:, None]
    accel = ACCELERATION_WEIGHT * ((np.abs(acc) / limits.acceleration) ** PEAK_POWER).sum(axis=-1)
    over = np.maximum(np.abs(q) - (limits.position - MARGIN), 0.0).sum(axis=-1) * 1e4
    return speed, accel, over


def refine_plan(
    path: PlanTargets,
    plan: ArmAnglePlan,
    max_iterations: int = 200,
    stop_speed: float = PEAK_GOAL,
) -> ArmAnglePlan:
    """The plan's arm angles moved off the grid (branches kept) to lower its peak speed and acceleration
    ratios: L-BFGS on ψ (K,), the gradient by central differences with stages five apart moved together (each
    ψ_k touches only the terms of stages k−2…k+2)."""
    from scipy.optimize import minimize

    idx, branch, limits = plan.indices, plan.branch, path.limits
    K = len(idx)
    dt = np.diff(path.times[idx])
    eps = 1e-6  # [rad]

    def joints(psi: np.ndarray) -> np.ndarray:  # (..., K) → (..., K, 7)
        return path.configurations(idx, psi, branch)[0]

    def cost(psi: np.ndarray) -> float:
        return float(sum(t.sum() for t in _terms(joints(psi), dt, limits)))

    def grad(psi: np.ndarray) -> np.ndarray:
        # stages five apart moved together, ± eps: 10 perturbed plans in one closed-form call
        steps = np.zeros((10, K))
        for colour in range(5):
            steps[2 * colour, colour::5] = eps
            steps[2 * colour + 1, colour::5] = -eps
        speed, accel, over = _terms(joints(psi[None] + steps), dt, limits)
        local = over  # per stage k: the terms it touches (transitions k−1, k; accelerations centred k−1…k+1; k)
        local[:, 1:] += speed
        local[:, :-1] += speed
        if K > 2:  # acceleration term i is centred on stage i + 1
            for shift in (0, 1, 2):
                local[:, shift : shift + K - 2] += accel
        g = np.zeros(K)
        for colour in range(5):
            g[colour::5] = ((local[2 * colour] - local[2 * colour + 1]) / (2 * eps))[colour::5]
        return g

    def good_enough(intermediate_result) -> None:  # within the goal speed and the acceleration limits: stop
        q = joints(intermediate_result.x)
        vel = np.diff(q, axis=0) / dt[:, None]
        acc = np.diff(vel, axis=0) / (0.5 * (dt[1:] + dt[:-1]))[:, None]
        if (np.abs(vel) / limits.velocity).max(initial=0.0) <= stop_speed and (np.abs(acc) / limits.acceleration).max(
            initial=0.0
        ) <= 1.0:
            raise StopIteration

    res = minimize(
        cost, plan.psi, jac=grad, method="L-BFGS-B", callback=good_enough, options={"maxiter": max_iterations}
    )
    psi = res.x if res.fun <= cost(plan.psi) else plan.psi
    return _plan(path, idx, joints(psi), psi, branch)


def best_plan(
    path: PlanTargets,
    goal: float = PEAK_GOAL,
) -> ArmAnglePlan | None:
    """Grid plans refined off the grid, best grid plan first, until one peaks at ≤ ``goal`` × the speed limits;
    the lowest-peak one found, or None when no plan exists (some pose is beyond reach or the position limits
    for every arm angle and branch)."""
    coarse = []
    for plan in plan_arm_angle(path):
        coarse.append(refine_plan(path, plan, COARSE_ITERATIONS))
        if coarse[-1].peak_speed <= goal:
            break
    best = None
    # between the stages the self-motion may turn faster than their averages show: refine the best ones at finer
    # stages
    for plan in sorted(coarse, key=lambda p: p.peak_speed)[:FINE_PLANS]:
        plan = refine_plan(path, densify(path, plan))
        if best is None or plan.peak_speed < best.peak_speed:
            best = plan
        if best.peak_speed <= goal:
            break
    return best


def densify(
    path: PlanTargets,
    plan: ArmAnglePlan,
    spacing: float = FINE_DT,
) -> ArmAnglePlan:
    """The plan at stages ``spacing`` [s] apart: at each, the arm angle of the plan's joint-space interpolation,
    in whichever branch of the two neighbouring plan stages lands nearer to it."""
    times = path.times
    idx = spaced_indices(times, spacing)
    q_lin = plan.reference(times)[idx]
    psi = arm_angle(path.geometry, q_lin)
    k = np.clip(np.searchsorted(times[plan.indices], times[idx], side="right") - 1, 0, len(plan.indices) - 1)
    k1 = np.minimum(k + 1, len(plan.indices) - 1)
    q_a, _ = path.configurations(idx, psi, plan.branch[k])
    q_b, _ = path.configurations(idx, psi, plan.branch[k1])
    nearer_b = np.abs(q_b - q_lin).max(axis=-1) < np.abs(q_a - q_lin).max(axis=-1)
    q = np.where(nearer_b[:, None], q_b, q_a)
    branch = np.where(nearer_b[:, None], plan.branch[k1], plan.branch[k])
    return _plan(path, idx, q, psi, branch)
