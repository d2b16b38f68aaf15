"""How evenly a track was sampled: frame intervals, dropped frames, frames without a value.

A camera or a phone that drops frames leaves longer intervals between timestamps; a tracker that was unsure
leaves frames without θ. Both change what a comparison can say, so they are counted and reported. Pure
functions on arrays.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

DROP_FACTOR = 1.5  # an interval longer than this × the median interval has dropped frames in it
UNEVEN_JITTER = 0.1  # interval spread (MAD / median) above this share is reported as uneven timing
MISSING_SHARE = 0.05  # more than this share of frames without a value is reported


@dataclass(frozen=True)
class SampleReport:
    """Timing and completeness of a sampled series (a track's θ)."""

    frames: int
    median_interval_s: float  # [s]
    jitter: float  # median absolute deviation of the intervals / the median interval
    dropped_frames: int  # frames missing from the timing: Σ round(interval / median) − 1 over long intervals
    longest_gap_s: float  # longest interval between frames [s]
    missing: int  # frames present but without a value (NaN)
    longest_missing_s: float  # longest run of frames without a value [s]

    @property
    def uneven(self) -> bool:
        """Dropped frames or jittery timestamps."""
        return self.dropped_frames > 0 or self.jitter > UNEVEN_JITTER

    @property
    def incomplete(self) -> bool:
        return self.frames > 0 and self.missing > MISSING_SHARE * self.frames


def sample_report(t: np.ndarray, value: np.ndarray) -> SampleReport:
    """Report on times t (n,) [s] (increasing) and values (n,) (NaN where missing)."""
    t = np.asarray(t, float)
    value = np.asarray(value, float)
    n = len(t)
    if n < 2:
        return SampleReport(n, math.nan, math.nan, 0, math.nan, int(np.sum(~np.isfinite(value))), math.nan)
    dt = np.diff(t)
    med = float(np.median(dt))
    jitter = float(np.median(np.abs(dt - med)) / med) if med > 0 else math.nan
    long = dt > DROP_FACTOR * med
    dropped = int(np.sum(np.round(dt[long] / med) - 1)) if med > 0 else 0
    bad = ~np.isfinite(value)
    longest = 0.0
    if bad.any():  # runs of missing values: from the last good frame before to the first good frame after
        edges = np.diff(np.concatenate([[0], bad.astype(int), [0]]))
        starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
        for a, b in zip(starts, ends):
            longest = max(longest, float(t[min(b, n - 1)] - t[max(a - 1, 0)]))
    return SampleReport(
        frames=n,
        median_interval_s=med,
        jitter=jitter,
        dropped_frames=max(dropped, 0),
        longest_gap_s=float(dt.max()),
        missing=int(bad.sum()),
        longest_missing_s=longest,
    )
