"""Bringing the redundancy to rest with the task at the ends of a joint path.

A joint file must start and end at rest (`lbr check`: the first and last step at most acceleration limit × step).
When the task path is at rest at an end, the task part of the joint motion is too, but the self-motion (the null
space pull toward the start, the momentum of the solver's extrapolation, an arm-angle plan) may still be moving
there. Near each such end the path is solved again sample by sample with the self-motion faded out: each sample
starts from the previous step with its null-space part (speed-weighted projection) scaled by w(t), a quintic ramp
from 1 to 0 over a window ending at the end, and takes box-constrained Newton steps (:meth:`.PathSolver.track`:
positions, speed and acceleration limits) — so the limits hold by construction, and where stopping the self-motion
would need more than the acceleration limit the box slows it down at the limit. The window is the shortest (from
``MIN_WINDOW``, doubling up to half the path) over which the fade adds at most ``ADDED_SHARE`` of the acceleration
limits; the start is settled the same way on the reversed path.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from .chain import pose_errors

MIN_WINDOW = 0.05  # [s] shortest fade-out window
ADDED_SHARE = 0.5  # the fade may add this share of the acceleration limits at most
RAMP_SLOPE = 1.875  # peak |w'|·T of the quintic ramp
REST_SHARE = 0.5  # "at rest": the least joint step within this share of acceleration limit × step²


def _weighted_projection(jac: np.ndarray, weights: np.ndarray, twist: np.ndarray) -> np.ndarray:
    """Least speed-weighted joint steps (m, 7) realising twists (m, 6) through Jacobians (m, 6, 7)."""
    jw = jac * weights[None, None, :]
    jj = jw @ jw.transpose(0, 2, 1) + 1e-12 * np.eye(6)
    x = np.linalg.solve(jj, twist[:, :, None])
    return weights[None, :] * (jw.transpose(0, 2, 1) @ x)[:, :, 0]


def _null_part(solver, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Null-space parts (m, 7) of joint steps v (m, 7) at configurations q (m, 7)."""
    _, _, jac = solver.chain.kinematics(q)
    return v - _weighted_projection(jac, solver.weights, np.einsum("mij,mj->mi", jac, v))


def task_at_rest(solver, q_first: np.ndarray, q_last: np.ndarray) -> tuple[bool, bool]:
    """Whether the task path lets the joints start and end at rest: the least (speed-weighted) joint step realising
    its first and last pose steps within ``REST_SHARE`` × acceleration limit × step² of every joint, at
    configurations q_first, q_last (7,) [rad] of the first and last pose. ``solver``: the path's
    :class:`~trajectories.ik.PathSolver`."""
    if solver.times is None or solver.n < 3:
        return False, False
    out = []
    for (a, b), q in (((1, 0), q_first), ((solver.n - 2, solver.n - 1), q_last)):
        _, _, jac = solver.chain.kinematics(np.asarray(q, dtype=float)[None])
        twist = pose_errors(solver.positions[[b]], solver.rotations[[b]], solver.positions[[a]], solver.rotations[[a]])
        step = np.abs(_weighted_projection(jac, solver.weights, twist))[0]
        dt = abs(float(solver.times[a] - solver.times[b]))
        out.append(bool((step <= REST_SHARE * solver.limits.acceleration * dt * dt).all()))
    return out[0], out[1]


def _ramp(s: float) -> float:
    """1 → 0 quintic over s ∈ [0, 1] (zero slope and curvature at both ends)."""
    s = min(max(s, 0.0), 1.0)
    return 1.0 - s**3 * (10.0 - 15.0 * s + 6.0 * s * s)


def _faded(solver, q: np.ndarray, first: int) -> np.ndarray | None:
    """q solved again from sample ``first`` + 1 to the end with the self-motion faded out (module docstring), or
    None where a sample cannot be reached inside its box."""
    t, opt = solver.times, solver.options
    tol_p, tol_r = max(opt.position_tolerance, 1e-7), max(opt.rotation_tolerance, 1e-6)
    out = q.copy()
    first = max(first, 1)
    span = t[-1] - t[first]
    for k in range(first + 1, solver.n):
        q1, q2 = out[k - 1], out[k - 2]
        dt, dt_prev = t[k] - t[k - 1], t[k - 1] - t[k - 2]
        v = (q1 - q2) * (dt / dt_prev)
        jac = pin.computeFrameJacobian(solver.robot.model, solver.robot.data, q1, solver.robot.tcp_id, pin.LOCAL)
        null = v - _weighted_projection(jac[None], solver.weights, (jac @ v)[None])[0]
        guess = q1 + v - (1.0 - _ramp((t[k] - t[first]) / span)) * null
        lo, hi, _ = solver.box(q1, q2, dt, dt_prev)
        qk, ep, er, _ = solver.track(k, guess, lo, hi, guess, 0.0, opt.max_iterations)
        if ep > tol_p or er > tol_r:
            return None
        out[k] = qk
    return out


def _still(solver, q: np.ndarray, q_prev: np.ndarray, dt: float) -> bool:
    """Whether the self-motion of the step q_prev → q (7,) [rad] is within ``REST_SHARE`` of what rest allows."""
    null = np.abs(_null_part(solver, q[None], (q - q_prev)[None]))[0] / dt
    return bool((null <= REST_SHARE * solver.limits.acceleration * dt).all())


def _settle_end(solver, q: np.ndarray) -> np.ndarray | None:
    """The end of q brought to rest (module docstring), or None when no window up to half the path does it."""
    t, lim = solver.times, solver.limits
    dt = np.diff(t)
    if _still(solver, q[-1], q[-2], dt[-1]):
        return q
    speed = np.abs(_null_part(solver, q[1:], np.diff(q, axis=0))) / dt[:, None]  # [rad/s] self-motion per step
    window, longest = 2 * MIN_WINDOW, 0.5 * (t[-1] - t[0])
    while True:
        window = min(window, longest)
        first = int(np.searchsorted(t, t[-1] - window))
        need = float((RAMP_SLOPE * speed[max(first - 1, 0) :].max(axis=0) / (ADDED_SHARE * lim.acceleration)).max())
        if need <= window or window >= longest:
            out = _faded(solver, q, first)
            if out is not None and (np.abs(out[-1] - out[-2]) <= lim.acceleration * dt[-1] ** 2).all():
                return out
            if window >= longest:
                return None
        window *= 2.0


def settle_ends(solver, q: np.ndarray, ends: tuple[bool, bool]) -> tuple[np.ndarray, tuple[bool, bool]]:
    """q (n, 7) [rad] with the self-motion brought to rest at the start and/or end (``ends``), as far as the
    limits allow → (q, whether each end could be settled). The start is settled on the reversed path."""
    if solver.times is None or solver.n < 4:
        return q, (False, False)
    done = [False, False]
    if ends[1]:
        out = _settle_end(solver, q)
        if out is not None:
            q, done[1] = out, True
    if ends[0] and not _still(solver, q[0], q[1], float(solver.times[1] - solver.times[0])):
        out = _settle_end(solver.reversed(), q[::-1].copy())
        if out is not None:
            q, done[0] = out[::-1].copy(), True
    return q, (done[0], done[1])
