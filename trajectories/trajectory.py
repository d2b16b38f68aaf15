"""Trajectory value types: joint and task-space samples on a uniform time grid."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

N_JOINTS = 7


@dataclass(frozen=True)
class JointTrajectory:
    """Joint positions sampled at a uniform step.

    t: (n,) time from 0 [s]; q: (n, 7) joint positions [rad].
    """

    t: np.ndarray
    q: np.ndarray

    def __post_init__(self) -> None:
        if self.q.ndim != 2 or self.q.shape[1] != N_JOINTS or self.q.shape[0] != self.t.shape[0]:
            raise ValueError(f"expected t (n,) and q (n, 7), got {self.t.shape} and {self.q.shape}")

    @classmethod
    def from_samples(cls, q: np.ndarray, dt: float) -> "JointTrajectory":
        """Trajectory from (n, 7) samples [rad] one step dt [s] apart, starting at t = 0."""
        q = np.asarray(q, dtype=float)
        return cls(t=np.arange(q.shape[0]) * dt, q=q)

    @property
    def dt(self) -> float:
        """Sample step [s] (0 for a single sample)."""
        if len(self.t) < 2:
            return 0.0
        return float((self.t[-1] - self.t[0]) / (len(self.t) - 1))

    @property
    def duration(self) -> float:
        """Time of the last sample [s]."""
        return float(self.t[-1]) if len(self.t) else 0.0

    def __len__(self) -> int:
        return int(self.t.shape[0])


@dataclass(frozen=True)
class TaskTrajectory:
    """Flange (or tool) poses in the base frame.

    t: (n,) [s]; position: (n, 3) [m]; quaternion: (n, 4) unit quaternion (w, x, y, z).
    """

    t: np.ndarray
    position: np.ndarray
    quaternion: np.ndarray

    def __post_init__(self) -> None:
        n = self.t.shape[0]
        if self.position.shape != (n, 3) or self.quaternion.shape != (n, 4):
            raise ValueError("expected t (n,), position (n, 3), quaternion (n, 4)")

    @property
    def dt(self) -> float:
        if len(self.t) < 2:
            return 0.0
        return float((self.t[-1] - self.t[0]) / (len(self.t) - 1))

    def __len__(self) -> int:
        return int(self.t.shape[0])
