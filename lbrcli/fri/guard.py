"""Per-cycle command guard: the last check of every command that leaves the client.

Joint position: 7 finite values inside the position limits, the step from the previous command within the velocity
limit and the second difference within the acceleration limit (both × period, as the controller executes them) and —
for every command but the braking stop's own — the state it creates inside the braking envelope
(:mod:`trajectories.envelope`: a jerk-limited stop from there stays inside every limit). The motion-safety core
(:class:`~lbrcli.fri.motion.ExecutedMotion`) admits or clamps commands into that envelope first, so a refusal here
is a bug signal, not a control strategy.
Torque (TORQUE mode): 7 finite values within the torque table. Wrench (WRENCH mode): 6 finite values within the
configured force [N] and torque [Nm] bounds. Limits are compared with a stated relative tolerance (REL_TOL), so a
command exactly at a limit passes. Pure Python over 7 floats: cheaper per cycle than numpy on tiny arrays.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from functools import cached_property
from typing import Sequence

from trajectories.envelope import REL_TOL, BrakingEnvelope

try:  # the quick acceptance, compiled (setup.py; without it the loop below alone decides)
    from trajectories import _quick
except ImportError:  # pragma: no cover - a build without a C compiler
    _quick = None
from trajectories.limits import JointLimits

DEFAULT_MAX_FORCE = 20.0  # [N] per axis, WRENCH mode
DEFAULT_MAX_MOMENT = 2.0  # [Nm] per axis, WRENCH mode


@dataclass(frozen=True)
class CommandGuard:
    """Bounds for one command period ``period_s`` [s] (send period × receive multiplier)."""

    upper: tuple[float, ...]  # [rad] |q| ≤ upper
    max_step: tuple[float, ...]  # [rad] velocity limit × period
    max_second: tuple[float, ...]  # [rad] acceleration limit × period²
    envelope: BrakingEnvelope
    max_torque: tuple[float, ...]  # [Nm]
    max_force: float  # [N] per axis
    max_moment: float  # [Nm] per axis
    period_s: float

    @classmethod
    def from_limits(
        cls,
        limits: JointLimits,
        period_s: float,
        max_force: float = DEFAULT_MAX_FORCE,
        max_moment: float = DEFAULT_MAX_MOMENT,
    ) -> "CommandGuard":
        k = 1.0 + REL_TOL
        return cls(
            upper=tuple(float(p) * k for p in limits.position),
            max_step=tuple(float(v) * period_s * k for v in limits.velocity),
            max_second=tuple(float(a) * period_s * period_s * k for a in limits.acceleration),
            envelope=BrakingEnvelope.from_limits(limits, period_s),
            max_torque=tuple(float(t) * k for t in limits.torque),
            max_force=max_force,
            max_moment=max_moment,
            period_s=period_s,
        )

    @property
    def free(self) -> tuple[float, ...]:
        """[rad] |q| ≤ free: a state inside the velocity/acceleration bounds never needs the position check."""
        return self.envelope.free

    def refuse_position(
        self, q: Sequence[float], prev: Sequence[float], prev2: Sequence[float], room_to_stop: bool = True
    ) -> str | None:
        """None if ``q`` [rad] may follow the commands ``prev`` and ``prev2`` (one and two periods before);
        ``room_to_stop``: the state it creates must also be brakeable (the braking envelope)."""
        if q is None or len(q) != 7:
            return f"the joint position command has {0 if q is None else len(q)} values, not 7"
        env = self.envelope
        if not room_to_stop and _quick is not None and _quick.steps(q, prev, prev2, self._packed):
            return None  # (compiled: the chained comparisons below, every joint passing them)
        # most commands are far from every limit: one chained comparison per joint, the full check only near one
        j = 0
        for x, p1, p2, free, max_step, max_second in zip(q, prev, prev2, env.free, self.max_step, self.max_second):
            step = x - p1
            second = step - (p1 - p2)
            if not (-free <= x <= free and -max_step <= step <= max_step and -max_second <= second <= max_second):
                problem = self._joint_problem(j, x, step, second, room_to_stop)  # also NaN
                if problem is not None:
                    return problem
            elif room_to_stop and not env.joint_ok(
                j, x, step / self.period_s, second / (self.period_s * self.period_s)
            ):
                return self._envelope_problem(j, x, step, second)
            j += 1
        return None

    @cached_property
    def _packed(self) -> bytes:
        """Per joint (free, max_step, max_second) as 21 float64, for the compiled quick acceptance."""
        env = self.envelope
        return struct.pack("21d", *(x for j in range(7) for x in (env.free[j], self.max_step[j], self.max_second[j])))

    def _joint_problem(self, j: int, x: float, step: float, second: float, room_to_stop: bool) -> str | None:
        """The full check of joint ``j`` (index) at ``x`` [rad] after ``step`` [rad] and ``second`` difference [rad]."""
        dt = self.period_s
        if not (-self.upper[j] <= x <= self.upper[j]):  # also NaN
            return f"A{j + 1} command {x:.6f} rad outside the position limit ±{self.upper[j]:.6f} rad"
        if not (-self.max_step[j] <= step <= self.max_step[j]):
            return (f"A{j + 1} step {step:+.6f} rad in {dt * 1e3:g} ms = {step / dt:+.4f} rad/s exceeds the "
                    f"velocity limit {self.max_step[j] / dt:.4f} rad/s")  # fmt: skip
        if not (-self.max_second[j] <= second <= self.max_second[j]):
            return (f"A{j + 1} second difference {second:+.3e} rad = {second / (dt * dt):+.2f} rad/s² exceeds the "
                    f"acceleration limit {self.max_second[j] / (dt * dt):.2f} rad/s²")  # fmt: skip
        if room_to_stop and not self.envelope.joint_ok(j, x, step / dt, second / (dt * dt)):
            return self._envelope_problem(j, x, step, second)
        return None

    def _envelope_problem(self, j: int, x: float, step: float, second: float) -> str:
        return self.envelope.explain(j, x, step / self.period_s, second / (self.period_s * self.period_s))

    def refuse_torque(self, tau: Sequence[float] | None) -> str | None:
        if tau is None or len(tau) != 7:
            return f"the torque command has {0 if tau is None else len(tau)} values, not 7"
        for j in range(7):
            x = tau[j]
            if not (-self.max_torque[j] <= x <= self.max_torque[j]):
                return f"A{j + 1} torque command {x:.4f} Nm outside the torque limit ±{self.max_torque[j]:.1f} Nm"
        return None

    def refuse_wrench(self, w: Sequence[float] | None) -> str | None:
        if w is None or len(w) != 6:
            return f"the wrench command has {0 if w is None else len(w)} values, not 6"
        for i in range(6):
            bound = self.max_force if i < 3 else self.max_moment
            x = w[i]
            if not (-bound <= x <= bound) or math.isnan(x):
                unit = "N" if i < 3 else "Nm"
                return f"wrench component {'xyzxyz'[i]}{'' if i < 3 else ' moment'} {x:.4f} {unit} outside ±{bound:g} {unit}"
        return None
