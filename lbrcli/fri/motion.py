"""What the controller executes from our joint position commands, and what may follow it.

:class:`ExecutedMotion` keeps the last three joint positions sent in COMMANDING_ACTIVE — continued, over lost
monitoring messages, as the controller's extrapolation continued them — and judges each next command against them
with the guard; a client-side stop brakes from them (``BrakingStop``). Built when the command period is known.
"""

from __future__ import annotations

from typing import Any, Sequence

from trajectories.limits import JointLimits

from .braking import BrakingStop
from .constants import ClientCommandMode
from .guard import CommandGuard

_TORQUE = int(ClientCommandMode.TORQUE)
_WRENCH = int(ClientCommandMode.WRENCH)
_ZERO6 = (0.0,) * 6
_ZERO7 = (0.0,) * 7
_CMD_ACTIVE = 4


class Refused(Exception):
    """A command failed the guard and nothing is moving under our command: end without sending it."""


class ExecutedMotion:
    """The sent history [rad], the guard on the next command, the braking stop (``hold_cycles`` at rest after it)."""

    def __init__(self, limits: JointLimits, period_s: float, max_force: float, max_moment: float, hold_cycles: int,
                 q: Sequence[float]) -> None:  # fmt: skip
        self.guard = CommandGuard.from_limits(limits, period_s, max_force, max_moment)
        self.brake = BrakingStop(limits, period_s)  # ready before it is needed
        self.hold_cycles = hold_cycles
        self.prev = self.prev2 = self.prev3 = tuple(q)  # what the controller executed, newest first
        self.active_sent = 0  # joint positions sent in COMMANDING_ACTIVE
        self.braking = False
        self.hold_left = 0
        self.braking_cycles = 0
        self.extrapolated_cycles = 0

    @property
    def moving(self) -> bool:
        """Commands were sent in COMMANDING_ACTIVE: a stop must brake."""
        return self.active_sent > 0

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
        if self.braking and n:  # the stop's profile no longer starts where the robot is: re-plan it from there
            self.brake.start(self.prev, self.prev2, self.prev3)
        return n

    def begin_braking(self) -> None:
        if not self.braking:
            self.brake.start(self.prev, self.prev2, self.prev3)
            self.braking = True
            self.hold_left = self.hold_cycles

    def held_long_enough(self) -> bool:
        """Count one cycle at rest after the braking stop; True when the hold is over."""
        if not (self.braking and self.brake.done):
            return False
        self.hold_left -= 1
        return self.hold_left <= 0

    def next_command(self, measured: Sequence[float], state: int, mode: int, q: Sequence[float],
                     tau: Sequence[float] | None, wrench: Sequence[float] | None) -> tuple[Any, Any, Any, str | None]:  # fmt: skip
        """The command to send (q [rad], tau [Nm] or None, wrench or None) and, if the client's was refused, why
        (the braking stop then replaces it). While braking the client's is ignored. :class:`Refused` when the
        command fails and nothing moves under our command (or the stop itself failed)."""
        guard = self.guard
        if state == _CMD_ACTIVE:
            prev, prev2 = self.prev, self.prev2
        else:  # COMMANDING_WAIT: the robot stands where it is measured, the command must be reachable from there
            prev = prev2 = tuple(measured)
        braking = self.braking
        if braking:
            q = self.brake.next()
            self.braking_cycles += 1
            tau = wrench = None
        reason = guard.refuse_position(q, prev, prev2, not braking)
        if reason is None and mode == _TORQUE:
            tau = tau if tau is not None else _ZERO7
            reason = guard.refuse_torque(tau)
        elif reason is None and mode == _WRENCH:
            wrench = wrench if wrench is not None else _ZERO6
            reason = guard.refuse_wrench(wrench)
        if reason is None:
            return q, tau, wrench, None
        text = f"guard refused the command: {reason}"
        if braking or state != _CMD_ACTIVE or not self.moving:
            raise Refused(text)
        self.begin_braking()
        q = self.brake.next()
        self.braking_cycles += 1
        if guard.refuse_position(q, prev, prev2, False) is not None:
            q = prev  # cannot happen within the limits; a hold is the last resort
        return q, (_ZERO7 if mode == _TORQUE else None), (_ZERO6 if mode == _WRENCH else None), text

    def sent(self, q: tuple[float, ...], state: int) -> None:
        """``q`` [rad] went out: in COMMANDING_ACTIVE the controller executes it."""
        if state == _CMD_ACTIVE:
            self.prev3, self.prev2, self.prev = self.prev2, self.prev, q
            self.active_sent += 1
        else:
            self.prev = self.prev2 = self.prev3 = q
