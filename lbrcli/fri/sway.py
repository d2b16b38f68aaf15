"""The sway of a ball or pendulum hanging from the flange, watched before a trajectory starts.

A *sway source* is a callable ``(state) -> float | None``: the current tilt [rad] (any sign), or None while there
is no reading. :class:`IoSway` reads an analog input of the monitoring message (the simulator's ``ball_theta``);
the CLI passes the pendulum module's newest reading. :class:`SwayWatch` keeps the largest |tilt| over the last
window (at least half a swing period: |θ| of a swing peaks twice a period) and says when it has stayed below a
threshold for a whole window. Allocation-free per message.
"""

from __future__ import annotations

import math
from typing import Callable

from .state import LBRState

SwaySource = Callable[[LBRState], "float | None"]


class IoSway:
    """The analog input ``name`` of each monitoring message [rad]; None if the message has no such input."""

    def __init__(self, name: str = "ball_theta") -> None:
        self.name = name
        self._present: bool | None = None

    def __call__(self, state: LBRState) -> float | None:
        ios = state.message.monitorData.readIORequest
        if self._present is None:
            self._present = any(io.name == self.name for io in ios)
        if not self._present:
            return None
        for io in ios:
            if io.name == self.name:
                return io.analogValue
        return None


def window_for_length(length: float | None) -> float:
    """Observation window [s]: 0.6 of the swing period of a string of ``length`` [m] (half a period and a margin
    for a longer string than stated); 1.2 s when the length is unknown (strings up to ≈ 1.4 m)."""
    if not length:
        return 1.2
    return 0.6 * 2.0 * math.pi * math.sqrt(length / 9.80665)


class SwayWatch:
    """Largest |tilt| [rad] from ``source`` over the last ``window_s`` [s], and whether it stayed below
    ``threshold`` [rad] for a whole window (``calm``); the trajectory waits at most ``max_wait_s`` [s] for that."""

    def __init__(self, source: SwaySource | None, threshold: float, window_s: float, max_wait_s: float) -> None:
        if not (math.isfinite(threshold) and threshold > 0):
            raise ValueError(f"sway threshold must be > 0 rad, got {threshold!r}")
        if not (math.isfinite(window_s) and window_s > 0):
            raise ValueError(f"sway window must be > 0 s, got {window_s!r}")
        if not (math.isfinite(max_wait_s) and max_wait_s >= 0):
            raise ValueError(f"sway wait must be >= 0 s, got {max_wait_s!r}")
        self.source = source
        self.threshold = threshold
        self.window_s = window_s
        self.max_wait_s = max_wait_s
        self._n = 0  # messages per window (from the send period at the first reading)
        self._ring: list[float] = []  # |tilt| of the last ``_n`` readings [rad]
        self._at = 0
        self._quiet = 0  # readings in a row below the threshold
        self.readings = 0

    def update(self, state: LBRState) -> None:
        """Read the source for this message (call once per monitoring message)."""
        if self.source is None:
            return
        x = self.source(state)
        if x is None or x != x:  # no reading (or NaN): neither calm nor a figure
            self._quiet = 0
            return
        if self._n == 0:
            self._n = max(1, math.ceil(self.window_s / max(state.sample_time, 1e-4) - 1e-9))
            self._ring = [-math.inf] * self._n
        a = abs(x)
        self._ring[self._at] = a
        self._at = (self._at + 1) % self._n
        self.readings += 1
        self._quiet = self._quiet + 1 if a < self.threshold else 0

    def restart(self) -> None:
        """Forget the readings so far (the robot has just come to rest: what follows is the free swing)."""
        if self._n:
            self._ring = [-math.inf] * self._n
        self._quiet = 0

    @property
    def amplitude(self) -> float | None:
        """Largest |tilt| [rad] over the last window (None before a reading since the start or a restart)."""
        m = max(self._ring, default=-math.inf)
        return None if m == -math.inf else m

    @property
    def calm(self) -> bool:
        """|tilt| has stayed below the threshold for a whole window."""
        return self._n > 0 and self._quiet >= self._n
