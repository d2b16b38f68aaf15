"""Inverse kinematics of whole paths on pinocchio, inside the joint position, velocity and acceleration limits.

Two passes:

1. A sequential pass over the path sampled every ``coarse_dt`` (every sample when the path is sparser):
   each pose starts from a first-order extrapolation of the two previous solutions and takes damped
   Gauss-Newton steps. The limits are constraints of each step — the joint positions, the speed limit
   (q̇_max·Δt around the previous solution) and the acceleration limit (q̈_max·Δt² around the extrapolation)
   form a box, and a step that would leave it is replaced by the box-constrained least-squares step
   (:mod:`.boxqp`). The 7th degree of freedom is resolved by a null-space pull toward the reference
   configuration at ``nullspace_rate`` [1/s], so it does not depend on the sampling; steps are weighted by
   the speed limits. When a sample is reachable only faster than the limits from where the redundancy has led,
   the pass goes back 0.1, 0.3 or 1 s and pulls the self-motion toward the configuration that sample needs.
   Library default (``nullspace_gain`` set): the legacy per-sample pull, every sample solved sequentially,
   speed bounds only with ``speed_limits=True``.
2. The coarse solution is interpolated (cubic spline) to every sample and refined by a few vectorised Newton
   iterations (:mod:`.chain`); if the refined path misses the tolerance or a limit, the same at a quarter of
   the spacing, then the sequential pass on every sample.

When ``q0`` is ``None`` the start is chosen for the whole path among the inverse solutions of the first pose
(:mod:`.ik_start`). A pose that cannot be reached raises :class:`IkError` saying why: out of reach (by how
much), reachable only beyond a joint's position limit, or only faster than a joint's speed limit (which joint
and the speed it needs).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import pinocchio as pin

from .arm_angle import ArmGeometry
from .boxqp import solve_box_qp
from .chain import Chain, pose_errors
from .errors import IkError
from .ik_reach import PathFact, closest_configuration, first_unreachable
from .limits import JointLimits
from .linsolve import solve_spd
from .resample import spaced_indices
from .robot import Robot

NO_TIMES_DT = 1e-3  # [s] sample period assumed for the null-space pull when a path has no times
NO_TIMES_STRIDE = 20  # samples between the arm-angle checks before solving a path without times
REPAIR_BACK = (0.1, 0.3, 1.0)  # [s] how far a repair goes back before a sample too fast to reach, per try
REPAIR_RATE = 10.0  # [1/s] null-space pull toward the configuration the stalled sample needs
MAX_REPAIRS = 6  # backtracks per pass at most
GUIDE_RATE = 5.0  # [1/s] null-space pull toward a reference path (an arm-angle plan)
SPLINE_ACCELERATION = 1.5  # interpolated peak acceleration accepted, × the coarse samples' own (when relaxed)
COARSE_REFINE = 4  # a coarse pass whose interpolation misses is retried at 1/4 of its spacing
STAGNATION = 0.9  # a box-bound Newton step that keeps this share of the error counts as stalled
STALL_STEPS, STALL_STEPS_FIRST = 3, 12  # such steps in a row that end a Newton loop (the first pose: a far start)


GIVEN_START = "from the start given (solve_ik_path.q0)"  # where a path from the caller's start began


@dataclass(frozen=True)
class IkOptions:
    """Tolerances, gains and limits handling of the path IK."""

    position_tolerance: float = 1e-9  # [m]
    rotation_tolerance: float = 1e-8  # [rad]
    max_iterations_first: int = 200  # Newton steps for the first pose
    max_iterations: int = 30  # Newton steps for each following pose
    damping: float = 1e-9  # DLS damping λ² [-]
    nullspace_rate: float = 1.0  # [1/s] pull toward q0 in the null space (fraction 1 − exp(−rate·Δt) per sample)
    # Legacy: a fraction per sample instead of the rate [-], and every sample solved sequentially (no coarse
    # pass). Set None to use ``nullspace_rate`` (what ``lbr ik`` does).
    nullspace_gain: float | None = 0.02
    max_step: float = 0.3  # largest joint step per Newton iteration [rad]
    limit_margin: float = 1e-4  # stay this far inside the position limits [rad]
    speed_limits: bool = False  # bound joint speeds and accelerations per sample (needs increasing times)
    coarse_dt: float = 0.02  # [s] sample spacing of the sequential pass on dense paths
    refine_iterations: int = 5  # vectorised Newton iterations on every sample after the coarse pass
    start_attempts: int = 4  # with q0 = None: best-scored start candidates tried on the full path
    # when the result exceeds the acceleration limit: with q0 = None also plan the arm angle over the whole path
    # (0.5–4 s more) and keep the path with the lower peak acceleration; then lower the accelerations along the
    # self-motion (:mod:`.ik_smooth`; done anyway for a task path at rest at both ends)
    smooth: bool = False
    # where the task path is at rest at an end, bring the self-motion to rest there too (needs times); at both
    # ends, also keep the accelerations inside the limits (the file must pass `lbr check`)
    rest_at_ends: bool = True


@dataclass(frozen=True)
class IkResult:
    """Joint path (n, 7) [rad] with the remaining TCP error per sample and how it was found."""

    q: np.ndarray
    position_error: np.ndarray  # [m]
    rotation_error: np.ndarray  # [rad]
    iterations: np.ndarray  # Newton steps of the sequential pass per sample (0 where only refined)
    start: str = "q0"  # where the start came from: "q0" or "auto (candidate i of m, margin x°)"
    velocity_ratio: float = 0.0  # peak |q̇| / limit over the path (backward differences)
    acceleration_ratio: float = 0.0  # peak |q̈| / limit over the path (second differences)
    acceleration_relaxed: int = 0  # samples whose acceleration bound was dropped because the path demands more
    candidates: tuple[str, ...] = field(default=())  # with q0 = None: what each start candidate scored
    task_at_rest: tuple[bool, bool] = (False, False)  # the task path lets the joints start / end at rest
    at_rest: tuple[bool, bool] = (False, False)  # the joint path starts / ends at rest (as `lbr check` asks)

    @property
    def max_position_error(self) -> float:
        return float(self.position_error.max()) if len(self.position_error) else 0.0

    @property
    def max_rotation_error(self) -> float:
        return float(self.rotation_error.max()) if len(self.rotation_error) else 0.0


def format_length(x: float) -> str:
    """3.2 mm / 12.4 µm."""
    return f"{x * 1e3:.1f} mm" if x >= 1e-3 else f"{x * 1e6:.1f} µm"


def format_angle(x: float) -> str:
    """2.50° / 17.5 µrad."""
    return f"{math.degrees(x):.2f}°" if x >= 1e-3 else f"{x * 1e6:.1f} µrad"


class _Stall(Exception):
    """The sequential pass could not reach sample ``k`` within its box."""

    def __init__(self, k: int, q: np.ndarray, q_prev: np.ndarray | None, dt: float, ep: float, er: float):
        self.k, self.q, self.q_prev, self.dt, self.ep, self.er = k, q, q_prev, dt, ep, er


class PathSolver:
    """One path's targets, limits and options; runs the passes of :func:`solve_ik_path`."""

    def __init__(
        self,
        robot: Robot,
        positions: np.ndarray,
        rotations: np.ndarray,
        limits: JointLimits,
        options: IkOptions = IkOptions(),
        times: np.ndarray | None = None,
    ) -> None:
        self.robot, self.limits, self.options = robot, limits, options
        self.positions = np.asarray(positions, dtype=float)
        self.rotations = np.asarray(rotations, dtype=float)
        self.times = None if times is None else np.asarray(times, dtype=float)
        self.n = len(self.positions)
        self.upper = limits.position - options.limit_margin
        self.lower = -self.upper
        self.speed = options.speed_limits and self.times is not None and bool((np.diff(self.times) > 0).all())
        self.acceleration_facts = False  # whether :meth:`fact` looked at A4's acceleration too
        self._full_fact: tuple[PathFact | None] | None = None  # :meth:`fact` at every sample, once found
        self.chain = Chain.of(robot)
        self.weights = limits.velocity / limits.velocity.max()  # step weights [-]
        self._w_inv2 = np.diag(1.0 / self.weights**2)
        self._damp6 = options.damping * np.eye(6)
        self._eye7 = np.eye(7)
        self._eye6 = np.eye(6)

    def target(self, k: int) -> pin.SE3:
        return pin.SE3(self.rotations[k], self.positions[k])

    def time(self, k: int) -> float:
        return float(self.times[k]) if self.times is not None else float(k)

    def null_gain(self, dt: float) -> float:
        if self.options.nullspace_gain is not None:
            return self.options.nullspace_gain
        return 1.0 - math.exp(-self.options.nullspace_rate * dt)

    def box(
        self, q1: np.ndarray | None, q2: np.ndarray | None, dt: float, dt_prev: float, scale: float = 1.0
    ) -> tuple[np.ndarray, np.ndarray, bool]:
        """Bounds of the next solution from the two previous ones, speed and acceleration limits × ``scale``;
        flag = acceleration bound dropped."""
        lo, hi = self.lower, self.upper
        if not self.speed or q1 is None:
            return lo, hi, False
        step = self.limits.velocity * (dt * scale)
        lo, hi = np.maximum(lo, q1 - step), np.minimum(hi, q1 + step)
        if q2 is None:
            return lo, hi, False
        pred = q1 + (q1 - q2) * (dt / dt_prev)
        room = self.limits.acceleration * (dt * dt * scale)
        lo_a, hi_a = np.maximum(lo, pred - room), np.minimum(hi, pred + room)
        clash = lo_a > hi_a
        if clash.any():  # braking in time is impossible: keep the position and speed bounds only
            lo_a[clash], hi_a[clash] = lo[clash], hi[clash]
        return lo_a, hi_a, bool(clash.any())

    def track(
        self,
        k: int,
        q: np.ndarray,
        lo: np.ndarray,
        hi: np.ndarray,
        q_ref: np.ndarray,
        gain: float,
        budget: int,
        first: bool = False,
        loose: bool = False,
    ) -> tuple[np.ndarray, float, float, int]:
        """Newton steps toward target k inside [lo, hi] → (q, position error [m], rotation error [rad], steps).

        ``loose``: stop at 1e-7 m / 1e-6 rad (samples refined afterwards)."""
        model, data, fid = self.robot.model, self.robot.data, self.robot.tcp_id
        opt = self.options
        tol_p, tol_r = opt.position_tolerance, opt.rotation_tolerance
        if loose:
            tol_p, tol_r = max(tol_p, 1e-7), max(tol_r, 1e-6)
        target = self.target(k)
        damp6, eye7, w, w_inv2 = self._damp6, self._eye7, self.weights, self._w_inv2
        q = np.minimum(np.maximum(q, lo), hi)
        null_pending = gain > 0.0
        it = 0
        worse = 0  # box-bound steps in a row that barely reduced the error
        last = math.inf
        boxed = False
        while True:
            pin.computeJointJacobians(model, data, q)
            dM = target.actInv(pin.updateFramePlacement(model, data, fid))
            err = pin.log6(dM).vector
            ep = math.sqrt(dM.translation @ dM.translation)
            er = math.sqrt(err[3:] @ err[3:])
            if (ep <= tol_p and er <= tol_r and not null_pending) or it >= budget:
                return q, ep, er, it
            size = ep + 0.1 * er  # [m]
            # pinned by the box at a constrained minimum above the tolerance: more steps cannot reach the target
            worse = worse + 1 if boxed and size > STAGNATION * last else 0
            if worse >= (STALL_STEPS_FIRST if first else STALL_STEPS):
                return q, ep, er, it
            last = size
            J = pin.Jlog6(dM) @ pin.getFrameJacobian(model, data, fid, pin.LOCAL)
            Jw = J * w  # speed-weighted: the step minimises Σ (dq_j / q̇max_j)²
            JJt = Jw @ Jw.T + damp6
            dq = -w * (Jw.T @ solve_spd(JJt, err))
            pull = None
            if null_pending:
                pinv = w[:, None] * solve_spd(JJt, Jw).T
                pull = gain * ((eye7 - pinv @ J) @ (q_ref - q))
                dq += pull
                null_pending = first and it < 20  # converge the first pose to the q_ref-closest solution
            size = np.abs(dq).max()
            if size > opt.max_step:
                dq *= opt.max_step / size
            new = q + dq
            if (new < lo).any() or (new > hi).any():
                H = J.T @ J + opt.damping * w_inv2
                g = -J.T @ err
                if pull is not None:
                    H += 1e-6 * w_inv2
                    g += 1e-6 * w_inv2 @ pull
                new = q + solve_box_qp(H, g, lo - q, hi - q).x
                boxed = True
            else:
                boxed = False
            q = new
            it += 1

    def sequential(
        self,
        indices: np.ndarray,
        q_start: np.ndarray,
        q_ref: np.ndarray,
        progress: Callable[[int], None] | None = None,
        margin_floor: float | None = None,
        loose: bool = False,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int]:
        """Solve the samples ``indices`` in order → (q (m, 7), position errors, rotation errors, steps, relaxed).
        ``q_ref``: the redundancy target (7,), or one per path sample (n, 7) followed at ``GUIDE_RATE``.

        Raises _Stall at the first sample missing the tolerance, or (``margin_floor`` [rad] given) coming
        closer than that to a position limit."""
        opt = self.options
        m = len(indices)
        out = np.empty((m, 7))
        ep_all, er_all = np.empty(m), np.empty(m)
        steps = np.zeros(m, dtype=np.int32)
        tol_p, tol_r = max(opt.position_tolerance, 1e-7), max(opt.rotation_tolerance, 1e-6)
        relaxed = 0
        dt_prev = 1.0
        scale = 0.97 if loose else 1.0  # room for the spline and refinement between loosely solved samples
        q = np.asarray(q_start, dtype=float)
        repairs: dict[int, int] = {}  # stalled sample → backtracks tried
        goal, goal_end = q_ref, -1  # pull target of a repair window, and where the window ends
        guided = q_ref.ndim == 2  # a reference configuration per sample (an arm-angle plan) instead of one
        i = 0
        while i < m:
            k = indices[i]
            ref = goal if i <= goal_end else (q_ref[k] if guided else q_ref)
            if i == 0:
                dt = NO_TIMES_DT
                lo, hi, _ = self.box(None, None, dt, dt)
                gain, budget, first = 1.0, opt.max_iterations_first, True
            else:
                dt = (self.times[k] - self.times[indices[i - 1]]) if self.times is not None else NO_TIMES_DT
                q1 = out[i - 1]
                q2 = out[i - 2] if i >= 2 else q1  # the arm starts at rest
                lo, hi, clash = self.box(q1, q2, dt, dt if i == 1 else dt_prev, scale)
                relaxed += clash
                q = 2.0 * q1 - q2
                budget, first = opt.max_iterations, False
                rate = REPAIR_RATE if i <= goal_end else GUIDE_RATE if guided else None
                gain = self.null_gain(dt) if rate is None else 1.0 - math.exp(-rate * dt)
            q, ep, er, it = self.track(k, q, lo, hi, ref, gain, budget, first, loose)
            if (ep > tol_p or er > tol_r) and i >= 1 and self.speed:
                # the acceleration bound may be what stops it: retry with position and speed bounds only
                lo, hi, _ = self.box(out[i - 1], None, dt, dt_prev, scale)
                q, ep, er, it2 = self.track(k, q, lo, hi, ref, 0.0, budget, loose=loose)
                it += it2
                relaxed += 1
            if (
                (ep > tol_p or er > tol_r)
                and i >= 2
                and self.speed
                and repairs.get(i, 0) < len(REPAIR_BACK)
                and sum(repairs.values()) < MAX_REPAIRS
            ):
                # too fast here from where the redundancy has led: go back and steer the self-motion early
                # toward the configuration this pose needs (reached from the previous sample, limits ignored)
                target_q, gp, gr = self.nearest_solution(k, out[i - 1])
                if gp <= tol_p and gr <= tol_r and (np.abs(target_q) <= self.upper).all():
                    tries = repairs.get(i, 0)
                    repairs[i] = tries + 1
                    back = max(1, int(round(REPAIR_BACK[tries] / max(dt, 1e-9))))
                    goal, goal_end = target_q, i
                    i = max(1, i - back)
                    dt_prev = (self.times[indices[i - 1]] - self.times[indices[i - 2]]) if i >= 2 else 1.0
                    continue
            if ep > tol_p or er > tol_r:
                raise _Stall(int(k), q, out[i - 1] if i else None, dt, ep, er)
            if margin_floor is not None and (self.limits.position - np.abs(q)).min() < margin_floor:
                raise _Stall(int(k), q, out[i - 1] if i else None, dt, ep, er)
            out[i], ep_all[i], er_all[i], steps[i] = q, ep, er, it
            dt_prev = dt
            if progress is not None and i % 250 == 0:
                progress(int(k))
            i += 1
        return out, ep_all, er_all, steps, relaxed

    def refine(
        self, q: np.ndarray, iterations: int, idx: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Vectorised Newton iterations on the samples (all, or ``idx``) still missing the tolerance (q clipped into
        the limits first) → (q, position errors [m], rotation errors [rad] of those samples)."""
        opt = self.options
        samples = np.arange(self.n) if idx is None else np.asarray(idx)
        q = np.array(q, dtype=float)
        q[samples] = np.clip(q[samples], self.lower, self.upper)
        damp = opt.damping * np.eye(6)
        ep, er = np.empty(len(samples)), np.empty(len(samples))
        todo = np.arange(len(samples))  # positions in ``samples``
        for it in range(iterations + 1):
            rows = samples[todo]
            pos, rot, jac = self.chain.kinematics(q[rows])
            err = pose_errors(pos, rot, self.positions[rows], self.rotations[rows])
            ep[todo] = e_p = np.linalg.norm(err[:, :3], axis=1)
            er[todo] = e_r = np.linalg.norm(err[:, 3:], axis=1)
            miss = (e_p > opt.position_tolerance) | (e_r > opt.rotation_tolerance)
            todo = todo[miss]
            if len(todo) == 0 or it == iterations:
                break
            J = jac[miss]
            x = np.linalg.solve(J @ J.transpose(0, 2, 1) + damp, err[miss, :, None])
            rows = samples[todo]
            q[rows] = np.clip(q[rows] + (J.transpose(0, 2, 1) @ x)[:, :, 0], self.lower, self.upper)
        return q, ep, er

    def rates(self, q: np.ndarray, idx: np.ndarray | None = None) -> tuple[float, float]:
        """Peak |q̇| and |q̈| over the path (or its samples ``idx``) relative to the limits (backward and second
        differences)."""
        if self.times is None or len(q) < 2:
            return 0.0, 0.0
        dt = np.diff(self.times if idx is None else self.times[idx])[:, None]
        vel = np.diff(q, axis=0) / dt
        v = float((np.abs(vel) / self.limits.velocity).max())
        if len(q) < 3:
            return v, 0.0
        acc = np.diff(vel, axis=0) / dt[1:]
        return v, float((np.abs(acc) / self.limits.acceleration).max())

    def nearest_solution(self, k: int, q_from: np.ndarray) -> tuple[np.ndarray, float, float]:
        """Unconstrained Gauss-Newton toward pose k from q_from → (q [rad], position error [m], rotation error [rad])."""
        model, data, fid = self.robot.model, self.robot.data, self.robot.tcp_id
        target = self.target(k)
        q = np.array(q_from, dtype=float)
        for _ in range(200):
            pin.computeJointJacobians(model, data, q)
            dM = target.actInv(pin.updateFramePlacement(model, data, fid))
            err = pin.log6(dM).vector
            J = pin.Jlog6(dM) @ pin.getFrameJacobian(model, data, fid, pin.LOCAL)
            dq = -J.T @ solve_spd(J @ J.T + 1e-10 * self._eye6, err)
            size = np.abs(dq).max()
            q = q + dq * min(1.0, 0.3 / max(size, 1e-300))
            if size < 1e-13:
                break
        pin.framesForwardKinematics(model, data, q)
        dM = target.actInv(data.oMf[fid])
        return q, float(np.linalg.norm(dM.translation)), float(np.linalg.norm(pin.log3(dM.rotation)))

    def diagnose(self, stall: _Stall, origin: str = GIVEN_START) -> IkError:
        """Why the path followed ``origin`` stalled at sample ``stall.k`` whose pose is reachable inside the limits
        (:meth:`fact` found nothing there): a joint's position limit or speed limit on the way lbr's redundancy
        went — a fact of that path, not of the pose."""
        k, t = stall.k, self.time(stall.k)
        # the configuration reaching the pose closest to the previous sample's (or to where it stalled)
        q, ep, er = self.nearest_solution(k, stall.q_prev if stall.q_prev is not None else stall.q)
        where = f"pose {k} (t = {t:.4f} s)"
        kw = dict(index=k, t=t, position_error=stall.ep, rotation_error=stall.er, kind="start")
        remaining = f"remaining error {format_length(stall.ep)}, {format_angle(stall.er)}"
        _, _, psi, branch = closest_configuration(
            ArmGeometry.of(self.robot), self.positions[k], self.rotations[k], self.upper
        )
        signs = "".join("+" if b > 0 else "−" for b in branch)
        reachable = (
            f"the pose itself is reachable inside the limits (e.g. at arm angle {math.degrees(psi):.1f}° in branch "
            f"{signs} of A2/A4/A6)"
        )
        hint = "; without solve_ik_path.q0 lbr chooses the start for the whole path" if origin == GIVEN_START else ""

        def held(text: str, reason: str, j: int, needed: float) -> IkError:
            return IkError(f"{where}: {text}; {reachable}; {remaining}{hint}", reason=reason, joint=j, needed=needed,
                           **kw)  # fmt: skip

        wrapped = np.where(np.abs(q) > self.limits.position, (q + np.pi) % (2 * np.pi) - np.pi, q)
        over = np.abs(wrapped) - self.limits.position
        if (ep <= 1e-6 and er <= 1e-5) and (over > 0).any():
            j = int(np.argmax(over))
            return held(
                f"the path {origin} ran into A{j + 1}'s position limit here (the arm angle it followed would need "
                f"A{j + 1} at {math.degrees(wrapped[j]):.2f}°, limit ±{math.degrees(self.limits.position[j]):.2f}°)",
                "position limit",
                j,
                float(wrapped[j]),
            )
        if stall.q_prev is not None and self.speed and ep <= 1e-6 and er <= 1e-5:
            speed = np.abs(q - stall.q_prev) / stall.dt
            ratio = speed / self.limits.velocity
            j = int(np.argmax(ratio))
            if ratio[j] > 1.0:
                return held(
                    f"the path {origin} needs A{j + 1} at {speed[j]:.2f} rad/s, above its limit "
                    f"{self.limits.velocity[j]:.2f} rad/s (×{ratio[j]:.1f}) here",
                    "velocity limit",
                    j,
                    float(speed[j]),
                )
        return IkError(f"{where}: the path {origin} did not converge inside the joint limits here; {reachable}; "
                       f"{remaining}{hint}", **kw)  # fmt: skip

    def fact(self, full: bool = True) -> PathFact | None:
        """The first sample no joint path reaches inside the position limits (and, with speed bounds, A4's speed
        limit; and its acceleration limit when the task path starts and ends at rest, so the file must pass
        `lbr check`), exact at every sample (:mod:`.ik_reach`), or None. Not ``full``: the arm angles only every
        ``coarse_dt`` (a pose excursion shorter than that can be missed; the solver then stalls there and asks
        again in full; the legacy pass on every sample does so too)."""
        if full and self._full_fact is not None:
            return self._full_fact[0]
        if self._full_fact is None:
            self.acceleration_facts = self.speed and all(self.task_rest())
        stride = 1
        if not full and self.n > 2:  # the coarse pass's spacing (without times: every NO_TIMES_STRIDE-th sample)
            dt = float(np.median(np.diff(self.times))) if self.times is not None else 0.0
            stride = max(1, int(round(self.options.coarse_dt / dt))) if dt > 0 else NO_TIMES_STRIDE
        found = first_unreachable(
            ArmGeometry.of(self.robot),
            self.positions,
            self.rotations,
            self.times,
            self.limits,
            self.options.limit_margin,
            speed=self.speed,
            acceleration=self.acceleration_facts,
            stride=stride,
        )
        if stride == 1:
            self._full_fact = (found,)
        return found

    def task_rest(self) -> tuple[bool, bool]:
        """Whether the task path starts / ends at rest (:func:`.ik_rest.task_at_rest`), judged at configurations
        of its first and last pose found from the thesis start."""
        from .ik_rest import task_at_rest

        if self.times is None or self.n < 3 or not self.options.rest_at_ends:
            return False, False
        seed = np.array([0.0, 0.6, 0.0, -1.2, 0.0, 0.9, 0.0])
        return task_at_rest(self, self.nearest_solution(0, seed)[0], self.nearest_solution(self.n - 1, seed)[0])

    def fact_error(self, fact: PathFact) -> IkError:
        """The refusal of a path at the sample of ``fact``."""
        k, t = fact.index, self.time(fact.index)
        before = (
            "every pose before it is within reach and has an arm angle inside the position limits"
            + (
                f", and A4 keeps its speed{' and acceleration' if self.acceleration_facts else ''} limit up to it"
                if self.speed
                else ""
            )
            if k
            else "it is the first pose"
        )
        moving = {"velocity limit": f"from pose {k - 1} it ", "acceleration limit": f"from poses {k - 2}, {k - 1} it "}
        why = (
            "; the task path starts and ends at rest, so its joint file must keep the acceleration limit to pass "
            "`lbr check`"
            if fact.reason == "acceleration limit"
            else ""
        )
        return IkError(
            f"pose {k} (t = {t:.4f} s) cannot be reached inside the joint limits: {moving.get(fact.reason, '')}"
            f"{fact.describe()} ({before}){why}",
            index=k,
            t=t,
            position_error=fact.needed if fact.reason == "out of reach" else math.nan,
            rotation_error=math.nan,
            reason=fact.reason,
            joint=fact.joint,
            needed=fact.needed,
            kind="pose" if fact.of_pose else "path",
        )

    def prefix(self, m: int) -> "PathSolver":
        """The first ``m`` samples of the path."""
        t = None if self.times is None else self.times[:m]
        return PathSolver(self.robot, self.positions[:m], self.rotations[:m], self.limits, self.options, t)

    def reversed(self) -> "PathSolver":
        """The same path backwards in time (times from 0)."""
        t = None if self.times is None else self.times[-1] - self.times[::-1]
        return PathSolver(self.robot, self.positions[::-1], self.rotations[::-1], self.limits, self.options, t)

    def finish(self, res: IkResult) -> IkResult:
        """The result with the self-motion brought to rest where the task path is (``options.rest_at_ends``,
        :mod:`.ik_rest`), its rates and errors updated, and whether it starts and ends at rest."""
        from dataclasses import replace

        from .check import rest_violations
        from .ik_rest import settle_ends, task_at_rest
        from .ik_smooth import lower_accelerations
        from .trajectory import JointTrajectory

        if self.times is None or self.n < 3:
            return res
        task_rest = task_at_rest(self, res.q[0], res.q[-1])
        q = res.q
        if self.options.rest_at_ends and any(task_rest):
            q, _ = settle_ends(self, q, task_rest)
        # a task path at rest at both ends must give a file `lbr check` passes: accelerations too
        if self.speed and (self.options.smooth or (self.options.rest_at_ends and all(task_rest))):
            q = lower_accelerations(self, q, task_rest if self.options.rest_at_ends else (False, False))
        ep, er = res.position_error, res.rotation_error
        changed = np.flatnonzero((q != res.q).any(axis=1))
        if len(changed):
            pos, rot, _ = self.chain.kinematics(q[changed])
            err = pose_errors(pos, rot, self.positions[changed], self.rotations[changed])
            ep, er = ep.copy(), er.copy()
            ep[changed], er[changed] = np.linalg.norm(err[:, :3], axis=1), np.linalg.norm(err[:, 3:], axis=1)
        vel, acc = self.rates(q)
        moving = {v.note for v in rest_violations(JointTrajectory(t=self.times, q=q), self.limits)}
        return replace(res, q=q, position_error=ep, rotation_error=er, velocity_ratio=vel, acceleration_ratio=acc,
                       task_at_rest=task_rest, at_rest=("start" not in moving, "end" not in moving))  # fmt: skip

    def coarse_indices(self, spacing: float | None = None) -> np.ndarray:
        """Samples of a sequential pass every ``spacing`` [s] (default ``coarse_dt``), first and last included."""
        if self.times is None or self.n < 3 or self.options.nullspace_gain is not None:
            return np.arange(self.n)
        return spaced_indices(self.times, self.options.coarse_dt if spacing is None else spacing)

    def interpolated(
        self, idx: np.ndarray, q_start: np.ndarray, q_ref: np.ndarray, progress: Callable[[int], None] | None
    ) -> IkResult | None:
        """Sequential pass on the samples ``idx``, spline to every sample and vectorised refinement → the result,
        or None when the refined path misses a tolerance or limit. Raises _Stall."""
        qc, _, _, steps_c, relaxed = self.sequential(idx, q_start, q_ref, progress, loose=True)
        return self.through(idx, qc, relaxed, steps_c)

    def through(
        self,
        idx: np.ndarray,
        qc: np.ndarray,
        relaxed: int,
        steps_c: np.ndarray | None = None,
        any_acceleration: bool = False,
    ) -> IkResult | None:
        """The path through solutions ``qc`` (m, 7) [rad] of the samples ``idx``: cubic spline to every sample and
        vectorised refinement → the result, or None when it misses a tolerance or limit. ``relaxed``: samples
        whose acceleration bound had to be dropped (the knots' own acceleration then sets what is accepted);
        ``any_acceleration``: accept whatever acceleration, reporting the samples above the limit as relaxed."""
        from scipy.interpolate import CubicSpline  # imported here: a refusal needs no scipy (0.5 s to import)

        opt = self.options
        spline = CubicSpline(self.times[idx], qc, axis=0)
        q, ep, er = self.refine(spline(self.times), opt.refine_iterations)
        vel, acc = self.rates(q)
        # where the pass had to drop an acceleration bound, the knots' own acceleration is what the path needs;
        # the interpolation may add a little to it, not more (a spike between knots is refined at finer spacing)
        if any_acceleration and self.speed:
            acc_allowed = math.inf
            step = np.diff(q, 2, axis=0) / (np.diff(self.times)[1:, None] ** 2)
            relaxed = int((np.abs(step) > self.limits.acceleration).any(axis=1).sum())
        else:
            acc_allowed = max(1.0, SPLINE_ACCELERATION * self.rates(qc, idx)[1]) if relaxed else 1.0
        if (
            (np.abs(q) <= self.upper + 1e-12).all()
            and ep.max() <= max(opt.position_tolerance, 1e-7)
            and er.max() <= max(opt.rotation_tolerance, 1e-6)
            and (not self.speed or (vel <= 1.0 and acc <= acc_allowed))
        ):
            steps = np.zeros(self.n, dtype=np.int32)
            if steps_c is not None:
                steps[idx] = steps_c
            return IkResult(q, ep, er, steps, velocity_ratio=vel, acceleration_ratio=acc, acceleration_relaxed=relaxed)
        return None

    def solve(
        self,
        q_start: np.ndarray,
        q_ref: np.ndarray,
        progress: Callable[[int], None] | None = None,
        fallback: bool = True,
    ) -> IkResult:
        """Coarse sequential pass, spline + vectorised refinement; when the refined path misses a tolerance or
        limit (fast self-motion near a singularity between knots), the same at a quarter of the spacing; then
        (``fallback``) the sequential pass on every sample if a coarse pass stalled or missed. Raises _Stall."""
        idx = self.coarse_indices()
        if len(idx) < self.n:
            try:
                res = self.interpolated(idx, q_start, q_ref, progress)
                if res is not None:
                    return res
                finer = self.coarse_indices(self.options.coarse_dt / COARSE_REFINE)
                if len(finer) < self.n:
                    res = self.interpolated(finer, q_start, q_ref, progress)
                    if res is not None:
                        return res
            except _Stall:
                if not fallback:
                    raise
        q, ep, er, steps, relaxed = self.sequential(np.arange(self.n), q_start, q_ref, progress)
        vel, acc = self.rates(q)
        return IkResult(q, ep, er, steps, velocity_ratio=vel, acceleration_ratio=acc, acceleration_relaxed=relaxed)


def solve_ik_path(
    robot: Robot,
    positions: np.ndarray,
    rotations: np.ndarray,
    q0: np.ndarray | None,
    limits: JointLimits,
    options: IkOptions = IkOptions(),
    *,
    times: np.ndarray | None = None,
    progress: Callable[[int], None] | None = None,
) -> IkResult:
    """Solve IK for TCP targets (positions (n, 3) [m], rotations (n, 3, 3)) at ``times`` (n,) [s].

    ``q0`` (7,) [rad] is the start guess and redundancy target; ``None`` chooses the start for the whole path
    (reported in ``IkResult.start``). Joint speeds and accelerations are bounded only when ``times`` is given.
    Raises IkError naming the first sample that cannot be reached and why.
    """
    solver = PathSolver(robot, positions, rotations, limits, options, times)
    if solver.n == 0:
        empty = np.empty(0)
        return IkResult(np.empty((0, 7)), empty, empty, np.empty(0, dtype=np.int32))
    # facts of the poses and path: before solving (the arm angles on the coarse grid, exact when one is found),
    # and at every sample once the solver stalls
    fact = solver.fact(full=False) and solver.fact()
    if q0 is None:
        if fact is not None:
            raise solver.fact_error(fact)
        from .ik_start import solve_with_auto_start

        return solver.finish(solve_with_auto_start(solver, progress))
    q_ref = np.clip(np.asarray(q0, dtype=float), solver.lower, solver.upper)
    if fact is None:
        try:
            return solver.finish(solver.solve(q_ref, q_ref, progress))
        except _Stall as stall:
            fact = solver.fact()
            if fact is None or fact.index > stall.k:
                raise solver.diagnose(stall) from None
            raise solver.fact_error(fact) from None
    # past the first unreachable sample nothing can be solved: whether the path from q0 stops before it — a fact
    # of that path — the coarse pass tells; where exactly, the pass on every sample (only then)
    part = solver.prefix(fact.index + 1)
    try:
        part.sequential(part.coarse_indices(), q_ref, q_ref, progress, loose=True)
    except _Stall as stall:
        if stall.k < fact.index:
            try:
                part.solve(q_ref, q_ref, progress)
            except _Stall as exact:
                stall = exact
            if stall.k < fact.index:
                raise solver.diagnose(stall) from None
    raise solver.fact_error(fact)
