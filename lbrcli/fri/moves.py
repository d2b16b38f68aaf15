"""Jerk-limited motions computed for the position interface: the move to a start (:class:`OnlineMove`, and
:class:`ShapedMove`, the same convolved with an input shaper so that a ball on a string is left at rest), and the
segment that rejoins a trajectory's rows after lost messages (:func:`rejoin`). Positions [rad], times [s]."""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np
from ruckig import InputParameter, Result, Ruckig, Trajectory

from trajectories.limits import JointLimits

from .errors import StopSession

_EYE3 = np.eye(3)
REJOIN_JERK_SHARE = 0.9  # of the jerk limit a rejoin plans at: its samples where it meets the rows (whose
# velocity and acceleration are differences, not the profile's own) stay within the limit


def _move_input(limits: JointLimits, scale: float, minimum_duration: float | None) -> InputParameter:
    """ruckig input for 7 joints at ``scale`` of the limits (and at least ``minimum_duration`` [s])."""
    inp = InputParameter(7)
    lim = limits.scaled(scale)
    inp.max_velocity = lim.velocity.tolist()
    inp.max_acceleration = lim.acceleration.tolist()
    inp.max_jerk = lim.jerk.tolist()
    if minimum_duration is not None:
        inp.minimum_duration = float(minimum_duration)
    return inp


def _plan_to_rest(
    otg: Ruckig, inp: InputParameter, q_from: Sequence[float], q_to: Sequence[float], v_from: Sequence[float] | None
) -> Trajectory:
    """The ruckig trajectory from ``q_from`` [rad] (moving at ``v_from`` [rad/s], or at rest) to rest at ``q_to``."""
    inp.current_position = list(q_from)
    inp.current_velocity = list(v_from) if v_from is not None else [0.0] * 7
    inp.current_acceleration = [0.0] * 7
    inp.target_position = list(q_to)
    inp.target_velocity = [0.0] * 7
    inp.target_acceleration = [0.0] * 7
    traj = Trajectory(7)
    res = otg.calculate(inp, traj)
    if res not in (Result.Working, Result.Finished):
        raise StopSession(f"ruckig could not plan the move ({res.name})", completed=False)
    return traj


class _SteppedMove:
    """A move followed one command period at a time: ``_k`` commands taken, ``done`` once it has arrived at
    ``target``; a subclass plans it (``start``) and says where it is at ``t`` [s] (``_at``) and when it arrives."""

    period_s: float
    target: tuple[float, ...]
    done: bool
    _k: int

    def skip(self, n: int) -> None:
        """``n`` command periods went by without our commands (the controller bridged them)."""
        if not self.done:
            self._k += n

    def unstep(self) -> None:
        """Take back the last :meth:`next` (computed a cycle ahead, never sent)."""
        if self._k > 0:
            self._k -= 1
            self.done = False

    def next(self) -> tuple[float, ...]:
        if self.done:
            return self.target
        self._k += 1
        t = self._k * self.period_s
        if t >= self._arrival_s():
            self.done = True
            return self.target
        return self._at(t)

    def _arrival_s(self) -> float:
        raise NotImplementedError

    def _at(self, t: float) -> tuple[float, ...]:
        raise NotImplementedError


class OnlineMove(_SteppedMove):
    """A rest-to-rest ruckig move (position interface), planned once and followed in time one cycle at a time. After
    lost messages (the controller extrapolated our commands meanwhile) it goes on in step with its plan
    (:meth:`skip`): it arrives when it was planned to, whatever is lost; the motion-safety core absorbs the difference
    between the controller's extrapolation and the plan (≈ the move's acceleration × period², well inside the
    limits of a move at a fraction of them)."""

    def __init__(
        self, limits: JointLimits, period_s: float, scale: float, minimum_duration: float | None = None
    ) -> None:
        self._otg = Ruckig(7)
        self._inp = _move_input(limits, scale, minimum_duration)
        self.period_s = period_s
        self._traj = Trajectory(7)
        self._k = 0  # commands taken
        self.target: tuple[float, ...] = ()
        self.done = True
        self.duration_s = 0.0

    def start(self, q_from: Sequence[float], q_to: Sequence[float], v_from: Sequence[float] | None = None) -> float:
        """Plan from ``q_from`` [rad] (at rest, or moving at ``v_from`` [rad/s]) to rest at ``q_to``; the duration
        [s]."""
        self._traj = _plan_to_rest(self._otg, self._inp, q_from, q_to, v_from)
        self._k = 0
        self.target = tuple(q_to)
        self.duration_s = self._traj.duration
        self.done = self.duration_s <= 0.0
        return self.duration_s

    def _arrival_s(self) -> float:
        return self.duration_s - 1e-12

    def _at(self, t: float) -> tuple[float, ...]:
        return tuple(self._traj.at_time(t)[0])


class ShapedMove(_SteppedMove):
    """A rest-to-rest ruckig move, input-shaped so that a ball on a string hanging from the TCP is left (nearly) at
    rest: with a ``robot`` model the TCP follows the unshaped move's TCP path convolved with the shaper (impulses
    ``amplitudes`` ≥ 0 summing to 1 at ``times`` [s]) — the joints are the convolved joint positions corrected by two
    Gauss–Newton steps on the TCP position (a joint-space convolution alone leaves the forward kinematics' curvature
    unshaped, ≈ 10× the sway); without one the joint positions are convolved. The convolution keeps velocity,
    acceleration and jerk within the unshaped move's (≤ ``scale`` of the limits; the correction adds a few % of
    them); the move is longer by the shaper's last time. A restart from motion (``v_from``, after lost messages) is
    not shaped. ≈ 90 µs a cycle with the correction."""

    def __init__(
        self,
        limits: JointLimits,
        period_s: float,
        scale: float,
        amplitudes: Sequence[float],
        times: Sequence[float],
        minimum_duration: float | None = None,
        robot: Any = None,
    ) -> None:
        self._otg = Ruckig(7)
        self._inp = _move_input(limits, scale, minimum_duration)
        self.period_s = period_s
        self.shaper = tuple(zip(map(float, amplitudes), map(float, times)))
        self._terms = self.shaper
        self._robot = robot  # trajectories.robot.Robot (pinocchio model, data and TCP frame) or None
        if robot is not None:
            import pinocchio

            self._pin = pinocchio
        self._traj = Trajectory(7)
        self._k = 0
        self._end = 0.0  # [s] when the shaped move has arrived
        self.target: tuple[float, ...] = ()
        self.done = True
        self.duration_s = 0.0

    def start(self, q_from: Sequence[float], q_to: Sequence[float], v_from: Sequence[float] | None = None) -> float:
        """Plan from ``q_from`` [rad] (at rest, or moving at ``v_from`` [rad/s]: unshaped) to rest at ``q_to``;
        the duration [s]."""
        moving = v_from is not None and any(v != 0.0 for v in v_from)
        traj = _plan_to_rest(self._otg, self._inp, q_from, q_to, v_from if moving else None)
        self._traj = traj
        self._terms = ((1.0, 0.0),) if moving or traj.duration == 0.0 else self.shaper  # nothing to shape: no delay
        self._end = traj.duration + self._terms[-1][1]
        self._k = 0
        self.target = tuple(q_to)
        self.duration_s = self._end
        self.done = False
        return self._end

    def _arrival_s(self) -> float:
        return self._end

    def _at(self, t: float) -> tuple[float, ...]:
        traj, dur = self._traj, self._traj.duration
        if self._robot is not None and len(self._terms) > 1:
            return self._corrected(t)
        q = [0.0] * 7
        for a, ti in self._terms:
            p = traj.at_time(min(max(t - ti, 0.0), dur))[0]
            for j in range(7):
                q[j] += a * p[j]
        return tuple(q)

    def _corrected(self, t: float) -> tuple[float, ...]:
        """The joints whose TCP is the shaped TCP position at ``t`` [s], nearest the shaped joints."""
        pin, robot = self._pin, self._robot
        model, data, fid = robot.model, robot.data, robot.tcp_id
        traj, dur = self._traj, self._traj.duration
        q = np.zeros(7)
        x = np.zeros(3)  # [m] the shaped TCP position
        for a, ti in self._terms:
            p = np.array(traj.at_time(min(max(t - ti, 0.0), dur))[0])
            q += a * p
            pin.framesForwardKinematics(model, data, p)
            x += a * data.oMf[fid].translation
        for _ in range(2):
            jac = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)[:3]
            e = x - pin.updateFramePlacement(model, data, fid).translation
            q += jac.T @ np.linalg.solve(jac @ jac.T + 1e-9 * _EYE3, e)
        return tuple(q.tolist())


def extrapolated(last: Sequence[float], before: Sequence[float], n: int, period_s: float
                 ) -> tuple[tuple[float, ...], tuple[float, ...], list[float]]:  # fmt: skip
    """Where the controller's constant-velocity extrapolation of our last two commands ``before``, ``last`` [rad]
    puts the arm after ``n`` lost periods of ``period_s`` [s]: (that command, the one a period before it, the
    velocity [rad/s])."""
    vel = [(a - b) / period_s for a, b in zip(last, before)]
    q = tuple(a + n * v * period_s for a, v in zip(last, vel))
    return q, tuple(a - v * period_s for a, v in zip(q, vel)), vel


def fade_factor(off: Sequence[float], off_prev: Sequence[float], jerk: Sequence[float], period_s: float,
                fastest: float) -> float:  # fmt: skip
    """The per-period factor F (≥ ``fastest``) of a double-pole fade o[k+1] = 2F·o[k] − F²·o[k−1] from the offsets
    ``off``, ``off_prev`` [rad] (this period, the one before) whose third difference stays within ``jerk`` [rad/s³]
    per joint. The fade is (a + b·k)·Fᵏ with a = off, b = off − F·off_prev; with λ = −ln F its third difference is
    at most λ³·|a| + (3 + 1/e)·λ²·|b| per period³ — each term is given half the budget."""
    lam = -math.log(fastest)  # [1/period]
    for _ in range(8):  # (b grows as λ shrinks: until no joint lowers λ further)
        low = lam
        for a, p, j in zip(off, off_prev, jerk):
            c = 0.5 * j * period_s**3  # [rad] per period³: half the budget
            if a != 0.0:
                low = min(low, (c / abs(a)) ** (1.0 / 3.0))
            b = abs(a - math.exp(-lam) * p)
            if b > 0.0:
                low = min(low, math.sqrt(c / (3.3679 * b)))
        if low >= lam * (1.0 - 1e-9):
            break
        lam = low
    return math.exp(-lam)


def rejoin(
    limits: JointLimits,
    period_s: float,
    q: Sequence[float],
    v: Sequence[float],
    rows: Sequence[Sequence[float]],
    first: int,
    max_tries: int = 20,
    share: float = 1.0,
) -> tuple[list[tuple[float, ...]], int]:
    """The commands that bring the robot from ``q`` [rad] moving at ``v`` [rad/s] (where the controller's
    extrapolation left it) back onto ``rows`` in step: jerk-limited (ruckig, at the limits), ``m`` commands for rows
    ``first`` … ``first + m − 1``, the last one exactly that row (with its velocity and acceleration). Returns (the
    commands, the next row). Towards the end of the rows: to the last row at rest, taking the time it needs.
    ``share`` < 1 plans within that share of the velocity/acceleration/jerk limits (never below what the rows
    themselves need where they are rejoined)."""
    otg = Ruckig(7, period_s)
    inp = InputParameter(7)
    vmax, amax = limits.velocity * share, limits.acceleration * share
    inp.max_velocity, inp.max_acceleration = vmax.tolist(), amax.tolist()
    inp.max_jerk = (limits.jerk * share * REJOIN_JERK_SHARE).tolist()
    inp.current_position = list(q)
    inp.current_velocity = list(v)
    inp.current_acceleration = [0.0] * 7  # the controller extrapolates at constant velocity
    n = len(rows)
    dt = period_s
    m = 8
    for _ in range(max_tries):
        r = first + m - 1
        traj = Trajectory(7)
        if r + 1 >= n:  # the end of the rows is near: stop on the last row
            inp.target_position = list(rows[-1])
            inp.target_velocity = [0.0] * 7
            inp.target_acceleration = [0.0] * 7
            inp.minimum_duration = None
            if otg.calculate(inp, traj) not in (Result.Working, Result.Finished):
                break
            k = max(1, int(math.ceil(traj.duration / dt - 1e-9)))
            out = [tuple(traj.at_time(min(i * dt, traj.duration))[0]) for i in range(1, k)]
            return out + [tuple(rows[-1])], n
        a, b, c = rows[r - 1], rows[r], rows[r + 1]
        inp.target_position = list(b)
        inp.target_velocity = [(z - x) / (2.0 * dt) for x, z in zip(a, c)]
        inp.target_acceleration = [(x - 2.0 * y + z) / (dt * dt) for x, y, z in zip(a, b, c)]
        if share < 1.0:  # the rows' own state where they are rejoined stays admissible
            inp.max_velocity = np.maximum(vmax, np.abs(inp.target_velocity) * 1.001).tolist()
            inp.max_acceleration = np.maximum(amax, np.abs(inp.target_acceleration) * 1.001).tolist()
        inp.minimum_duration = m * dt
        res = otg.calculate(inp, traj)
        if res in (Result.Working, Result.Finished) and traj.duration <= m * dt * (1 + 1e-12):
            return [tuple(traj.at_time(i * dt)[0]) for i in range(1, m)] + [tuple(b)], r + 1
        m = int(math.ceil(m * 1.25))  # (the time-optimal rejoin is not monotonic in m: no jump to its duration)
    raise StopSession(
        f"messages were lost at row {first}: the rows cannot be rejoined within the limits", completed=False
    )
