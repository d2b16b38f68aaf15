"""Small box-constrained quadratic programs: min ½ xᵀHx − gᵀx subject to lo ≤ x ≤ hi (primal active set).

Used by the IK for each Newton step with joint position, velocity and acceleration bounds; H is the 7×7
damped Gauss-Newton matrix, so it is symmetric positive definite and the solution is unique.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


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
    x = np.clip(np.zeros(m) if x0 is None else np.asarray(x0, dtype=float), lo, hi)
    active = np.where(x <= lo, -1, np.where(x >= hi, 1, 0))
    active[lo >= hi] = -1
    for _ in range(max_iter):
        free = active == 0
        target = x.copy()
        if free.any():
            fixed = ~free
            rhs = g[free] - H[np.ix_(free, fixed)] @ x[fixed]
            target[free] = np.linalg.solve(H[np.ix_(free, free)], rhs)
        step = target - x
        # largest feasible fraction of the step
        alpha, block = 1.0, -1
        for i in np.flatnonzero(free):
            if step[i] > 0 and x[i] + step[i] > hi[i]:
                a = (hi[i] - x[i]) / step[i]
            elif step[i] < 0 and x[i] + step[i] < lo[i]:
                a = (lo[i] - x[i]) / step[i]
            else:
                continue
            if a < alpha:
                alpha, block = a, i
        x = x + alpha * step
        if block >= 0:
            active[block] = 1 if step[block] > 0 else -1
            x[block] = hi[block] if step[block] > 0 else lo[block]
            continue
        # optimal on the free set: check the multipliers of the fixed variables (gradient of the objective)
        grad = H @ x - g
        wrong = np.where(active == -1, -grad, np.where(active == 1, grad, 0.0))
        wrong[lo >= hi] = 0.0
        worst = int(np.argmax(wrong))
        if wrong[worst] <= 1e-14 * (1.0 + np.abs(g).max()):
            break
        active[worst] = 0
    return BoxQpSolution(x=x, active=active)
