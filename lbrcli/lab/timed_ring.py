"""Time-stamped samples in a ring, read back at any time by linear interpolation: the robot's poses for the camera's
pivot, the simulated ball for the simulated camera. One writer; readers see a row only once it is complete (the row
is written before the count), in this process or — over a shared buffer — in others."""

from __future__ import annotations

from typing import Sequence

import numpy as np


class TimedRing:
    """``rows`` samples of (t [s], ``width`` values) in ``buffer`` (anything numpy can view: a bytearray, an mmap
    shared with other processes; None: private memory) laid out as an int64 count and then the float64 rows."""

    LOOKBACK = 1024  # rows searched per look-up: a reader looks back a second or so

    def __init__(self, rows: int, width: int, buffer=None) -> None:
        self.rows, self.width = rows, width
        self.buffer = bytearray(self.nbytes(rows, width)) if buffer is None else buffer
        self._count = np.frombuffer(self.buffer, dtype=np.int64, count=1)
        self._data = np.frombuffer(self.buffer, dtype=np.float64, offset=8, count=rows * (1 + width)).reshape(
            rows, 1 + width
        )

    @staticmethod
    def nbytes(rows: int, width: int) -> int:
        return 8 * (1 + rows * (1 + width))

    def push(self, t: float, values: Sequence[float]) -> None:
        n = int(self._count[0])
        row = self._data[n % self.rows]
        row[0] = t
        row[1:] = values
        self._count[0] = n + 1

    def __len__(self) -> int:
        return int(self._count[0])

    def time_of(self, index: int) -> float:
        """Time [s] of the sample written index-th (from 0; it must still be in the ring)."""
        return float(self._data[index % self.rows, 0])

    @property
    def newest_t(self) -> float:
        """Time of the newest sample [s] (−inf when empty)."""
        n = int(self._count[0])
        return float(self._data[(n - 1) % self.rows, 0]) if n else -np.inf

    def at(self, t: float) -> np.ndarray | None:
        """The values at time t [s], linear between samples (the oldest kept before them, the newest after); None
        when empty."""
        n = int(self._count[0])
        if n == 0:
            return None
        idx = np.arange(max(0, n - min(self.rows - 1, self.LOOKBACK)), n) % self.rows
        times = self._data[idx, 0]
        j = int(np.searchsorted(times, t))
        if j <= 0:
            return self._data[idx[0], 1:].copy()
        if j >= len(idx):
            return self._data[idx[-1], 1:].copy()
        a, b = self._data[idx[j - 1]], self._data[idx[j]]
        w = (t - a[0]) / (b[0] - a[0]) if b[0] > a[0] else 1.0
        return a[1:] + w * (b[1:] - a[1:])
