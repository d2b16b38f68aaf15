"""Rest-to-rest motion with a piecewise-linear acceleration on a uniform grid (the robust designs' profile).

Acceleration nodes a_0 … a_N [m/s²] at t_k = k·δ (a_0 = a_N = 0), linear in between: the jerk is piecewise
constant, velocity piecewise quadratic, position piecewise cubic, all closed form. Its Fourier transform is
exact: ∫ a(t)·e^{iωt} dt = δ·sinc²(ωδ/2)·Σ a_k e^{iωt_k} (a sum of hat functions).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .profiles import ProfileDerivatives


@dataclass(frozen=True)
class RampProfile(ProfileDerivatives):
    """distance [m] moved with the acceleration nodes ``accel`` (N+1,) [m/s²] every ``step`` δ [s]."""

    distance: float
    step: float
    accel: np.ndarray

    @property
    def duration(self) -> float:
        """Time from start to rest [s]."""
        return float(self.step * (len(self.accel) - 1))

    def _nodes(self) -> tuple[np.ndarray, np.ndarray]:
        """Velocity [m/s] and position [m] at the nodes."""
        a, d = self.accel, self.step
        v = np.concatenate([[0.0], np.cumsum(0.5 * d * (a[1:] + a[:-1]))])
        dp = d * v[:-1] + d * d * (a[:-1] / 3.0 + a[1:] / 6.0)
        return v, np.concatenate([[0.0], np.cumsum(dp)])

    def derivative(self, t: np.ndarray, order: int) -> np.ndarray:
        """d^order/dt^order of the position at times t [s] (order 0..3; m/s^order); at rest outside."""
        t = np.asarray(t, dtype=float)
        a, d = self.accel, self.step
        n = len(a) - 1
        k = np.clip(np.floor(t / d).astype(int), 0, n - 1)
        tau = np.clip(t, 0.0, self.duration) - k * d
        a0, jerk = a[k], (a[k + 1] - a[k]) / d
        v, p = self._nodes()
        if order == 0:
            out = p[k] + v[k] * tau + a0 * tau**2 / 2 + jerk * tau**3 / 6
            return np.where(t >= self.duration, self.distance, np.where(t <= 0, 0.0, out))
        if order == 1:
            out = v[k] + a0 * tau + jerk * tau**2 / 2
        elif order == 2:
            out = a0 + jerk * tau
        elif order == 3:
            out = jerk
        else:
            raise ValueError(f"order {order} not in 0..3")
        return np.where((t >= self.duration) | (t < 0), 0.0, out)

    def peaks(self) -> tuple[float, float, float]:
        """Peak |velocity| [m/s], |acceleration| [m/s²], |jerk| [m/s³]."""
        v, _ = self._nodes()
        a, d = self.accel, self.step
        # velocity extrema inside an interval where the acceleration crosses zero
        cross = np.nonzero(a[:-1] * a[1:] < 0)[0]
        tz = (cross + a[cross] / (a[cross] - a[cross + 1])) * d
        vmax = float(max(np.abs(v).max(), np.abs(self.velocity(tz)).max() if len(tz) else 0.0))
        return vmax, float(np.abs(a).max()), float(np.abs(np.diff(a)).max() / d)

    def spectrum(self, omega: np.ndarray) -> np.ndarray:
        """∫ a(t)·e^{iωt} dt [m/s] at angular frequencies ω [rad/s]."""
        w = np.asarray(omega, dtype=float)
        tk = np.arange(len(self.accel)) * self.step
        hat = self.step * np.sinc(w * self.step / (2 * np.pi)) ** 2
        return hat * (np.exp(1j * np.multiply.outer(w, tk)) @ self.accel)


__all__ = ["RampProfile"]
