"""Is the sway sensor telling the truth? Checks of each reading against the observer's prediction for its moment, and
the residual sway as a fit rather than a peak of noisy readings.

:class:`SensorHealth` watches one angle: a reading that is not a number; readings that jump farther from the
prediction than a swinging ball can (several in a row); a sensor that stands still while the model says the ball
swings (stuck, frozen, or reading a ball that is not there); readings that move against the model (a reversed sign);
an estimate that grows beyond any plausible sway (the feedback feeding on a wrong sensor). The first fault is kept
(``fault``); the controller then stops correcting and says why.

:func:`swing_amplitude` is the sway left: the amplitude of the pendulum-frequency sinusoid fitted (least squares, with
an offset) to the readings of a window — noise of a few tenths of a degree averages out over the window's samples.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class HealthOptions:
    jump: float = math.radians(5.0)  # [rad] a reading this far from the prediction is no ball's …
    jumps: int = 3  # … this many in a row: a fault
    still_s: float = 0.6  # [s] readings within ``still_range`` this long …
    still_range: float = math.radians(0.02)  # [rad]
    moving_range: float = math.radians(2.0)  # [rad] … while the prediction spans more …
    drive: float = 0.08  # [m/s] … or the pivot's speed changes more within the window: stuck
    window_s: float = 1.0  # [s] the correlation of readings and predictions over this window …
    against: float = -0.5  # … below this, with the prediction spanning ``moving_range``: reversed
    diverged: float = math.radians(25.0)  # [rad] an estimate beyond this: the feedback runs away


class _Extremes:
    """Largest and least value of a sliding window of (t, value) pairs: monotonic deques, O(1) per value on average
    (a reading costs the same whatever the window's length — a 1 ms loop cannot afford a pass over the window)."""

    __slots__ = ("_hi", "_lo")

    def __init__(self) -> None:
        self._hi: deque[tuple[float, float]] = deque()
        self._lo: deque[tuple[float, float]] = deque()

    def add(self, t: float, value: float, t0: float) -> float:
        """Take ``value`` at ``t`` [s], forget the values before ``t0`` [s]: the span (largest − least) left."""
        hi, lo = self._hi, self._lo
        while hi and not hi[-1][1] > value:
            hi.pop()
        hi.append((t, value))
        while lo and not lo[-1][1] < value:
            lo.pop()
        lo.append((t, value))
        while hi[0][0] < t0:
            hi.popleft()
        while lo[0][0] < t0:
            lo.popleft()
        return hi[0][1] - lo[0][1]


class SensorHealth:
    """Checks of one sensed angle; call :meth:`reading` with each reading and the prediction for its moment.

    Per reading the work is constant (it runs inside the 1 ms FRI cycle): the windows' extremes are kept by
    :class:`_Extremes`, the pivot's speed change as a running sum whose span over the window is the change's range;
    only the one-off sign judgement looks at a whole window."""

    def __init__(self, name: str, options: HealthOptions = HealthOptions()) -> None:
        self.name, self.o = name, options
        self.fault: str | None = None
        self._jumps = 0
        self._sign_judged = False
        self._recent: deque[tuple[float, float, float]] = deque()  # (t, reading, prediction) of the whole window
        self._pred = _Extremes()  # predictions over the whole window
        self._still = _Extremes()  # readings over the last still_s
        self._pushed = _Extremes()  # the pivot's speed change summed since the first reading [m/s], over still_s
        self._dv = 0.0
        self._t_last: float | None = None

    def reading(self, t: float, value: float, predicted: float, reference: float | None = None,
                drive: float = 0.0) -> str | None:  # fmt: skip
        """Judge a reading [rad] that arrived at ``t`` [s] against the observer's prediction [rad] for its moment
        (jumps) and the plan's open-loop sway ``reference`` [rad] for that moment (a still or reversed sensor: the
        observer follows whatever the sensor says, the plan's swing does not); the fault text the first time one is
        found, else None. ``drive`` [m/s²]: the pivot's acceleration along the axis now — a ball that does not move
        at all while the pivot's speed changes is not being seen."""
        if self.fault is not None:
            return None
        o = self.o
        if not math.isfinite(value):
            return self._set(f"{self.name} is not a number")
        if abs(value - predicted) > o.jump:
            self._jumps += 1
            if self._jumps >= o.jumps:
                return self._set(f"{self.name} jumped {math.degrees(value - predicted):+.1f}° from where the ball can be "
                                 f"({o.jumps} readings in a row)")  # fmt: skip
        else:
            self._jumps = 0
        pred = predicted if reference is None else reference
        # the pivot's velocity change (its acceleration integrated): a change of Δv swings a ball on any string by
        # about Δv/√(g·l) — several degrees for the threshold at lab lengths
        if self._t_last is not None:
            self._dv += drive * (t - self._t_last)
        self._t_last = t
        rec = self._recent
        rec.append((t, value, pred))
        t_window, t_still = t - max(o.still_s, o.window_s), t - o.still_s
        while rec[0][0] < t_window:
            rec.popleft()
        spread = self._pred.add(t, pred, t_window)
        still = self._still.add(t, value, t_still)
        pushed = self._pushed.add(t, self._dv, t_still)
        if t - rec[0][0] < 0.9 * min(o.still_s, o.window_s):
            return None
        if still <= o.still_range and (spread > o.moving_range or pushed > o.drive):
            return self._set(f"{self.name} stood still ({math.degrees(still):.3f}° over {o.still_s:g} s) while the move "
                             f"must have swung the ball (the model: {math.degrees(spread):.1f}°; the pivot's speed "
                             f"changed {pushed:.3f} m/s): stuck, frozen, or not seeing the ball")  # fmt: skip
        if not self._sign_judged and spread > o.moving_range:
            return self._judge_sign()
        return None

    def _judge_sign(self) -> str | None:
        """The sign, judged once over the first window the plan swings the ball in: later a string of another length
        drifts out of phase with the model (that is what the damper corrects), which says nothing of the sign."""
        vals = np.array([r[1] for r in self._recent])
        pred = np.array([r[2] for r in self._recent])
        if not (np.std(vals) > 0 and np.std(pred) > 0):
            return None
        self._sign_judged = True
        c = float(np.corrcoef(vals, pred)[0, 1])
        if c < self.o.against:
            return self._set(f"{self.name} swings against the move's swing (correlation {c:.2f}): its sign is reversed")
        return None

    def estimate(self, value: float) -> str | None:
        """Judge the controller's estimate [rad]: beyond any plausible sway is a fault."""
        if self.fault is None and not abs(value) <= self.o.diverged:
            return self._set(f"the estimated sway from {self.name} reached {math.degrees(value):.1f}°: the feedback "
                             "runs away on a sensor that does not match the ball")  # fmt: skip
        return None

    def _set(self, text: str) -> str:
        self.fault = text
        return text


def swing_amplitude(t: np.ndarray, values: np.ndarray, period: float) -> float:
    """Amplitude [rad] of the sinusoid of ``period`` [s] (with an offset) fitted by least squares to ``values`` [rad]
    at times ``t`` [s]; 0 for fewer than 4 samples."""
    t = np.asarray(t, dtype=float)
    v = np.asarray(values, dtype=float)
    keep = np.isfinite(v)
    t, v = t[keep], v[keep]
    if len(v) < 4:
        return 0.0
    w = 2 * math.pi / period
    A = np.column_stack([np.cos(w * t), np.sin(w * t), np.ones_like(t)])
    (a, b, _), *_ = np.linalg.lstsq(A, v, rcond=None)
    return float(math.hypot(a, b))
