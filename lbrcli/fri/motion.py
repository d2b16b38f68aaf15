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

from typing import Any, Sequence

from trajectories.envelope import BrakingEnvelope
from trajectories.limits import JointLimits

from .braking import EFFORT_RAMP_MIN_S, BrakingStop, Coast, EffortRamp  # noqa: F401 (re-exported)
from .constants import STATE_COMMANDING_ACTIVE as _CMD_ACTIVE
from .constants import ClientCommandMode
from .guard import CommandGuard
from .rejoin import Rejoin, executed_history, gap_history, gap_offsets, path_jerk, far as _far

_TORQUE = int(ClientCommandMode.TORQUE)
_WRENCH = int(ClientCommandMode.WRENCH)
_ZERO6 = (0.0,) * 6
_ZERO7 = (0.0,) * 7
CLAMP_TOL = 1e-12  # [rad] a change below this is rounding, not a clamp
BENT_CYCLES = 50  # after a clamp of the bridged history's making, an exact client's rows are clamped back onto
# the path (not refused) for this many commands
ALT_CYCLES = 3  # commands judged also against the bridged history after a reply the controller reported missing
MATCH_TOL = 1e-9  # [rad] the commanded position a message reports is ours (rounding of its arithmetic)
NOISE_ALLOWANCE = 2e-5  # [rad] a measured position (FRI 2.x) this close to the model's is the model's (sensor noise)
JERK_CYCLES = 100  # after the controller bridged a period: commands held to the jerk limit of what it executed, for
# this many commands after the last one that needed it (every client, jerk-limited or not)
COAST_MAX = 10  # commands coasting at most, then back onto the client's path while replies stay late (no coast
# again until the controller confirms one in time: a busy machine would coast off the path)
REJOIN_MAX = 0.05  # [rad] an offset back onto the client's path larger than this ends the session (braking stop)
EFFORT_RANGE_S = 0.25  # [s] a stop ramps an effort down by at most its range (torque limit, wrench bound) per this


class Refused(Exception):
    """A command failed the guard and nothing is moving under our command: end without sending it."""


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
        self.coast = Coast(limits, period_s)  # our commands while the controller's confirmations lag
        self.coasting = False
        self.lagging, self._coast_left = False, COAST_MAX  # lagging: no reply confirmed in time since one was bridged
        self.replans = False  # the client re-plans from the executed state (``replan_due``) instead of an offset
        self.replan_due = False  # set when it should (until the client's next command)
        self.coast_cycles = 0  # commands sent coasting
        self.rejoin_cycles = 0  # commands sent with a rejoin offset
        # the executed history minus the client's own commands, newest first (None: none), and the next one's
        self._d1: tuple | None = None
        self._d2 = self._d3 = self._d1
        self._pend: tuple | None = None
        self._replan: bool | tuple = False  # a clamp to re-plan the offset from (a tuple: shift its plan by it)
        self._gap: tuple | None = None  # (our last two commands) before the gap just extrapolated
        self._jerk_left = 0  # commands left that are held to the jerk limit whatever the client asked
        self._c1: tuple | None = None  # the client's last three commands (before any offset), newest first
        self._c2 = self._c3 = self._c1
        self._c_run = 0  # of those, how many are one period apart (none across a gap)
        self._gap_path: tuple | None = None  # (those two, the periods bridged) at a gap, until the client's next

    moving = property(lambda self: self.active_sent > 0, doc="Commands were sent in COMMANDING_ACTIVE: a stop must brake.")  # fmt: skip
    steady = property(lambda self: self.rejoin.done and not (self.coasting or self.replan_due or self._gap or self._gap_path),
                      doc="No bridge being made up for: a prepared reply may go out (held to the jerk limit).")  # fmt: skip

    # -- the executed state, for clients that re-plan ---------------------------------------------------------
    position = property(lambda self: self.prev, doc="[rad] where the controller was last commanded (extrapolation included).")  # fmt: skip

    velocity = property(lambda self: tuple((3.0 * a - 4.0 * b + c) / (2.0 * self.period_s) for a, b, c in zip(self.prev, self.prev2, self.prev3)),
                        doc="[rad/s] the history's continuous velocity (step velocity + half a period of its acceleration).")  # fmt: skip
    acceleration = property(lambda self: tuple((a - 2.0 * b + c) / self.period_s**2 for a, b, c in zip(self.prev, self.prev2, self.prev3)),
                            doc="[rad/s²] the last step acceleration.")  # fmt: skip

    def extrapolate(self, n: int) -> int:
        """The controller bridged ``n`` command periods without our commands: continue the history as it did (at the
        last commands' velocity, within the velocity limit); ``n`` (≤ 64). A braking stop goes on from there."""
        n = min(n, 64)
        cap = self.guard.max_step
        self._gap = (self.prev, self.prev2) if n else None  # (what the first message after the gap is judged from)
        if n:  # (the client's next command comes n periods after its last: no jerk of its own from those)
            self._jerk_left, self._c_run = JERK_CYCLES, 0
            # the client's path before the gap: its next command after it is joined to the executed history
            self._gap_path = (self._c1, self._c2, n) if self._c2 is not None else None
        for _ in range(n):
            prev, prev2 = self.prev, self.prev2
            nxt = tuple(p + max(-c, min(c, p - b)) for p, b, c in zip(prev, prev2, cap))
            self.prev3, self.prev2, self.prev = prev2, prev, nxt
        self.extrapolated_cycles += n
        if n and self.coasting:  # the coast no longer starts where the robot is
            self.coast.start(self.prev, self.prev2, self.prev3)
        if n:  # the client re-plans from here (it is told the periods it skipped), or goes on along its path: the
            # offset from where the controller went is planned at its next command (:meth:`_join_gap`)
            self._s1, self._s2, self._s3 = self.prev, self.prev2, self.prev3
            self._forget_path()
        if self.braking and n:  # the stop's profile no longer starts where the robot is: re-plan it from there
            self.brake.start(self.prev, self.prev2, self.prev3)
        return n

    def reply_lost(self, position: Sequence[float] | None = None, measured: bool = False) -> bool:
        """The controller's reflected counter says our last command had not reached it when it sent its message: it
        bridged that period (held, or extrapolated, its velocity) or executed an older command of ours late. Which,
        the message's ``position`` [rad] says — the commanded position of FRI 1.15, exactly; ``measured`` (FRI 2.x): the
        measured one, taken as the bridged extrapolation within ``NOISE_ALLOWANCE``, else as it is. Unless it is
        our command, that position is the executed one from now on (True, :attr:`rebased`): the history is
        :func:`~lbrcli.fri.rejoin.executed_history`, a braking stop is re-planned from it, any other motion rejoins the client's path
        (:class:`~lbrcli.fri.rejoin.Rejoin`) and, for ``JERK_CYCLES``, every client is held to the jerk limit.
        Without a position: for the next ``ALT_CYCLES`` commands the envelope admits only what is admissible after
        either the sent or the bridged history."""
        cap = self.guard.max_step
        base = self._alt if self._alt is not None else (self.prev, self.prev2, self.prev3)  # losses in a row: its own
        bridged = tuple(p + max(-c, min(c, p - b)) for p, b, c in zip(base[1], base[2], cap))
        if position is not None and len(position) == 7:
            x = tuple(position)
            tol = NOISE_ALLOWANCE if measured else MATCH_TOL
            if _far(x, self.prev) <= tol:  # it executed our command (late, carried forward): it follows us again
                self._alt, self._alt_left = None, 0
                self.confirmed()
                return False
            if measured and _far(x, bridged) <= tol:  # (a measured position: the model's, not the noise)
                x = bridged
            self._rebase(executed_history(self.envelope, x, self.prev2, self.prev3))
            return True
        self._alt = (bridged, base[1], base[2])
        self._alt_left = ALT_CYCLES
        self._forget_path()  # the executed history is a guess now: no offset planned from it
        return False

    def gap_seen(self, position: Sequence[float] | None, n: int, measured: bool = False) -> bool:
        """After :meth:`extrapolate` of ``n`` periods: the first message after the gap reports ``position`` [rad]
        (as :meth:`reply_lost`). If it is not where the extrapolation put the robot (a controller that held, or
        braked), the executed history becomes the one that ends there at the velocity it held over the gap (the
        average from our last command): True. The client re-plans from the executed state (no offset); for
        ``JERK_CYCLES`` every client is held to the jerk limit of it."""
        if self._gap is None or position is None or len(position) != 7:
            return False
        c, c1 = self._gap
        self._gap = None
        x = tuple(position)
        if _far(x, self.prev) <= (NOISE_ALLOWANCE if measured else MATCH_TOL):
            return False
        new = gap_history(self.envelope, x, c, c1, n)
        self.prev, self.prev2, self.prev3 = new
        self._s1, self._s2, self._s3 = new
        self.rebased = True
        self.rebased_cycles += 1
        self._bent = BENT_CYCLES
        self._jerk_left = JERK_CYCLES
        if self.braking:
            self.brake.start(*new)
        return True

    def _join_gap(self, q: Sequence[float]) -> None:
        """The client's first command ``q`` [rad] after a gap: its path over the gap is the parabola through its last
        two commands before and ``q``; the executed history minus it is the offset that :class:`Rejoin` brings to 0."""
        c1, c2, n = self._gap_path  # type: ignore[misc]
        self._gap_path = None
        if not self.replans:  # (a client that re-planned from the executed history: a path through it counts it twice)
            self._d1, self._d2, self._d3 = d = gap_offsets((self.prev, self.prev2, self.prev3), c1, c2, n, q)
            self.rejoin.start(*d)

    def _forget_path(self) -> None:  # no offset back onto the client's path (it re-plans from the executed state)
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
        self._jerk_left = JERK_CYCLES
        if self.braking:  # the stop's profile no longer starts where the robot is: re-plan it from there
            self.brake.start(self.prev, self.prev2, self.prev3)
        else:  # coast until the controller confirms our commands again, then back onto the client's path
            self.rejoin.done = True
            self.lagging = True
            if self._coast_left > 0:
                self.coast.start(self.prev, self.prev2, self.prev3)
                self.coasting = True
            else:
                self._back_to_path()

    def confirmed(self) -> None:
        """The controller's message reflects our last reply, in time: coasting ends, back onto the client's path."""
        self.lagging = False
        self._coast_left = COAST_MAX
        if self.coasting:
            self.coasting = False
            self._back_to_path()

    def _back_to_path(self) -> None:
        """The offset from the client's path (the commands sent minus the client's) brought back to zero
        (:class:`~lbrcli.fri.rejoin.Rejoin`), or the client told to re-plan from the executed state."""
        if self.braking:
            return
        if self.replans:
            self._forget_path()
            self.replan_due = True
        elif self._d1 is not None:
            self.rejoin.start(self._d1, self._d2 or _ZERO7, self._d3 or _ZERO7)

    def retime(self, period_s: float) -> None:
        """The controller executes each command in ``period_s`` [s], faster than its period says: plan the braking
        stop at that period (the executed history is faster than we thought, and so must be its deceleration)."""
        if period_s < self.period_s and not self.braking:
            self.brake = BrakingStop(self._limits, period_s)

    def begin_braking(self) -> None:
        self.coasting = False
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
        self.loss_refused = self.replan_due = end_coast = False
        raw, hist = q, None
        if q is not None and len(q) == 7:
            if self._gap_path is not None and not self.braking and not self.coasting:
                self._join_gap(q)
            hist = (self._c1, self._c2, self._c3) if self._c_run >= 3 else None  # (the path's jerk: when needed)
            self._c1, self._c2, self._c3 = tuple(q), self._c1, self._c2
            self._c_run += 1
        if self.coasting and q is not None and len(q) == 7:  # the controller's confirmations lag: ours is the coast
            q = self.coast.next()
            self.coast_cycles += 1
            self._coast_left -= 1
            end_coast = self._coast_left <= 0  # (this one is the coast's last: the next goes back onto the path)
            far = _far(q, raw)
            if far > REJOIN_MAX:
                self.loss_refused = True
                return None, (f"replies lost or late: coasting until the controller confirmed our commands left the "
                              f"motion {far:.4f} rad off the client's path (more than {REJOIN_MAX:g} rad)")  # fmt: skip
        elif not self.rejoin.done and q is not None and len(q) == 7:  # after a bridged command: the offset back
            off = self.rejoin.next()
            self.rejoin_cycles += 1
            far = max(abs(e) for e in off)
            if far > REJOIN_MAX:  # bridged so often that the motion cannot keep to the path within the limits
                self.loss_refused = True
                return None, (f"replies lost: the commands the controller bridged left the motion {far:.4f} rad off "
                              f"the client's path (more than {REJOIN_MAX:g} rad)")  # fmt: skip
            q = tuple(x + e for x, e in zip(q, off))
            if self.rejoin.done:  # its last sample: held to the jerk limit, with the two after it
                self._jerk_left = max(self._jerk_left, 3)
        forced = not jerk and (self._jerk_left > 0 or not self.rejoin.done or self.coasting)
        # (jerk: at least the client's own; a limit path + offset cannot keep would bend it against the offset's plan)
        floor = path_jerk(raw, *hist, self.period_s) if hist is not None and forced and not self.coasting else None
        adm = env.admit(q, self.prev, self.prev2, self.prev3, jerk or forced, floor)
        if adm.reason is not None and forced:  # (no command within the jerk limit is brakeable: the limits first)
            adm = env.admit(q, self.prev, self.prev2, self.prev3, False)
        if adm.reason is not None:
            return None, adm.reason
        if (
            exact and adm.clamped > CLAMP_TOL and not (self._bent or self._jerk_left) and self.rejoin.done
        ):  # the client's own command
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
            # a clamp of the offset (or one the jerk limit forced on the client): re-plan the offset from there
            self._replan = (raw is not q or forced) and adm.clamped > CLAMP_TOL
            if self._replan and raw is not q and not self.rejoin.done:  # (the offset's plan goes on, shifted by it)
                self._replan = tuple(a - b for a, b in zip(adm.q, q))
        if end_coast:  # (from the history this command ends: in :meth:`sent`)
            self.coasting = False
            self._replan = not self.replans and not self.braking
            self.replan_due = self.replans
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
        else:  # COMMANDING_WAIT: the robot stands at ``measured`` (the ipo position), the command must reach it
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
            e = self._ramp.next()
            tau, wrench = (e, None) if mode == _TORQUE else (None, e)
        return q, tau, wrench, None

    def sent(self, q: tuple[float, ...], state: int, prepared: bool = False) -> None:
        """``q`` [rad] went out: in COMMANDING_ACTIVE the controller executes it (``prepared``: the client's own)."""
        if state == _CMD_ACTIVE:
            if prepared:  # (the client's command history, as :meth:`admit` keeps it)
                self._c1, self._c2, self._c3 = q, self._c1, self._c2
                self._c_run += 1
            self.prev3, self.prev2, self.prev = self.prev2, self.prev, q
            self._s3, self._s2, self._s1 = self._s2, self._s1, q  # (what was sent, also where a rebase replaced it)
            self.active_sent += 1
            self.rebased = False
            self._d3, self._d2, self._d1, self._pend = self._d2, self._d1, self._pend, None
            r, self._replan = self._replan, False
            if r is not False and not self.coasting and self.replans:  # a clamp: the client re-plans from there
                self._forget_path()
                self.replan_due = True
            elif r is not False and not self.coasting:  # a new offset from the history, or the running one shifted
                self.rejoin.start(self._d1, self._d2 or _ZERO7, self._d3 or _ZERO7) if r is True or self.rejoin.done else self.rejoin.shift(r)  # type: ignore[arg-type]  # fmt: skip
            self._bent, self._jerk_left = max(0, self._bent - 1), max(0, self._jerk_left - 1)
            if self._alt is not None:
                a = self._alt
                self._alt_left -= 1
                self._alt = (q, a[0], a[1]) if self._alt_left > 0 else None
        else:
            self.prev = self.prev2 = self.prev3 = self._s1 = self._s2 = self._s3 = q
