"""The FRI client that follows targets from a source: online IK for poses, ruckig between targets, the dead-man rule.

Every cycle it drains the source. A joint target [rad] goes to ruckig as it is; a TCP pose goes through the online
IK (:class:`trajectories.ik_online.OnlineIk`, warm-started from the previous solution, a few Gauss–Newton steps
within the cycle, continued on the next cycles until it converges, the redundancy pulled toward the posture at
activation) and its twist feed-forward through the Jacobian's damped pseudo-inverse. The state goes back after the
FRI reply (:meth:`after_reply`). The targets go on a :class:`~lbrcli.bridge.timeline.TargetTimeline` (their source's
clock, read back a short delay behind the newest), and ruckig (position interface, at ``speed_scale`` of the velocity,
acceleration and jerk limits) follows that reference — so a 30 Hz, jittery or bursty source still gives a smooth
stream at the FRI period without overshoot, and the application's guard checks every command. It ends with :class:`~lbrcli.fri.StopSession` (the application brakes
within the limits): when no target arrived for ``timeout_s`` after the first (or none within ``first_target_s``),
when the owning source sends something that is not a target or a joint target outside the position limits, or
when it sends the end message (completed).
"""

from __future__ import annotations

import time
from typing import Callable, Sequence

import numpy as np
import pinocchio as pin

from lbrcli.fri import LBRClient, LBRState, StopSession
from trajectories.ik_online import OnlineIk, OnlineIkOptions, fixed_angles_to_matrix, quaternion_to_matrix
from trajectories.limits import JointLimits
from trajectories.robot import Robot

from .inbox import TargetInbox
from .protocol import KIND_JOINT, KIND_POSE, State, Target
from .timeline import TargetTimeline, TimelineOptions
from .tracker import ReferenceTracker, Untrackable

JUMP_S = 0.05  # [s] the reference's clock jumps when it is this far from where it is due
MAX_WARP = 0.05  # the reference's clock runs at most 5 % fast or slow while it catches up
CATCHUP_S = 0.5  # [s] an offset is worked off at offset / CATCHUP_S (up to MAX_WARP)
WARP_BANDWIDTH = 3.0  # [rad/s] of the warp's filter (≈ 1 s to settle)
REFINE_CYCLES = 50  # cycles a pose that has not converged is refined further before it counts as unreached


class TargetFollower(LBRClient):
    """Follows ``source``'s targets; sends the state back every ``state_every`` messages (0: never)."""

    jerk_limited = True  # its motion is ruckig's: the safety core keeps any clamp within the jerk limit too
    replans = True  # after a command the controller bridged: the tracker re-plans from what it executed

    def __init__(self, source: TargetInbox, limits: JointLimits, *, robot: Robot | None = None,
                 timeout_s: float = 0.1, first_target_s: float = 30.0, speed_scale: float = 0.5,
                 state_every: int = 1, ik_options: OnlineIkOptions = OnlineIkOptions(),
                 timeline: TimelineOptions = TimelineOptions(),
                 clock: Callable[[], float] = time.monotonic) -> None:  # fmt: skip
        if not (0 < speed_scale <= 1):
            raise ValueError(f"speed_scale must be in (0, 1], got {speed_scale}")
        self.source = source
        self.clock = clock  # [s] the source's arrival times are on this clock (the inbox's: time.monotonic)
        self.limits = limits
        self.timeout_s = timeout_s
        self.first_target_s = first_target_s
        self.state_every = state_every
        self.ik = OnlineIk(robot or Robot(), limits, ik_options)
        self.timeline = TargetTimeline(timeline)
        self._limits = limits.scaled(speed_scale)
        self._upper = limits.position.tolist()  # [rad] symmetric: |q| ≤ position
        self._lower = [-x for x in self._upper]
        self._tracker: ReferenceTracker | None = None
        self._tau = 0.0  # [s] where on the targets' clock the last command stands
        self._dt = 0.0  # [s] one command period
        self._warp = 0.0  # the reference's clock runs at (1 + warp) periods per command period
        self._warp_rate = 0.0  # [1/s]
        self._t_start = 0.0  # [s] time.monotonic() at activation
        self._count = 0
        self._seq = 0
        self._q: Sequence[float] | None = None
        self._pending: tuple[LBRState, Sequence[float]] | None = None  # the state to send after the reply
        self._prepared: list[float] | None = None  # the next command, computed after the last reply
        self._tau_prepared = 0.0  # [s] _tau before that
        self._pose: tuple[np.ndarray, np.ndarray, Target] | None = None  # a pose still being refined
        self._ik_q: np.ndarray | None = None  # [rad] the last IK solution (the next seed)
        self._posture: np.ndarray | None = None  # [rad] where the arm stood at activation: the IK's redundancy pull
        self._refine_left = 0
        self.unreached = False  # the last pose target was not reached (closest configuration followed)
        # figures
        self.targets_followed = 0
        self.pose_targets = 0
        self.poses_unreached = 0
        self.max_ik_position_error = 0.0  # [m] over the poses that did not converge
        self.ik_time_max = 0.0  # [s] longest IK work in one cycle
        self.dry_cycles = 0  # commands past the newest target (coasting, then holding)

    def _check_source(self, now: float) -> None:
        src = self.source
        src.poll()
        if src.error is not None:
            raise StopSession(f"the source sent something that is not a target: {src.error}", completed=False)
        if src.ended:
            raise StopSession("the source ended the session", completed=True)
        if src.latest is None:
            if now - self._t_start > self.first_target_s:
                bad = getattr(src, "last_bad", None)
                why = f" ({src.bad} invalid; the last: {bad})" if bad else ""
                raise StopSession(f"no target arrived within {self.first_target_s:g} s of commanding{why}",
                                  completed=False)  # fmt: skip
        elif now - src.latest_time > self.timeout_s:
            raise StopSession(f"dead-man: no target for {(now - src.latest_time) * 1e3:.0f} ms "
                              f"(more than {self.timeout_s * 1e3:g} ms)", completed=False)  # fmt: skip

    def _send_state(self, state: LBRState, q: Sequence[float]) -> None:
        """Note the state to send back (every ``state_every`` messages); :meth:`after_reply` sends it."""
        self._count += 1
        if self.state_every and not self._count % self.state_every and self.source.owner is not None:
            self._pending = (state, q)

    def after_reply(self) -> None:
        """Send the noted state back to the source once the FRI reply is on its way (it never delays a command);
        while the application brakes, the state with the ipo position and the braking flag."""
        if self.braking:
            self._send_state(self.robot_state, self.robot_state.ipo_joint_position)
        if self._pending is None:
            return
        state, q = self._pending
        self._pending = None
        msg = state.message
        tgt = self.source.latest
        self._seq += 1
        pos, rot = self.ik.tcp(np.asarray(q, dtype=float))
        x, y, z, w = pin.Quaternion(rot).coeffs()
        self.source.send(State(msg.connectionInfo.sessionState, self.braking, self._tracker is not None, self.unreached,
                               self._seq, (tgt.seq or 0) if tgt else 0, tgt.t if tgt else 0.0, state.timestamp,
                               tuple(msg.monitorData.measuredJointPosition.value), tuple(q),
                               tuple(msg.monitorData.externalTorque.value), (*pos.tolist(), w, x, y, z)))  # fmt: skip

    def monitor(self, state: LBRState) -> None:
        self._prepared = None
        self.source.poll()
        self._send_state(state, state.measured_joint_position)

    def wait_for_command(self, state: LBRState) -> None:
        self._prepared = None
        self.source.poll()
        self.hold_ipo(state)
        self._send_state(state, state.ipo_joint_position)

    def _joint_target(self, tgt: Target) -> None:
        q = tgt.values
        for j in range(7):
            if not self._lower[j] <= q[j] <= self._upper[j]:
                raise StopSession(f"the target for A{j + 1} ({q[j]:.4f} rad) is outside its position limits "
                                  f"[{self._lower[j]:g}, {self._upper[j]:g}]", completed=False)  # fmt: skip
        self._pose = None
        self._ik_q = None
        self.unreached = False
        self.timeline.add(q, tgt.v, tgt.t, self.source.latest_time)

    def _pose_target(self, tgt: Target) -> None:
        vals = tgt.values
        position = np.array(vals[:3])
        rot = quaternion_to_matrix(*vals[3:7]) if tgt.kind == KIND_POSE else fixed_angles_to_matrix(*vals[3:6])
        self._pose = (position, rot, tgt)
        self._refine_left = REFINE_CYCLES
        self.pose_targets += 1
        self._refine_pose(first=True)

    def _refine_pose(self, first: bool = False) -> None:
        position, rot, tgt = self._pose  # type: ignore[misc]
        t0 = time.perf_counter()
        seed = self._ik_q if self._ik_q is not None else self._tracker.q  # type: ignore[union-attr]
        res = self.ik.solve(seed, position, rot, posture=self._posture)
        self._ik_q = res.q
        v = None
        if tgt.v is not None:  # q̇ = J⁺·twist (damped) at the solution
            jac = self.ik.jacobian(res.q)
            v = jac.T @ np.linalg.solve(jac @ jac.T + 1e-4 * np.eye(6), np.array(tgt.v[:6]))
        if first:
            self.timeline.add(res.q, v, tgt.t, self.source.latest_time)
        else:
            self.timeline.replace_last(res.q, v)
        self._refine_left -= 1
        if res.converged or self._refine_left <= 0:
            self._pose = None
            self.unreached = not res.converged
            if not res.converged:
                self.poses_unreached += 1
                self.max_ik_position_error = max(self.max_ik_position_error, res.position_error)
        self.ik_time_max = max(self.ik_time_max, time.perf_counter() - t0)

    def command(self, state: LBRState) -> Sequence[float]:
        now = self.clock()
        if self._tracker is None:  # activation: start from where the controller holds the robot, at rest
            self._t_start = now
            self._dt = self.command_period_s
            self._tracker = ReferenceTracker(self._limits, self._dt, state.ipo_joint_position)
            self._q = state.ipo_joint_position
            self._posture = np.array(state.ipo_joint_position)
        self._check_source(now)
        if not self.reply_due:
            return self._q  # type: ignore[return-value]
        q, self._prepared = self._prepared, None
        ex = self.executed
        if q is None or self.skipped or (ex is not None and ex.replan_due):  # (prepared before a message was lost,
            if q is not None:  # or before the controller's history said to re-plan: the reference as before)
                self._tau = self._tau_prepared
            q = self._next(now, self.skipped)
        self._q = q
        self._send_state(state, q)
        return q

    def prepare_command(self) -> Sequence[float] | None:
        """Reply first: the next command [rad], computed after this reply from the targets polled in this cycle —
        the reference one period on, as the next message's cycle would step it (None before activation). A source
        that ends or goes quiet is found in the next cycle (one period later than in its own cycle)."""
        if self._tracker is None:
            return None
        self._tau_prepared = self._tau
        self._prepared = self._next(self.clock(), 0)
        return self._prepared

    def _next(self, now: float, skipped: int) -> list[float]:
        """The next command [rad] ``skipped`` periods after the last one the controller missed: the targets that
        arrived, followed by the tracker."""
        tl = self.timeline
        tracker = self._tracker
        ex = self.executed
        if ex is not None and (
            skipped or ex.replan_due or (ex.last_clamp > 0.0 and ex.rejoin.done)
        ):  # (any clamp: the next
            # step starts from it) the controller extrapolated our last commands (lost messages), or the safety core
            # clamped one: re-plan from what it executed (unless the core is taking the motion back onto our path
            # after a command the controller bridged)
            tracker.reset(ex.position, ex.velocity, ex.acceleration)
        src = self.source
        if src.fresh:
            src.fresh = False
            tgt = src.latest
            first = tl.empty
            if tgt.kind == KIND_JOINT:  # type: ignore[union-attr]
                self._joint_target(tgt)  # type: ignore[arg-type]
            else:
                self._pose_target(tgt)  # type: ignore[arg-type]
            self.targets_followed += 1
            if first:
                self._tau = tl.due(now)
        elif self._pose is not None:
            self._refine_pose()
        if tl.empty:  # no target yet: hold
            q = tracker.hold()
        else:
            # the reference advances one period per command (the controller's clock, steadier than ours). Before
            # the first target's time it stands still, so its clock may be set to where the timeline says it is due;
            # once it moves it is pulled there by running up to MAX_WARP faster or slower, the warp following a
            # critically damped filter (the tracker sees a small, smooth change of the reference's velocity); more
            # than JUMP_S off (a stall), it jumps
            dt = self._dt
            tau = self._tau + dt * (1 + skipped)
            due = tl.due(now)
            off = due - tau
            if tau <= tl.oldest or abs(off) > JUMP_S:
                tau = due
                self._warp = self._warp_rate = 0.0
            else:
                want = max(-MAX_WARP, min(MAX_WARP, off / CATCHUP_S))
                k = WARP_BANDWIDTH
                self._warp_rate += (k * k * (want - self._warp) - 2.0 * k * self._warp_rate) * dt
                self._warp = max(-MAX_WARP, min(MAX_WARP, self._warp + self._warp_rate * dt))
                tau += self._warp * dt
            self._tau = tau
            if tau >= tl.newest:
                self.dry_cycles += 1
            tl.forget(tau - dt)
            lo, up = self._lower, self._upper
            start = tau - dt
            rate = 1.0 + self._warp  # the reference's clock per tracker second

            look = tl.ahead if tau < tl.newest + tl.options.coast_s else tl.at  # the source is alive: it goes on

            def reference(t: float):
                q, v, a = look(start + t * rate)
                return np.clip(q, lo, up), v * rate, a * (rate * rate)

            try:
                q = tracker.step(reference)
            except Untrackable as exc:
                raise StopSession(str(exc), completed=False) from None
        return q.tolist()

    def figures(self) -> dict:
        f = dict(self.source.figures())
        f["targets_followed"] = self.targets_followed
        tl = self.timeline
        f.update(timing="source time" if tl.source_clock else "arrival", delay_max_ms=tl.largest_delay * 1e3,
                 reference_dry_cycles=self.dry_cycles)  # fmt: skip

        if self.pose_targets:
            f.update(pose_targets=self.pose_targets, poses_unreached=self.poses_unreached,
                     max_ik_position_error_m=self.max_ik_position_error, ik_time_max_ms=self.ik_time_max * 1e3)  # fmt: skip
        return f
