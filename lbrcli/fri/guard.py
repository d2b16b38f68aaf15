"""Per-cycle command guard: every joint position sent to the robot is inside the position limits and reached
from the previous command no faster than the velocity limit.

Pure Python over 7 floats (cheaper per cycle than numpy on tiny arrays). A refusal returns a reason; the
session then holds the last safe command and ends the stream.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

from trajectories.limits import JointLimits


@dataclass(frozen=True)
class CommandGuard:
    """Bounds for one command period.

    lower/upper: position limits [rad]; max_step: velocity limit × period [rad per command].
    """

    lower: tuple[float, ...]
    upper: tuple[float, ...]
    max_step: tuple[float, ...]
    period_s: float  # [s] between two commands (send period × receive multiplier)

    @classmethod
    def from_limits(cls, limits: JointLimits, period_s: float) -> "CommandGuard":
        pos = [float(p) for p in limits.position]
        return cls(
            lower=tuple(-p for p in pos),
            upper=tuple(pos),
            max_step=tuple(float(v) * period_s for v in limits.velocity),
            period_s=period_s,
        )

    def refuse(self, previous: Sequence[float], command: Sequence[float]) -> str | None:
        """None if ``command`` [rad] is safe after ``previous`` [rad]; else the reason (joint, value, limit)."""
        for j in range(7):
            q = command[j]
            if not (self.lower[j] <= q <= self.upper[j]):  # also catches NaN
                return f"A{j + 1} command {q:.6f} rad outside the position limit ±{self.upper[j]:.6f} rad"
            step = q - previous[j]
            if step > self.max_step[j] or -step > self.max_step[j]:
                return (
                    f"A{j + 1} step {step:+.6f} rad in {self.period_s * 1e3:g} ms = {step / self.period_s:+.4f} rad/s "
                    f"exceeds the velocity limit {self.max_step[j] / self.period_s:.4f} rad/s"
                )
        return None
