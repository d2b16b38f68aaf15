"""Lowering a joint path's accelerations by moving it along its self-motion, one linear programme per round.

The iiwa has one redundant degree of freedom: at each sample q_k the null space of the TCP Jacobian is one
direction n_k (the last right singular vector, its sign kept continuous along the path). Moving sample k by
α_k·n_k keeps its pose to first order, and the path's steps and second differences are linear in α. Each round
solves with HiGHS (:func:`scipy.optimize.linprog`, interior point)

    minimise s + λ·Σ|Δ²α|  subject to  |Δ²(q + α·n)| ≤ s·q̈max·Δt²,  |Δ(q + α·n)| ≤ 0.99·q̇max·Δt (or no faster
    than the step already is),  |q + α·n| ≤ position limits,  |α_k| ≤ ``TRUST``

on a window around each cluster of samples above the acceleration limit — with the robot at rest before the
first and after the last sample, as `lbr check` counts the steps a controller executes — then projects the moved
samples back onto their poses (vectorised Newton steps, :meth:`.PathSolver.refine`). The small cost on Δ²α keeps
the moves smooth, so the projection changes the accelerations little. Rounds (windows doubled each time) end when
no sample is above the limit or a round does not lower the peak.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.optimize import linprog

WINDOW = 0.2  # [s] moved around the samples above the limit, each side (doubled every round)
TRUST = 0.25  # [rad] largest move of a sample per round (the first-order model holds)
ROUNDS = 6
SPEED_SHARE = 0.99  # of the speed limits, the LP's bound on the steps
SMOOTHING = 1e-3  # LP cost of Σ|Δ²α| in units of the smallest acceleration step (keeps the moves smooth)


def _null_directions(solver, q: np.ndarray) -> np.ndarray:
    """Unit null-space directions (m, 7) of the TCP Jacobian at q (m, 7), signs continuous along the rows."""
    _, _, jac = solver.chain.kinematics(q)
    n = np.linalg.svd(jac)[2][:, -1, :]
    flips = np.sign(np.einsum("ij,ij->i", n[1:], n[:-1]))
    flips[flips == 0] = 1.0
    n[1:] *= np.cumprod(flips)[:, None]
    return n


def _difference_rows(ext_n: np.ndarray, col: np.ndarray, taps: tuple[float, ...], nvar: int):
    """Sparse rows (r, nvar) of the differences with ``taps`` of the moves α·n over the extended window (rows of
    ``ext_n`` (m + 2, 7), variable index per row ``col``, −1 for a fixed row): one row per (joint, difference)."""
    m_ext = len(ext_n)
    span = len(taps)
    count = m_ext - span + 1
    i = np.arange(count)
    rows, cols, vals = [], [], []
    for j in range(7):
        for off, tap in enumerate(taps):
            c = col[i + off]
            keep = c >= 0
            rows.append(j * count + i[keep])
            cols.append(c[keep])
            vals.append(tap * ext_n[i[keep] + off, j])
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(7 * count, nvar))


def _context(q: np.ndarray, end: int, rest: bool) -> np.ndarray:
    """The row beyond a path end (``end`` 0 or −1): the robot at rest there (a copy of the end sample), or moving on
    at the speed of the last step (a linear extrapolation)."""
    inner = 1 if end == 0 else -2
    return q[end] if rest else 2.0 * q[end] - q[inner]


@dataclass(frozen=True)
class _Window:
    """Samples ``idx`` of a path with one row of context each side (``ext``, (m + 2, 7) [rad]), their null-space
    directions ``n`` (m, 7) (``ext_n`` with the context rows), which samples move (``free``) and the LP column of
    each row's α (``col``, −1: fixed)."""

    idx: np.ndarray
    n: np.ndarray
    ext: np.ndarray
    ext_n: np.ndarray
    free: np.ndarray
    col: np.ndarray

    @property
    def nf(self) -> int:
        return int(self.free.sum())


def _window(solver, q: np.ndarray, lo: int, hi: int, rest: tuple[bool, bool]) -> _Window:
    """The samples lo..hi of ``q`` and their context: the neighbour outside the window (fixed), or beyond a path end
    the robot at rest (a copy of the end sample, moving with it) or moving on (a fixed extrapolation)."""
    n_all = len(q)
    idx = np.arange(lo, hi + 1)
    m = len(idx)
    n = _null_directions(solver, q[idx])
    before = q[lo - 1] if lo > 0 else _context(q, 0, rest[0])
    after = q[hi + 1] if hi < n_all - 1 else _context(q, -1, rest[1])
    ext = np.vstack([before, q[idx], after])
    ext_n = np.zeros((m + 2, 7))
    ext_n[1:-1] = n
    free = np.ones(m, dtype=bool)
    if lo > 0:
        free[0] = False  # joined to the unmoved path
    if hi < n_all - 1:
        free[-1] = False
    nf = int(free.sum())
    col = np.full(m + 2, -1)
    col[1:-1][free] = np.arange(nf)
    if lo == 0 and rest[0]:
        ext_n[0], col[0] = n[0], col[1]
    if hi == n_all - 1 and rest[1]:
        ext_n[-1], col[-1] = n[-1], col[-2]
    return _Window(idx, n, ext, ext_n, free, col)


def _round_lp(solver, q: np.ndarray, w: _Window):
    """The LP of one round over the window: minimise the peak second difference as a share ``s`` of the
    acceleration limit (plus a small cost on the curvature of α), speeds and position limits bounded, every |α| ≤
    TRUST. (cost, A_ub, b_ub, bounds) for ``linprog``."""
    h = float(np.median(np.diff(solver.times)))
    vmax, amax = solver.limits.velocity * h, solver.limits.acceleration * h * h  # per step [rad]
    m, nf, ext, n, free = len(w.idx), w.nf, w.ext, w.n, w.free
    nvar = nf + 1 + max(nf - 2, 0)  # the α of the free samples, s, then u ≥ |Δ²α| (kept smooth: small cost)
    d2 = _difference_rows(w.ext_n, w.col, (1.0, -2.0, 1.0), nvar)
    base2 = np.diff(ext, 2, axis=0).T.ravel()  # joint-major, as the rows
    a_rows = np.repeat(amax, m)
    s_col = sp.csr_matrix((-a_rows, (np.arange(7 * m), np.full(7 * m, nf))), shape=(7 * m, nvar))
    d1 = _difference_rows(w.ext_n, w.col, (-1.0, 1.0), nvar)
    base1 = np.diff(ext, axis=0).T.ravel()
    # speeds kept SPEED_SHARE inside the limit (the projection back onto the poses moves them a little), or where a
    # step is already faster, not faster than it is
    v_rows = np.maximum(np.repeat(vmax * SPEED_SHARE, m + 1), np.abs(base1))
    # position limits, where a move within the trust region could reach them
    qf, nfree = q[w.idx[free]].T.ravel(), n[free].T.ravel()  # joint-major
    bound = np.repeat(solver.upper, nf)
    near = np.flatnonzero(np.abs(qf) + TRUST * np.abs(nfree) > bound)
    pos = sp.csr_matrix((nfree[near], (np.arange(len(near)), np.tile(np.arange(nf), 7)[near])), shape=(len(near), nvar))
    qf, bound = qf[near], bound[near]
    nu = max(nf - 2, 0)
    k = np.arange(nu)
    curv = sp.csr_matrix(
        (
            np.concatenate([np.ones(nu), -2 * np.ones(nu), np.ones(nu), -np.ones(nu)]),
            (np.tile(k, 4), np.concatenate([k, k + 1, k + 2, nf + 1 + k])),
        ),
        shape=(nu, nvar),
    )
    a_ub = sp.vstack(
        [
            d2 + s_col,
            -d2 + s_col,
            d1,
            -d1,
            pos,
            -pos,
            curv,
            -curv - 2 * sp.csr_matrix((np.ones(nu), (k, nf + 1 + k)), shape=(nu, nvar)),
        ]
    ).tocsr()
    b_ub = np.concatenate([-base2, base2, v_rows - base1, v_rows + base1, bound - qf, bound + qf, np.zeros(2 * nu)])
    cost = np.zeros(nvar)
    cost[nf] = 1.0
    cost[nf + 1 :] = SMOOTHING / float(amax.min())
    bounds = [(-TRUST, TRUST)] * nf + [(0.0, None)] * (1 + nu)
    return cost, a_ub, b_ub, bounds


def _round(solver, q: np.ndarray, lo: int, hi: int, rest: tuple[bool, bool]) -> np.ndarray | None:
    """One LP round on the samples lo..hi → the moved and re-projected path, or None when the LP fails. ``rest``:
    whether the robot is at rest before the first / after the last sample."""
    w = _window(solver, q, lo, hi, rest)
    cost, a_ub, b_ub, bounds = _round_lp(solver, q, w)
    res = linprog(cost, A_ub=a_ub, b_ub=b_ub, bounds=bounds, method="highs-ipm")
    if res.x is None:
        return None
    alpha = np.zeros(len(w.idx))
    alpha[w.free] = res.x[: w.nf]
    moved = q.copy()
    moved[w.idx] = q[w.idx] + alpha[:, None] * w.n
    out, ep, er = solver.refine(moved, solver.options.refine_iterations + 5, w.idx)
    if ep.max() > max(solver.options.position_tolerance, 1e-7) or er.max() > max(
        solver.options.rotation_tolerance, 1e-6
    ):
        return None
    return out


def _ratios(solver, q: np.ndarray, rest: tuple[bool, bool]) -> tuple[np.ndarray, float]:
    """Per sample the peak second-difference ratio (the robot at rest before / after the path where ``rest`` says,
    else moving on), and the peak step ratio."""
    h = float(np.median(np.diff(solver.times)))
    padded = np.vstack([_context(q, 0, rest[0]), q, _context(q, -1, rest[1])])
    acc = (np.abs(np.diff(padded, 2, axis=0)) / (solver.limits.acceleration * h * h)).max(axis=1)
    vel = float((np.abs(np.diff(q, axis=0)) / (solver.limits.velocity * h)).max(initial=0.0))
    return acc, vel


def lower_accelerations(solver, q: np.ndarray, rest: tuple[bool, bool] = (True, True)) -> np.ndarray:
    """q (n, 7) [rad] moved along its self-motion until no sample is above the acceleration limit (module
    docstring), as far as ``ROUNDS`` rounds get; q itself when no round lowers the peak or keeps the speeds.
    ``rest``: whether the robot must be at rest before the first / after the last sample (as `lbr check` asks)."""
    if solver.times is None or solver.n < 4:
        return q
    h = float(np.median(np.diff(solver.times)))
    width = int(round(WINDOW / h))
    acc, vel = _ratios(solver, q, rest)
    best, best_peak = q, float(acc.max())
    for _ in range(ROUNDS):
        over = np.flatnonzero(acc > 1.0 + 1e-9)
        if len(over) == 0:
            break
        # one LP per cluster of samples above the limit (windows that do not touch)
        cuts = np.flatnonzero(np.diff(over) > 2 * width + 2)
        for first, last in zip(np.r_[over[0], over[cuts + 1]], np.r_[over[cuts], over[-1]]):
            lo, hi = max(0, int(first) - width), min(solver.n - 1, int(last) + width)
            q = _round(solver, q, lo, hi, rest)
            if q is None:
                break
        if q is None:
            break
        acc, vel = _ratios(solver, q, rest)
        if vel > 1.0 + 1e-9:
            break
        if acc.max() < best_peak:
            best, best_peak = q, float(acc.max())
        else:
            break
        width *= 2  # what is left may need the self-motion rearranged further away
    return best
