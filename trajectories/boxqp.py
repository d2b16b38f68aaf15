"""Small box-constrained quadratic programs: min ½ xᵀHx − gᵀx subject to lo ≤ x ≤ hi (primal active set).

Used by the IK for each Newton step with joint position, velocity and acceleration bounds; H is the 7×7
damped Gauss-Newton matrix, so it is symmetric positive definite and the solution is unique.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .linsolve import solve_spd


@dataclass(frozen=True)
class BoxQpSolution:
    """Minimiser x and which variables end at a bound: −1 lower, +1 upper, 0 free."""

    x: np.ndarray
    active: np.ndarray


def solve_box_qp(
    H: np.ndarray, g: np.ndarray, lo: np.ndarray, hi: np.ndarray, x0: np.ndarray | None = None, max_iter: int = 50
) -> BoxQpSolution:
    """Minimise ½ xᵀHx − gᵀx over lo ≤ x ≤ hi (H positive definite, lo ≤ hi).

    Primal active-set method from a feasible start (x0 clipped into the box, 0 by default): solve on the free
    variables, walk to the first blocking bound and fix it, release a fixed variable whose multiplier has the
    wrong sign. Exact after finitely many steps; ``max_iter`` only guards against cycling.
    """
    m = len(g)
    x = np.minimum(np.maximum(np.zeros(m) if x0 is None else np.asarray(x0, dtype=float), lo), hi)
    pinned = lo >= hi
    active = np.zeros(m, dtype=np.int8)
    active[x <= lo] = -1
    active[x >= hi] = 1
    active[pinned] = -1
    tol = 1e-14 * (1.0 + float(np.abs(g).max()))
    for _ in range(max_iter):
        free = np.flatnonzero(active == 0)
        if len(free):
            fixed = np.flatnonzero(active)
            rows = H[free]
            rhs = g[free] - rows[:, fixed] @ x[fixed] if len(fixed) else g[free]
            xf = x[free]
            step = solve_spd(rows[:, free], rhs) - xf
            # largest feasible fraction of the step: the first bound it meets blocks it
            end = xf + step
            ratio = np.ones(len(free))
            up, down = end > hi[free], end < lo[free]
            ratio[up] = (hi[free][up] - xf[up]) / step[up]
            ratio[down] = (lo[free][down] - xf[down]) / step[down]
            b = int(np.argmin(ratio))
            if ratio[b] < 1.0:
                x[free] = xf + ratio[b] * step
                i = free[b]
                active[i] = 1 if step[b] > 0 else -1
                x[i] = hi[i] if step[b] > 0 else lo[i]
                continue
            x[free] = end
        # optimal on the free set: check the multipliers of the fixed variables (gradient of the objective)
        grad = H @ x - g
        wrong = np.where(active == -1, -grad, np.where(active == 1, grad, 0.0))
        wrong[pinned] = 0.0
        worst = int(np.argmax(wrong))
        if wrong[worst] <= tol:
            break
        active[worst] = 0
    return BoxQpSolution(x=x, active=active.astype(int))
