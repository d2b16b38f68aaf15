"""The braking envelope: the joint states from which a jerk-limited stop stays inside every limit.

A position-controlled robot executes the commands q_k one period dt apart; per joint its step velocity is
v_k = (q_k − q_{k−1}) / dt and its acceleration a_k = (v_k − v_{k−1}) / dt (what the controller executes and what the
FRI guard measures). A stop from there is the time-optimal jerk-limited profile to rest (ruckig's velocity interface,
each joint on its own) started from the continuous state

    v_c = v_k + a_k·dt/2,  a_k

— the state whose first sampled step continues the history with a jerk inside the limit. The state is *brakeable*
(inside the envelope) when that stop keeps

- the velocity: |v_c| ≤ V, and the velocity it still gains while the acceleration is ramped to zero,
  v_c + a_k·|a_k| / (2J), within ±V;
- the acceleration: |a_k| ≤ A;
- the position: where the stop ends, q_k + d(v_c, a_k) (:func:`stop_distance`), within ±Q.

A command admitted only into this set always leaves a braking stop within the limits (also next to a position
limit and at full speed); a command outside it is clamped to it (:meth:`BrakingEnvelope.admit`) or refused.
Pure Python on 7 floats for the per-cycle path; :func:`brakeable` checks whole files with numpy.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from functools import cached_property
from typing import Sequence

import numpy as np

from .limits import JointLimits

try:  # the quick acceptance of a command, compiled (setup.py; without a compiler the Python loop alone decides)
    from . import _quick
except ImportError:  # pragma: no cover - a build without a C compiler
    _quick = None

REL_TOL = 1e-9  # relative slack on every limit (a command exactly at a limit passes)
_NO_FLOOR = (0.0,) * 7
_PACK7 = struct.Struct("7d").pack
SHRINK = 1e-10  # relative: clamped commands aim this far inside the bounds (rounding of q → differences)
STOP_SLACK_STEPS = 2.0  # [periods] at the current speed added to every stop distance (sampling of the stop)


def stop_distance(v: float, a: float, a_max: float, j_max: float) -> float:
    """Signed distance [rad] of the time-optimal jerk-limited stop from velocity ``v`` [rad/s] and acceleration ``a``
    [rad/s²] to rest (acceleration ramped at ``j_max`` [rad/s³], at most ``a_max`` [rad/s²]): the farthest point it
    reaches in the direction of motion. A state that already brakes so hard that ramping the acceleration back to
    zero reverses it (a·v < 0, a² / 2J > |v|) goes as far as the point where its velocity crosses zero."""
    if v == 0.0 and a == 0.0:
        return 0.0
    s = 1.0 if (v > 0.0 or (v == 0.0 and a > 0.0)) else -1.0
    v, a = v * s, a * s  # v ≥ 0 now; a > 0: still speeding up in the direction of motion
    if a < -a_max:
        a = -a_max
    elif a > a_max:
        a = a_max
    J = j_max
    if a < 0.0 and a * a > 2.0 * J * v:  # over-braking: the velocity crosses zero while the acceleration is ramped up
        t = (-a - math.sqrt(a * a - 2.0 * J * v)) / J  # when it does
        return s * max(0.0, v * t + 0.5 * a * t * t + J * t * t * t / 6.0)
    p2 = J * v + 0.5 * a * a  # peak deceleration² of the triangular profile
    if p2 <= a_max * a_max:
        p = math.sqrt(p2)
        t1 = (a + p) / J
        d1 = v * t1 + 0.5 * a * t1 * t1 - J * t1 * t1 * t1 / 6.0
        v1 = v + a * t1 - 0.5 * J * t1 * t1
        t3 = p / J
        d3 = v1 * t3 - 0.5 * p * t3 * t3 + J * t3 * t3 * t3 / 6.0
        return s * max(0.0, d1 + d3)
    t1 = (a + a_max) / J
    d1 = v * t1 + 0.5 * a * t1 * t1 - J * t1 * t1 * t1 / 6.0
    v1 = v + a * t1 - 0.5 * J * t1 * t1
    v2 = 0.5 * a_max * a_max / J
    t2 = (v1 - v2) / a_max
    d2 = v1 * t2 - 0.5 * a_max * t2 * t2
    t3 = a_max / J
    d3 = v2 * t3 - 0.5 * a_max * t3 * t3 + J * t3 * t3 * t3 / 6.0
    return s * max(0.0, d1 + d2 + d3)


def reverse_distance(v: float, a: float, a_max: float, j_max: float) -> float:
    """Unsigned distance [rad] an over-braking stop (see :func:`stop_distance`) may travel back against its motion;
    0 for any other state."""
    if v * a >= 0.0 or a * a <= 2.0 * j_max * abs(v):
        return 0.0
    u = 0.5 * a * a / j_max - abs(v)  # the reverse speed it reaches at most
    return u * abs(a) / j_max + abs(stop_distance(u, 0.0, a_max, j_max))


def velocity_peak(v_c: float, a: float, j_max: float) -> float:
    """The velocity [rad/s] a stop from (``v_c``, ``a``) reaches while it ramps the acceleration to zero."""
    return v_c + a * abs(a) / (2.0 * j_max)


@dataclass(frozen=True)
class Admission:
    """The outcome of :meth:`BrakingEnvelope.admit` for one command."""

    q: tuple[float, ...]  # [rad] the command to send (the client's, or clamped into the envelope)
    clamped: float  # [rad] largest |change| made to the client's command (0: admitted as it was)
    joint: int  # 0-based joint changed most (−1: none)
    reason: str | None  # set when no admissible command exists from this history (the robot must brake)


@dataclass(frozen=True)
class BrakingEnvelope:
    """The envelope for one command period ``dt`` [s] (limits per joint, symmetric)."""

    dt: float
    position: tuple[float, ...]  # [rad] Q
    velocity: tuple[float, ...]  # [rad/s] V
    acceleration: tuple[float, ...]  # [rad/s²] A
    jerk: tuple[float, ...]  # [rad/s³] J
    free: tuple[float, ...]  # [rad] |q| ≤ free: the position never limits a state inside the other bounds

    @classmethod
    def from_limits(cls, limits: JointLimits, dt: float) -> "BrakingEnvelope":
        pos = tuple(float(x) for x in limits.position)
        vel = tuple(float(x) for x in limits.velocity)
        acc = tuple(float(x) for x in limits.acceleration)
        jerk = tuple(float(x) for x in limits.jerk)
        # the longest stop inside the velocity/acceleration bounds, with one period of travel and 1 % to spare
        free = tuple(p - 1.01 * (stop_distance(v, a, a, j) + (STOP_SLACK_STEPS + 1.0) * v * dt)
                     for p, v, a, j in zip(pos, vel, acc, jerk))  # fmt: skip
        return cls(dt, pos, vel, acc, jerk, free)

    # -- one joint ---------------------------------------------------------------------------------------------
    def joint_ok(self, j: int, q: float, v: float, a: float) -> bool:
        """The step state (q [rad], v [rad/s], a [rad/s²]) of joint ``j`` (0-based) is brakeable."""
        k = 1.0 + REL_TOL
        V, A, J = self.velocity[j] * k, self.acceleration[j] * k, self.jerk[j]
        v_c = v + 0.5 * a * self.dt
        if not (-A <= a <= A and -V <= v_c <= V and -V <= v <= V):  # also NaN
            return False
        peak = velocity_peak(v_c, a, J)
        if not -V <= peak <= V:
            return False
        return self.room_to_stop(j, q, v_c, a)

    def room_to_stop(self, j: int, q: float, v_c: float, a: float, strict: bool = False) -> bool:
        """The stop of joint ``j`` from ``q`` [rad] at (``v_c``, ``a``) ends inside its position limit (``strict``:
        by the clamp's own margin, so that rounding of the command cannot take it out again)."""
        Q = self.position[j] * ((1.0 - REL_TOL) if strict else (1.0 + REL_TOL))
        if -self.free[j] <= q <= self.free[j]:
            return True
        A, J = self.acceleration[j], self.jerk[j]
        slack = STOP_SLACK_STEPS * abs(v_c) * self.dt
        d = stop_distance(v_c, a, A, J)
        back = reverse_distance(v_c, a, A, J)
        rs = slack if back > 0.0 else 0.0
        if d >= 0.0:
            return q + d + slack <= Q and q - back - rs >= -Q
        return q + d - slack >= -Q and q + back + rs <= Q

    def _bounds(self, j: int, v1: float, a1: float, q1: float, q2: float, jerk: bool,
                jerk_floor: float = 0.0) -> tuple[float, float]:  # fmt: skip
        """The interval [rad/s²] of next accelerations of joint ``j`` that keep it brakeable, the position aside
        (``jerk``: within max(J, ``jerk_floor`` [rad/s³]) of the last acceleration too)."""
        dt = self.dt
        s = 1.0 - SHRINK
        V, A, J = self.velocity[j] * s, self.acceleration[j] * s, self.jerk[j] * s
        lo, hi = -A, A
        if jerk:
            JF = max(J, jerk_floor * s)
            lo, hi = max(lo, a1 - JF * dt), min(hi, a1 + JF * dt)
        # step velocity v1 + a·dt and continuous velocity v1 + 1.5·a·dt within ±V
        lo = max(lo, (-V - v1) / dt, (-V - v1) / (1.5 * dt))
        hi = min(hi, (V - v1) / dt, (V - v1) / (1.5 * dt))
        # the peak while ramping down: h(a) = a|a|/2J + 1.5·dt·a + v1 within ±V (h increases with a)
        hi = min(hi, _peak_root(v1 - V, dt, J))
        lo = max(lo, -_peak_root(-v1 - V, dt, J))
        return lo, hi

    def _position_ok(self, j: int, q1: float, v1: float, a: float, strict: bool = True) -> bool:
        dt = self.dt
        v = v1 + a * dt
        return self.room_to_stop(j, q1 + v * dt, v + 0.5 * a * dt, a, strict)

    # -- a command ---------------------------------------------------------------------------------------------
    def admit(self, q: Sequence[float], q1: Sequence[float], q2: Sequence[float], q3: Sequence[float],
              jerk: bool = False, jerk_floor: Sequence[float] | None = None) -> Admission:  # fmt: skip
        """The command nearest ``q`` [rad] (per joint) that keeps a braking stop available, after the executed
        commands ``q1``, ``q2``, ``q3`` (one, two and three periods before). ``jerk``: also within the jerk limit
        relative to them — per joint at least ``jerk_floor`` [rad/s³] if given (a path's own jerk, which the
        envelope does not judge). ``reason`` is set (and ``q`` is meaningless) when the history itself leaves no
        admissible command (the robot must brake) or ``q`` is not 7 finite values."""
        if q is None or len(q) != 7:
            return Admission(
                tuple(q1), 0.0, -1, f"the joint position command has {0 if q is None else len(q)} values, not 7"
            )
        dt = self.dt
        idt2 = 1.0 / (dt * dt)
        k = (1.0 + REL_TOL) * dt
        if _quick is not None:  # every joint inside every bound and far from its position limit: accepted as it is
            packed = _PACK7(*jerk_floor) if jerk and jerk_floor is not None else None
            if _quick.admit(q, q1, q2, q3, self._packed_bounds, packed, jerk, k, idt2, dt):
                return Admission(tuple(q), 0.0, -1, None)
        out: list[float] | None = None
        worst, worst_j = 0.0, -1
        floor = jerk_floor if jerk and jerk_floor is not None else _NO_FLOOR
        for j, x, p1, p2, p3, (A, JD, V, J2, free), jf in zip(range(7), q, q1, q2, q3, self._fast_bounds, floor):
            if jf * k > JD:
                JD = jf * k
            a = (x - 2.0 * p1 + p2) * idt2
            v1 = (p1 - p2) / dt
            # most commands: inside every bound and far from the position limit — a few float operations, inline
            # (this runs for every joint of every cycle)
            if -A <= a <= A and (not jerk or -JD <= a - (p1 - 2.0 * p2 + p3) * idt2 <= JD):  # (also NaN)
                v = v1 + a * dt
                v_c = v + 0.5 * a * dt
                if -V <= v <= V and -V <= v_c <= V and -V <= v_c + a * abs(a) / J2 <= V:
                    if -free <= x <= free or self.room_to_stop(j, x, v_c, a):
                        continue
            a1 = (p1 - 2.0 * p2 + p3) * idt2
            if not math.isfinite(x):
                return Admission(tuple(q1), 0.0, j, f"A{j + 1} command is {x}: not a number")
            lo, hi = self._bounds(j, v1, a1, p1, p2, jerk, jf)
            if lo > hi:
                return Admission(tuple(q1), 0.0, j, self._describe(j, v1, a1))
            b = min(max(a, lo), hi)
            if not self._position_ok(j, p1, v1, b):
                b = self._position_bound(j, p1, v1, a, lo, hi, True)
                if b is None:  # not with the clamp's margin: as close as the check allows
                    b = self._position_bound(j, p1, v1, a, lo, hi, False)
                if b is None:
                    return Admission(tuple(q1), 0.0, j, f"A{j + 1} at {p1:.4f} rad moving {v1:+.4f} rad/s can no "
                                     f"longer stop before its position limit ±{self.position[j]:.4f} rad")  # fmt: skip
            if b != a:
                y = 2.0 * p1 - p2 + b * dt * dt
                if out is None:
                    out = list(q)
                out[j] = y
                d = abs(y - x)
                if d > worst:
                    worst, worst_j = d, j
        return Admission(tuple(q) if out is None else tuple(out), worst, worst_j, None)

    def admit_either(self, q: Sequence[float], histories: Sequence[tuple], jerk: bool = False) -> Admission:
        """As :meth:`admit`, but admissible after each of ``histories`` ((q1, q2, q3) each): when it is not known
        which the controller executed (a reply it may have bridged). Per joint the command is clamped into the
        intersection of the intervals — the velocity and acceleration bounds after every history, the jerk bound
        after the first one as far as it fits (the bridged history's jump in acceleration is the controller's);
        where they do not meet, into the first history's."""
        first = self.admit(q, *histories[0], jerk)
        if first.reason is not None or len(histories) == 1:
            return first
        if all(self.admit(first.q, *h, False).clamped == 0.0 for h in histories[1:]):
            return first
        out = list(first.q)
        worst, worst_j = first.clamped, first.joint
        for j in range(7):
            lo = hi = math.nan
            for with_jerk in (True, False) if jerk else (False,):
                lo, hi = -math.inf, math.inf
                for k, h in enumerate(histories):
                    iv = self._interval(j, h[0][j], h[1][j], h[2][j], with_jerk and k == 0)
                    if iv is not None:
                        lo, hi = max(lo, iv[0]), min(hi, iv[1])
                if lo <= hi:
                    break
            if lo <= hi:
                y = min(max(q[j], lo), hi)
                if y != out[j]:
                    out[j] = y
                    d = abs(y - q[j])
                    if d > worst:
                        worst, worst_j = d, j
        return Admission(tuple(out), worst, worst_j, None)

    def _interval(self, j: int, p1: float, p2: float, p3: float, jerk: bool) -> tuple[float, float] | None:
        """The commands [rad] of joint ``j`` admissible after (p1, p2, p3), with the clamp's margins; None: none."""
        dt = self.dt
        v1 = (p1 - p2) / dt
        a1 = (p1 - 2.0 * p2 + p3) / (dt * dt)
        lo, hi = self._bounds(j, v1, a1, p1, p2, jerk)
        if lo > hi:
            return None
        if not self._position_ok(j, p1, v1, hi):
            b = self._position_bound(j, p1, v1, math.inf, lo, hi, True)
            if b is None:
                return None
            hi = b
        if not self._position_ok(j, p1, v1, lo):
            b = self._position_bound(j, p1, v1, -math.inf, lo, hi, True)
            if b is None:
                return None
            lo = b
        base = 2.0 * p1 - p2
        return base + lo * dt * dt, base + hi * dt * dt

    @cached_property
    def _fast_bounds(self) -> tuple[tuple[float, float, float, float, float], ...]:
        """Per joint the bounds of :meth:`admit`'s quick acceptance: A·k [rad/s²], J·dt·k [rad/s²] (the jerk bound on one
        step's change of acceleration), V·k [rad/s], 2·J [rad/s³] and free [rad], k = 1 + REL_TOL."""
        k = 1.0 + REL_TOL
        return tuple((self.acceleration[j] * k, self.jerk[j] * self.dt * k, self.velocity[j] * k, 2.0 * self.jerk[j],
                      self.free[j]) for j in range(7))  # fmt: skip

    @cached_property
    def _packed_bounds(self) -> bytes:
        """:attr:`_fast_bounds` as 35 float64 (for the compiled quick acceptance)."""
        return struct.pack("35d", *(x for b in self._fast_bounds for x in b))

    def _position_bound(self, j: int, p1: float, v1: float, a: float, lo: float, hi: float,
                        strict: bool) -> float | None:  # fmt: skip
        """The acceleration in [lo, hi] nearest ``a`` whose stop ends inside the position limit (bisection: the stop's
        end grows with the acceleration); None if there is none."""
        ok_lo, ok_hi = self._position_ok(j, p1, v1, lo, strict), self._position_ok(j, p1, v1, hi, strict)
        if not ok_lo and not ok_hi:
            return None
        # the admissible part is an interval touching lo (upper limit in the way) or hi (lower limit in the way)
        good, bad = (lo, hi) if ok_lo else (hi, lo)
        if (a - good) * (bad - good) <= 0.0:  # a lies beyond good, away from the limit: it was admissible
            return min(max(a, lo), hi)
        for _ in range(40):
            mid = 0.5 * (good + bad)
            if self._position_ok(j, p1, v1, mid, strict):
                good = mid
            else:
                bad = mid
        return good

    def explain(self, j: int, q: float, v: float, a: float) -> str:
        """Why the step state (q [rad], v [rad/s], a [rad/s²]) of joint ``j`` (0-based) is not brakeable."""
        V, A, Q = self.velocity[j], self.acceleration[j], self.position[j]
        k = 1.0 + REL_TOL
        v_c = v + 0.5 * a * self.dt
        if not math.isfinite(q + v + a):
            return f"A{j + 1} command is not a number"
        if abs(q) > Q * k:
            return f"A{j + 1} command {q:.6f} rad outside the position limit ±{Q:.6f} rad"
        if abs(v) > V * k:
            return f"A{j + 1} step of {v:+.4f} rad/s exceeds the velocity limit {V:.4f} rad/s"
        if abs(a) > A * k:
            return f"A{j + 1} acceleration {a:+.2f} rad/s² exceeds the acceleration limit {A:.2f} rad/s²"
        peak = velocity_peak(v_c, a, self.jerk[j])
        if max(abs(v_c), abs(peak)) > V * k:
            return (f"A{j + 1} at {v:+.4f} rad/s accelerating {a:+.2f} rad/s² leaves no braking stop within the "
                    f"velocity limit {V:.4f} rad/s (a jerk-limited stop would reach {peak:+.4f} rad/s)")  # fmt: skip
        d = stop_distance(v_c, a, self.acceleration[j], self.jerk[j])
        return (f"A{j + 1} at {q:.6f} rad moving {v:+.4f} rad/s cannot stop before the position limit "
                f"±{Q:.6f} rad (it needs to {q + d:.6f} rad)")  # fmt: skip

    def _describe(self, j: int, v1: float, a1: float) -> str:
        v_c = v1 + 0.5 * a1 * self.dt
        peak = velocity_peak(v_c, a1, self.jerk[j])
        return (f"A{j + 1} moving {v1:+.4f} rad/s accelerating {a1:+.2f} rad/s² cannot stop within the limits (a stop "
                f"would reach {peak:+.4f} rad/s, limit {self.velocity[j]:.4f} rad/s)")  # fmt: skip

    def state_ok(self, q1: Sequence[float], q2: Sequence[float], q3: Sequence[float]) -> int:
        """−1 if the state the commands ``q1`` (newest), ``q2``, ``q3`` [rad] leave is brakeable, else the first joint
        (0-based) that is not."""
        dt = self.dt
        for j in range(7):
            v = (q1[j] - q2[j]) / dt
            a = (q1[j] - 2.0 * q2[j] + q3[j]) / (dt * dt)
            if not self.joint_ok(j, q1[j], v, a):
                return j
        return -1


def _peak_root(c: float, dt: float, J: float) -> float:
    """The root of a|a|/(2J) + 1.5·dt·a + c = 0 (increasing in a) [rad/s²]; ``c`` = v1 − V."""
    b = 1.5 * dt
    if c <= 0.0:  # root ≥ 0: a²/2J + b·a + c = 0
        return J * (-b + math.sqrt(b * b - 2.0 * c / J))
    # root < 0: −a²/2J + b·a + c = 0  →  a² − 2Jb·a − 2Jc = 0, the negative root
    return J * b - math.sqrt(J * J * b * b + 2.0 * J * c)


# -- whole files (numpy) -------------------------------------------------------------------------------------------
def brakeable(q: np.ndarray, dt: float, limits: JointLimits) -> tuple[np.ndarray, np.ndarray]:
    """For rows ``q`` (n, 7) [rad] streamed one per ``dt`` [s] from rest: (peak, room) — the velocity [rad/s] a
    braking stop from each row would reach (n, 7; compare with the velocity limit) and whether its stop ends inside
    the position limits (n, 7, bool)."""
    q = np.asarray(q, dtype=float)
    padded = np.vstack([q[:1], q[:1], q])
    v = np.diff(padded, axis=0)[1:] / dt  # (n, 7) step velocity at each row
    a = np.diff(padded, 2, axis=0) / (dt * dt)
    v_c = v + 0.5 * a * dt
    peak = v_c + a * np.abs(a) / (2.0 * limits.jerk)
    peak = np.where(np.abs(v_c) > np.abs(peak), v_c, peak)
    env = BrakingEnvelope.from_limits(limits, dt)
    room = np.ones(q.shape, dtype=bool)
    near = np.abs(q) > np.asarray(env.free)[None, :]
    for i, j in zip(*np.nonzero(near)):
        room[i, j] = env.room_to_stop(int(j), float(q[i, j]), float(v_c[i, j]), float(a[i, j]))
    return peak, room
