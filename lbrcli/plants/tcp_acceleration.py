"""The TCP's acceleration as a position-controlled robot realises it, one cycle at a time (what plants are driven by).

The value returned at cycle k is the second difference (p[k] − 2·p[k−1] + p[k−2])/h², the acceleration at the
previous sample (as ``planners.pendulum.SampledAcceleration`` for a whole path); the TCP rests before the start.
"""

from __future__ import annotations

from typing import Sequence


class TcpAcceleration:
    """Second differences of the TCP positions [m] pushed every ``period_s`` [s], starting at rest at ``tcp0``."""

    def __init__(self, period_s: float, tcp0: Sequence[float]) -> None:
        self._ih2 = 1.0 / (period_s * period_s)
        self._p0 = self._p1 = list(tcp0)  # TCP positions at the last two cycles [m]

    def push(self, tcp: Sequence[float]) -> tuple[float, float, float]:
        """The TCP at this cycle [m] → its acceleration at the previous sample [m/s²]."""
        p0, p1, p2, ih2 = tcp, self._p0, self._p1, self._ih2
        acc = (
            (p0[0] - 2.0 * p1[0] + p2[0]) * ih2,
            (p0[1] - 2.0 * p1[1] + p2[1]) * ih2,
            (p0[2] - 2.0 * p1[2] + p2[2]) * ih2,
        )
        self._p0, self._p1 = list(p0), p1
        return acc

    @property
    def previous(self) -> tuple[float, float, float]:
        """The TCP at the sample the last acceleration belongs to (one cycle before the last pushed) [m]."""
        p = self._p1
        return (p[0], p[1], p[2])
