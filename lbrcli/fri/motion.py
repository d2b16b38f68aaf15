"""The motion-safety core: what the controller executes from our commands, and what may follow it.

:class:`ExecutedMotion` keeps the last three joint positions sent in COMMANDING_ACTIVE — continued, over lost
monitoring messages, as the controller's extrapolation continued them — and admits each next command only into the
braking envelope (:class:`trajectories.envelope.BrakingEnvelope`: a jerk-limited stop from the state it creates stays
inside every limit). A client's command outside it is clamped to it (feedback and following clients) or, when the
client asked for its command to be sent exactly (a file's rows), ends the session with the braking stop instead; the
guard then checks what is sent (a refusal is a bug signal). Every client-side stop brakes from the executed history
(``BrakingStop``) and, in TORQUE or WRENCH mode, ramps the effort down (:class:`EffortRamp`). One instance per
session, built when the command period is known; the same for every client.
"""

from __future__ import annotations

import math
from typing import Any, Sequence

from trajectories.envelope import BrakingEnvelope
from trajectories.limits import JointLimits

from .braking import BrakingStop
from .constants import STATE_COMMANDING_ACTIVE as _CMD_ACTIVE
from .constants import ClientCommandMode
from .guard import CommandGuard
from .rejoin import Rejoin

_TORQUE = int(ClientCommandMode.TORQUE)
_WRENCH = int(ClientCommandMode.WRENCH)
_ZERO6 = (0.0,) * 6
_ZERO7 = (0.0,) * 7
CLAMP_TOL = 1e-12  # [rad] a change below this is rounding, not a clamp
BENT_CYCLES = 50  # after a clamp of the bridged history's making, an exact client's rows are clamped back onto
# the path (not refused) for this many commands
ALT_CYCLES = 3  # commands judged also against the bridged history after a reply the controller reported missing
MATCH_TOL = 1e-9  # [rad] the position a message reports is the bridged one or ours (rounding of its arithmetic)
REJOIN_MAX = 0.05  # [rad] an offset back onto the client's path larger than this ends the session (braking stop)
EFFORT_RAMP_MIN_S = 0.05  # [s] the shortest effort ramp of a stop
EFFORT_RANGE_S = (
    0.25  # [s] a stop ramps an effort down at most at its whole range (torque limit, wrench bound) per this
)


class Refused(Exception):
    """A command failed the guard and nothing is moving under our command: end without sending it."""


class EffortRamp:
    """The torque or wrench of a stop: from the last one sent to zero along a raised cosine whose steepest rate is at
    most ``rates`` [Nm/s or N/s per component] (and that lasts at least ``EFFORT_RAMP_MIN_S``)."""

    def __init__(self, rates: Sequence[float], period_s: float) -> None:
        self.rates = tuple(rates)
        self.period_s = period_s
        self._from: tuple[float, ...] = ()
        self._n = 0
        self._k = 0

    def start(self, effort: Sequence[float]) -> None:
        self._from = tuple(effort)
        # a raised cosine from e to 0 over T has its steepest rate π·|e| / (2T)
        t = max([EFFORT_RAMP_MIN_S] + [math.pi * abs(e) / (2.0 * r) for e, r in zip(self._from, self.rates)])
        self._n = max(1, int(math.ceil(t / self.period_s)))
        self._k = 0

    @property
    def done(self) -> bool:
        return self._k >= self._n

    def next(self) -> tuple[float, ...]:
        if self._k < self._n:
            self._k += 1
        s = 0.5 * (1.0 + math.cos(math.pi * self._k / self._n))
        return tuple(e * s for e in self._from)


class ExecutedMotion:
    """The sent history [rad], the envelope and guard on the next command, the braking stop (``hold_cycles`` at rest
    after it) and the effort ramps of TORQUE and WRENCH mode."""

    def __init__(self, limits: JointLimits, period_s: float, max_force: float, max_moment: float, hold_cycles: int,
                 q: Sequence[float]) -> None:  # fmt: skip
        self.period_s = period_s
        self.guard = CommandGuard.from_limits(limits, period_s, max_force, max_moment)
        self.envelope: BrakingEnvelope = self.guard.envelope
        self._limits = limits
        self.brake = BrakingStop(limits, period_s)  # ready before it is needed
        # effort rates of a stop: the whole torque table, or the wrench bounds, per EFFORT_RANGE_S
        self.torque_ramp = EffortRamp([float(t) / EFFORT_RANGE_S for t in limits.torque], period_s)
        self.wrench_ramp = EffortRamp([b / EFFORT_RANGE_S for b in [max_force] * 3 + [max_moment] * 3], period_s)
        self.hold_cycles = hold_cycles
        self.prev = self.prev2 = self.prev3 = tuple(q)  # what the controller executed, newest first
        self._s1 = self._s2 = self._s3 = self.prev  # the last commands sent, newest first
        self.active_sent = 0  # joint positions sent in COMMANDING_ACTIVE
        self.braking = False
        self.hold_left = 0
        self.braking_cycles = 0
        self.extrapolated_cycles = 0
        self.clamped_cycles = 0  # commands the core changed to keep a braking stop available
        self.largest_clamp = 0.0  # [rad]
        self.last_clamp = 0.0  # [rad] the change the last admitted command needed
        self.last_torque: tuple[float, ...] | None = None  # the effort last sent (TORQUE / WRENCH mode)
        self.last_wrench: tuple[float, ...] | None = None
        self._ramp: EffortRamp | None = None
        self._alt: tuple | None = None  # the history had the controller bridged a reply it reported missing
        self._alt_left = 0
        self.loss_refused = False  # the last refusal came from replies the controller reported missing
        self._bent = 0  # cycles left in which an exact client's rows may be clamped back onto the path
        self.rebased = False  # the history was just replaced by the one the controller bridged (until the next send)
        self.rebased_cycles = 0  # replies the controller reported missing whose bridged history it confirmed
        self.rejoin = Rejoin(limits, period_s)  # the offset back onto the client's path after such a bridge
        self.rejoin_cycles = 0  # commands sent with a rejoin offset
        # the executed history minus the client's own commands, newest first (None: none), and the next one's
        self._d1: tuple | None = None
        self._d2: tuple | None = None
        self._d3: tuple | None = None
        self._pend: tuple | None = None
        self._replan = False

    @property
    def moving(self) -> bool:
        """Commands were sent in COMMANDING_ACTIVE: a stop must brake."""
        return self.active_sent > 0

    # -- the executed state, for clients that re-plan ---------------------------------------------------------
    @property
    def position(self) -> tuple[float, ...]:
        """[rad] where the controller was last commanded (its extrapolation included)."""
        return self.prev

    @property
    def velocity(self) -> tuple[float, ...]:
        """[rad/s] the continuous velocity the history continues into (step velocity + half a period of its
        acceleration): what a re-planned motion starts from."""
        dt = self.period_s
        return tuple((3.0 * a - 4.0 * b + c) / (2.0 * dt) for a, b, c in zip(self.prev, self.prev2, self.prev3))

    @property
    def acceleration(self) -> tuple[float, ...]:
        """[rad/s²] the last step acceleration."""
        dt2 = self.period_s * self.period_s
        return tuple((a - 2.0 * b + c) / dt2 for a, b, c in zip(self.prev, self.prev2, self.prev3))

    def extrapolate(self, n: int) -> int:
        """The controller bridged ``n`` command periods without our commands: continue the history as it did (at the
        last commands' velocity, within the velocity limit); ``n`` (≤ 64). A braking stop goes on from there."""
        n = min(n, 64)
        cap = self.guard.max_step
        for _ in range(n):
            prev, prev2 = self.prev, self.prev2
            nxt = tuple(p + max(-c, min(c, p - b)) for p, b, c in zip(prev, prev2, cap))
            self.prev3, self.prev2, self.prev = prev2, prev, nxt
        self.extrapolated_cycles += n
        if n:  # the client re-plans from here (it is told the periods it skipped): no offset from its old path
            self._s1, self._s2, self._s3 = self.prev, self.prev2, self.prev3
            self._forget_path()
        if self.braking and n:  # the stop's profile no longer starts where the robot is: re-plan it from there
            self.brake.start(self.prev, self.prev2, self.prev3)
        return n

    def reply_lost(self, position: Sequence[float] | None = None) -> bool:
        """The controller's reflected counter says our last command had not reached it when it sent its message: it
        bridged that period (it held the velocity of the commands before) or executed our command late (our
        simulator carries a late command forward by its lateness). The message's ``position`` [rad] (the commanded
        position it reports, else the measured one) may say which: the bridged position, or the command sent the
        period before carried forward by a period (within ``MATCH_TOL``), is the executed history from now on — True, :attr:`rebased`; a braking stop is re-planned from it, any other motion
        rejoins the client's path (:class:`~lbrcli.fri.rejoin.Rejoin`); our command: nothing changes. Anything else
        (a command later still, a real robot's measured position, which lags): for the next ``ALT_CYCLES``
        commands the envelope admits only what is admissible after either the sent or the bridged history."""
        cap = self.guard.max_step
        base = self._alt if self._alt is not None else (self.prev, self.prev2, self.prev3)  # losses in a row: its own
        bridged = tuple(p + max(-c, min(c, p - b)) for p, b, c in zip(base[1], base[2], cap))
        if position is not None and len(position) == 7:
            # bridged, or the command we sent the period before carried forward by one period (a late reply)
            late = tuple(p + max(-c, min(c, p - b)) for p, b, c in zip(self._s2, self._s3, cap))
            for executed in (bridged, late):
                new = (executed, base[1], base[2])  # (a history the envelope cannot brake from: not taken)
                if (
                    max(abs(x - y) for x, y in zip(position, executed)) <= MATCH_TOL
                    and self.envelope.state_ok(*new) < 0
                ):
                    self._rebase(new)
                    return True
            if max(abs(x - y) for x, y in zip(position, self.prev)) <= MATCH_TOL:  # it executed our command
                self._alt, self._alt_left = None, 0
                return False
        self._alt = (bridged, base[1], base[2])
        self._alt_left = ALT_CYCLES
        self._forget_path()  # the executed history is a guess now: no offset planned from it
        return False

    def _forget_path(self) -> None:
        """No offset back onto the client's path (the client re-plans from the executed state, as after a clamp)."""
        self._d1 = self._d2 = self._d3 = self._pend = None
        self.rejoin.done = True

    def _rebase(self, new: tuple) -> None:
        """``new`` (three positions [rad], newest first) is the history the controller executed."""
        old = (self.prev, self.prev2, self.prev3)
        d = [tuple(x - y + z for x, y, z in zip(n, o, dk or _ZERO7))
             for n, o, dk in zip(new, old, (self._d1, self._d2, self._d3))]  # fmt: skip
        self._d1, self._d2, self._d3 = d  # (the executed history minus the client's commands)
        self.prev, self.prev2, self.prev3 = new
        self._alt, self._alt_left = None, 0
        self.rebased = True
        self.rebased_cycles += 1
        self._bent = BENT_CYCLES  # an exact client's next rows, measured against it, may need a clamp
        if self.braking:  # the stop's profile no longer starts where the robot is: re-plan it from there
            self.brake.start(self.prev, self.prev2, self.prev3)
        else:  # back onto the client's path within the limits
            self.rejoin.start(*d)

    def retime(self, period_s: float) -> None:
        """The controller executes each command in ``period_s`` [s], faster than its period says: plan the braking
        stop at that period (the executed history is faster than we thought, and so must be its deceleration)."""
        if period_s < self.period_s and not self.braking:
            self.brake = BrakingStop(self._limits, period_s)

    def begin_braking(self) -> None:
        if not self.braking:
            self.brake.start(self.prev, self.prev2, self.prev3)
            self.braking = True
            self.hold_left = self.hold_cycles
            self._ramp = None

    def held_long_enough(self) -> bool:
        """Count one cycle at rest after the braking stop (and the effort ramp); True when the hold is over."""
        if not (self.braking and self.brake.done and (self._ramp is None or self._ramp.done)):
            return False
        self.hold_left -= 1
        return self.hold_left <= 0

    def admit(self, q: Sequence[float], exact: bool, jerk: bool) -> tuple[tuple[float, ...] | None, str | None]:
        """The position to send for the client's ``q`` [rad] in COMMANDING_ACTIVE: (q or its clamp, None), or
        (None, why) when it cannot be sent (not 7 finite values, no admissible command, or ``exact`` and a clamp
        would change it)."""
        env = self.envelope
        self.loss_refused = False
        raw = q
        if not self.rejoin.done and q is not None and len(q) == 7:  # after a bridged command: the offset back
            off = self.rejoin.next()
            self.rejoin_cycles += 1
            far = max(abs(e) for e in off)
            if far > REJOIN_MAX:  # bridged so often that the motion cannot keep to the path within the limits
                self.loss_refused = True
                return None, (f"replies lost: the commands the controller bridged left the motion {far:.4f} rad off "
                              f"the client's path (more than {REJOIN_MAX:g} rad)")  # fmt: skip
            q = tuple(x + e for x, e in zip(q, off))
        adm = env.admit(q, self.prev, self.prev2, self.prev3, jerk)
        if adm.reason is not None:
            return None, adm.reason
        if exact and adm.clamped > CLAMP_TOL and not self._bent and self.rejoin.done:  # the client's own command
            # leaves the envelope: refuse, never bend it (unless we bent the path just before, after a reply the
            # controller may have bridged, or are taking the motion back onto it)
            j = adm.joint
            dt = self.period_s
            p1, p2 = self.prev[j], self.prev2[j]
            return None, self.envelope.explain(j, q[j], (q[j] - p1) / dt, (q[j] - 2.0 * p1 + p2) / (dt * dt))
        if self._alt is not None:  # after a reply that may be lost: admissible after the bridged history too (a
            # clamp of the controller's making, ≈ acceleration × period², also for exact clients)
            adm = env.admit_either(q, ((self.prev, self.prev2, self.prev3), self._alt), jerk)
            if adm.clamped > CLAMP_TOL:
                self._bent = BENT_CYCLES
            if adm.reason is not None:
                self.loss_refused = True
                return None, (f"replies lost: no command suits both what the controller executed and what it "
                              f"bridged ({adm.reason})")  # fmt: skip
        self.last_clamp = adm.clamped
        if adm.clamped > CLAMP_TOL:
            self.clamped_cycles += 1
            if adm.clamped > self.largest_clamp:
                self.largest_clamp = adm.clamped
        if raw is not q or adm.clamped > 0.0:  # what is sent differs from the client's command by this much
            self._pend = tuple(x - y for x, y in zip(adm.q, raw))
            self._replan = raw is not q and adm.clamped > 0.0  # a clamp of the offset: re-plan it from there
        return adm.q, None

    def next_command(self, measured: Sequence[float], state: int, mode: int, q: Sequence[float],
                     tau: Sequence[float] | None, wrench: Sequence[float] | None, exact: bool = False,
                     jerk: bool = False) -> tuple[Any, Any, Any, str | None]:  # fmt: skip
        """The command to send (q [rad], tau [Nm] or None, wrench or None) and, if the client's could not be sent,
        why (the braking stop then replaces it). While braking the client's is ignored. :class:`Refused` when the
        command cannot be sent and nothing moves under our command (or the stop itself failed)."""
        guard = self.guard
        if state == _CMD_ACTIVE:
            prev, prev2 = self.prev, self.prev2
        else:  # COMMANDING_WAIT: the robot stands where it is measured, the command must be reachable from there
            prev = prev2 = tuple(measured)
        if self.braking:
            return self._braking_command(mode, prev, prev2)
        reason = None
        if state == _CMD_ACTIVE:
            q, reason = self.admit(q, exact, jerk)
        if reason is None:
            reason = guard.refuse_position(q, prev, prev2, state != _CMD_ACTIVE)
        if reason is None and mode == _TORQUE:
            tau = tau if tau is not None else _ZERO7
            reason = guard.refuse_torque(tau)
        elif reason is None and mode == _WRENCH:
            wrench = wrench if wrench is not None else _ZERO6
            reason = guard.refuse_wrench(wrench)
        if reason is None:
            if mode == _TORQUE:
                self.last_torque = tuple(tau)  # type: ignore[arg-type]
            elif mode == _WRENCH:
                self.last_wrench = tuple(wrench)  # type: ignore[arg-type]
            return q, tau, wrench, None
        text = reason if self.loss_refused else f"guard refused the command: {reason}"
        if state != _CMD_ACTIVE or not self.moving:
            raise Refused(text)
        self.begin_braking()
        q, tau, wrench, _ = self._braking_command(mode, prev, prev2)
        return q, tau, wrench, text

    def _braking_command(self, mode: int, prev: Sequence[float], prev2: Sequence[float]) -> tuple[Any, Any, Any, None]:
        q = self.brake.next()
        self.braking_cycles += 1
        if self.guard.refuse_position(q, prev, prev2, False) is not None:
            q = prev  # cannot happen from inside the envelope; a hold is the last resort
        tau = wrench = None
        if mode == _TORQUE or mode == _WRENCH:
            if self._ramp is None:
                self._ramp = self.torque_ramp if mode == _TORQUE else self.wrench_ramp
                last = self.last_torque if mode == _TORQUE else self.last_wrench
                self._ramp.start(last if last is not None else (_ZERO7 if mode == _TORQUE else _ZERO6))
            if mode == _TORQUE:
                tau = self._ramp.next()
            else:
                wrench = self._ramp.next()
        return q, tau, wrench, None

    def sent(self, q: tuple[float, ...], state: int) -> None:
        """``q`` [rad] went out: in COMMANDING_ACTIVE the controller executes it."""
        if state == _CMD_ACTIVE:
            self.prev3, self.prev2, self.prev = self.prev2, self.prev, q
            self._s3, self._s2, self._s1 = self._s2, self._s1, q  # (what was sent, also where a rebase replaced it)
            self.active_sent += 1
            self.rebased = False
            self._d3, self._d2, self._d1, self._pend = self._d2, self._d1, self._pend, None
            if self._replan:
                self._replan = False
                self.rejoin.start(self._d1, self._d2 or _ZERO7, self._d3 or _ZERO7)  # type: ignore[arg-type]
            if self._bent:
                self._bent -= 1
            if self._alt is not None:
                a = self._alt
                self._alt = (q, a[0], a[1])
                self._alt_left -= 1
                if self._alt_left <= 0:
                    self._alt = None
        else:
            self.prev = self.prev2 = self.prev3 = self._s1 = self._s2 = self._s3 = q
