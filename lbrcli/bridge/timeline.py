"""Targets placed on a time line and read back a fixed delay behind: a smooth reference from a jittery source.

A source samples its motion at its own times (the target's ``t`` [s], e.g. MATLAB's ``toc``) and the network
delivers the samples late and in bursts. Chasing each newest sample as it lands makes the arm jerk ahead and
overshoot; the bridge instead reads the samples back on their own clock, ``delay_s`` behind the newest, and
interpolates between them (quintic Hermite through positions, velocities — the feed-forward or differences — and
accelerations: a twice differentiable reference) — the way a trajectory controller plays
a buffered stream. Knots closer than ``MIN_KNOT_S`` merge (differences over sub-millisecond, jittery spacing would
give a reference with jerks a hundred times the motion's own). The source's clock is mapped onto ours by the
smallest ``arrival − t`` over the last second (the least delayed message); when its ``t`` goes back or stands (a
restarted ``tic``, or a source without a clock) the target is placed where it arrived and later ones count from
there. The automatic delay follows the 95th percentile of lateness plus two gaps of the recent targets (the segment
being read has its final shape only once the target after it arrived: a 1 kHz source ≈ 8 ms, a 30 Hz one ≈ 70 ms),
and changes by at most ``DELAY_RATE`` once the reference moves, so the reference never jumps. When the source falls
silent the reference carries the last segment on for at most ``coast_s`` and then holds.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Sequence

import numpy as np

OFFSET_WINDOW_S = 1.0  # [s] the source-clock offset: the least delayed message of this window
DELAY_SAMPLES = 200  # targets whose gap + lateness set the automatic delay
DELAY_QUANTILE = 0.95
DELAY_RATE = 0.02  # [s] / [s] the automatic delay changes at most this fast (the clock's warp follows)
MIN_DELAY_S = 0.002  # [s]
MAX_KNOTS = 512
MIN_KNOT_S = 0.004  # [s] knots closer than this are merged (the newest moves): differences over sub-millisecond,
# jittery spacing make a reference with jerks 100x the motion's own


@dataclass(frozen=True)
class TimelineOptions:
    """``delay_s`` None: automatic within [``MIN_DELAY_S``, ``max_delay_s``]; ``coast_s``: how long the reference
    keeps the last velocity after the newest target before it holds [s]."""

    delay_s: float | None = None
    max_delay_s: float = 0.1
    coast_s: float = 0.02


class TargetTimeline:
    """Joint targets on the source's clock; :meth:`due` says where on that clock the reference should be at a
    ``time.monotonic()`` instant, :meth:`at` gives the reference position [rad], velocity [rad/s] and acceleration
    [rad/s²] there."""

    def __init__(self, options: TimelineOptions = TimelineOptions()) -> None:
        self.options = options
        self._t: deque[float] = deque(maxlen=MAX_KNOTS)  # [s] source time of each knot (arrival time: own clock)
        self._q: deque[np.ndarray] = deque(maxlen=MAX_KNOTS)
        self._v: deque[np.ndarray] = deque(maxlen=MAX_KNOTS)  # [rad/s] the feed-forward, else estimated
        self._given: deque[bool] = deque(maxlen=MAX_KNOTS)  # the velocity is the source's feed-forward
        self._a: deque[np.ndarray] = deque(maxlen=MAX_KNOTS)  # [rad/s²] estimated
        self._offsets: deque[tuple[float, float]] = deque()  # (arrival, arrival − t), increasing offsets: a min queue
        self._spread: deque[float] = deque(maxlen=DELAY_SAMPLES)  # [s] gap + lateness of each target
        self._covered = 0  # targets measured
        self._coef: dict[float, np.ndarray] = {}  # final segments' coefficients by their first knot's time
        self._epoch = 0.0  # [s] added to the source's t (its clock restarted: moved on to where it arrived)
        self._restarts = 0  # targets whose t did not grow
        self._added = 0  # targets
        self.delay = options.delay_s if options.delay_s is not None else options.max_delay_s  # [s] until measured
        self._delay_goal = self.delay
        self._last_now = 0.0
        self._started = False  # the reference has passed the first target: the delay changes slowly from now on
        self.largest_delay = 0.0  # [s] since the reference started

    @property
    def empty(self) -> bool:
        return not self._t

    def add(self, q: Sequence[float], v: Sequence[float] | None, t: float, arrival: float) -> None:
        """A target ``q`` [rad] (feed-forward ``v`` [rad/s] or None) stamped ``t`` [s] by its source, arrived at
        ``arrival`` [s] (``time.monotonic()``)."""
        self._added += 1
        stamp = t + self._epoch
        if self._t and not stamp > self._t[-1]:
            # the source's clock went back or stands (restarted, or a source without one): from here its times count
            # from where this target lands on the knots' clock by its arrival
            self._epoch = arrival - self.offset - t
            stamp = t + self._epoch
            self._restarts += 1
        if self._t and not stamp > self._t[-1]:  # (two in one instant) the newer one counts
            self.replace_last(q, v)
            return
        off = arrival - stamp
        thin = len(self._t) >= 2 and stamp - self._t[-2] < MIN_KNOT_S
        if self._t and not thin:
            gap = stamp - self._t[-1]
            # what the delay must cover for this target: its gap and lateness, and the gap before it (the knot before
            # this one has its final velocity and acceleration only now)
            cover = gap + max(0.0, off - self.offset)
            if len(self._t) >= 2:
                cover += self._t[-1] - self._t[-2]
            self._spread.append(cover)
            self._covered += 1
            n = len(self._spread)
            if self.options.delay_s is None and (n < 20 or self._covered % 20 == 0):  # (a quantile every 20)
                goal = float(np.quantile(self._spread, DELAY_QUANTILE)) if n >= 5 else 2 * max(self._spread)
                self._delay_goal = min(self.options.max_delay_s, max(MIN_DELAY_S, goal))
        offs = self._offsets
        while offs and offs[-1][1] >= off:
            offs.pop()
        offs.append((arrival, off))
        while offs[0][0] < arrival - OFFSET_WINDOW_S:
            offs.popleft()
        if thin:  # a dense source: the newest knot moves to this target (knots ≥ MIN_KNOT_S apart)
            for d in (self._t, self._q, self._v, self._a, self._given):
                d.pop()
        self._t.append(stamp)
        self._q.append(np.array(q, dtype=float))
        self._v.append(np.zeros(len(q)))
        self._a.append(np.zeros(len(q)))
        self._given.append(False)
        self._set_velocity(v)

    def replace_last(self, q: Sequence[float], v: Sequence[float] | None) -> None:
        """The newest target refined (a pose's IK solution converging)."""
        self._q[-1] = np.array(q, dtype=float)
        self._set_velocity(v)

    def _set_velocity(self, v: Sequence[float] | None) -> None:
        """The newest knot's velocity and acceleration (the feed-forward or a backward difference; the acceleration
        of the one before), and those of the knot before it, final now that it has a successor: its velocity the
        feed-forward or the three-point difference, its acceleration the central difference of the velocities
        (feed-forward) or the second divided difference of the positions."""
        n = len(self._t)
        ts, qs, vs, acc = self._t, self._q, self._v, self._a
        if v is not None:
            vs[-1] = np.array(v, dtype=float)
            self._given[-1] = True
        elif n >= 2:
            vs[-1] = (qs[-1] - qs[-2]) / (ts[-1] - ts[-2])
        if n >= 2:
            acc[-1] = (vs[-1] - vs[-2]) / (ts[-1] - ts[-2]) if self._given[-1] and self._given[-2] else acc[-2]
        if n >= 3:
            h0, h1 = ts[-2] - ts[-3], ts[-1] - ts[-2]
            d0, d1 = (qs[-2] - qs[-3]) / h0, (qs[-1] - qs[-2]) / h1
            if not self._given[-2]:
                vs[-2] = (d0 * h1 + d1 * h0) / (h0 + h1)
            if self._given[-1] and self._given[-3]:
                acc[-2] = (vs[-1] - vs[-3]) / (h0 + h1)
            else:
                acc[-2] = 2.0 * (d1 - d0) / (h0 + h1)

    @property
    def offset(self) -> float:
        """[s] our clock minus the source's (the least delayed target of the last second)."""
        return self._offsets[0][1] if self._offsets else 0.0

    @property
    def source_clock(self) -> bool:
        """The targets are placed on their source's clock (False: by arrival, the source's ``t`` does not grow)."""
        return self._restarts * 2 < max(1, self._added)

    def due(self, now: float) -> float:
        """The time on the knots' clock [s] the reference should show at ``now`` [s] (``time.monotonic()``): the
        delay behind, mapped through the offset (the automatic delay moves toward its goal here)."""
        if self.options.delay_s is None:
            if self._started:
                step = DELAY_RATE * max(0.0, now - self._last_now)
                self.delay += max(-step, min(step, self._delay_goal - self.delay))
            else:  # the reference has not moved yet: the delay may take any value
                self.delay = self._delay_goal
            if self._started:  # (before the reference moves the delay is a guess)
                self.largest_delay = max(self.largest_delay, self.delay)
        self._last_now = now
        tau = now - self.delay - self.offset
        self._started = self._started or (bool(self._t) and tau > self._t[0])
        return tau

    @property
    def oldest(self) -> float:
        """[s] the oldest target kept, on the knots' clock (the first one until the reference reaches it)."""
        return self._t[0]

    @property
    def newest(self) -> float:
        """[s] the newest target's time on the knots' clock."""
        return self._t[-1]

    def forget(self, tau: float) -> None:
        """Let go of the knots before ``tau`` on the knots' clock (one at or before it stays)."""
        ts = self._t
        while len(ts) > 2 and ts[1] <= tau:
            self._coef.pop(ts[0], None)
            ts.popleft()
            self._q.popleft()
            self._v.popleft()
            self._a.popleft()
            self._given.popleft()

    def at(self, tau: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The reference position [rad], velocity [rad/s] and acceleration [rad/s²] at ``tau`` on the knots' clock
        (at or after the last :meth:`forget`)."""
        ts = self._t
        n = len(ts)
        zero = np.zeros_like(self._q[0])
        if tau < ts[0]:  # before the first target (the session's start): hold it
            return self._q[0], zero, zero
        if n == 1:
            return self._q[0], zero, zero
        if tau >= ts[-1]:  # past the newest target: its velocity carried on for coast_s, then a hold there
            v = self._v[-1]
            c = tau - ts[-1]
            if c >= self.options.coast_s:
                return self._q[-1] + v * self.options.coast_s, zero, zero
            return self._q[-1] + v * c, v, zero
        k = 0
        while ts[k + 1] <= tau:  # (usually the first segment; a look ahead may reach further)
            k += 1
        return self._hermite(k, tau)

    def ahead(self, tau: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """As :meth:`at`, but past the newest target the motion carried on at its velocity without end: a guess of
        the reference's future for a plan that must meet it (not a reference to follow)."""
        ts = self._t
        if len(ts) < 2 or tau <= ts[-1]:
            return self.at(tau)
        v = self._v[-1]
        return self._q[-1] + v * (tau - ts[-1]), v, np.zeros_like(v)

    def _hermite(self, k: int, tau: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The quintic Hermite segment from knot ``k`` to ``k + 1`` (positions, velocities and accelerations: the
        reference is twice continuously differentiable) at ``tau``."""
        ts = self._t
        t0 = ts[k]
        h = ts[k + 1] - t0
        final = k <= len(ts) - 4  # its knots have successors: they no longer change
        coef = self._coef.get(t0) if final else None
        if coef is None:
            coef = self._coefficients(k, h)
            if final:
                if len(self._coef) > MAX_KNOTS:  # (knots the deque let go of)
                    self._coef.clear()
                self._coef[t0] = coef
        s = (tau - t0) / h
        s2 = s * s
        s3 = s2 * s
        ih = 1.0 / h
        ih2 = ih * ih
        powers = np.array([[1.0, s, s2, s3, s2 * s2, s3 * s2],
                           [0.0, ih, 2.0 * s * ih, 3.0 * s2 * ih, 4.0 * s3 * ih, 5.0 * s2 * s2 * ih],
                           [0.0, 0.0, 2.0 * ih2, 6.0 * s * ih2, 12.0 * s2 * ih2, 20.0 * s3 * ih2]])  # fmt: skip
        out = powers @ coef
        return out[0], out[1], out[2]

    def _coefficients(self, k: int, h: float) -> np.ndarray:
        """(6, n): segment ``k``'s polynomial in s = (tau − t_k) / h, lowest power first."""
        q0, dq = self._q[k], self._q[k + 1] - self._q[k]
        m0, m1 = self._v[k] * h, self._v[k + 1] * h
        c0, c1 = self._a[k] * (h * h), self._a[k + 1] * (h * h)
        return np.array([q0, m0, 0.5 * c0,
                         10.0 * dq - 6.0 * m0 - 4.0 * m1 - 1.5 * c0 + 0.5 * c1,
                         -15.0 * dq + 8.0 * m0 + 7.0 * m1 + 1.5 * c0 - c1,
                         6.0 * dq - 3.0 * m0 - 3.0 * m1 - 0.5 * c0 + 0.5 * c1])  # fmt: skip
