"""Input shapers: impulse sequences that cancel the residual swing of a pendulum of known period.

A shaper is a list of impulses (amplitude A_i ≥ 0 summing to 1, time t_i [s]). Convolving a motion profile with
it leaves the peak velocity, acceleration and jerk of the profile unchanged or lower (facts/physics.md) and
adds t_n to its duration. Designs (Singer & Seering 1990, Singhose et al.) for an undamped pendulum (ζ = 0)
of period T [s]; ``residual_vibration`` is the linear residual V(r) for a frequency ratio r = ω_true/ω_design.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

SHAPER_NAMES = ("zv", "zvd", "zvdd", "mzv", "ei", "ei2")


@dataclass(frozen=True)
class Shaper:
    """Impulse sequence: amplitudes (m,) [-] summing to 1 and times (m,) [s] from 0."""

    name: str
    amplitudes: np.ndarray
    times: np.ndarray

    @property
    def duration(self) -> float:
        """Time added to a shaped move [s]."""
        return float(self.times[-1])

    def residual(self, omega: float | np.ndarray) -> np.ndarray:
        """Linear residual vibration V(ω) = |Σ A_i exp(iω t_i)| at angular frequencies ω [rad/s] (0..1)."""
        w = np.asarray(omega, dtype=float)[..., None]
        return np.abs(np.sum(self.amplitudes * np.exp(1j * w * self.times), axis=-1))


def _ei_amplitudes(v: float) -> np.ndarray:
    return np.array([(1 + v) / 4, (1 - v) / 2, (1 + v) / 4])


def _two_hump_ei(v: float) -> tuple[np.ndarray, np.ndarray]:
    """Two-hump EI (Singhose): 4 impulses over 1.5 T, with X = (V²(√(1−V²)+1))^(1/3)."""
    x = (v * v * (math.sqrt(1 - v * v) + 1)) ** (1 / 3)
    a1 = (3 * x * x + 2 * x + 3 * v * v) / (16 * x)
    a2 = 0.5 - a1
    return np.array([a1, a2, a2, a1]), np.array([0.0, 0.5, 1.0, 1.5])


def make_shaper(name: str, period: float, tolerance: float = 0.05) -> Shaper:
    """Shaper ``name`` (one of SHAPER_NAMES) for a pendulum of ``period`` [s].

    ``tolerance`` is the vibration level V the EI shapers accept at the design frequency (default 5 %).
    """
    T = float(period)
    if name == "zv":
        a, t = np.array([0.5, 0.5]), np.array([0.0, 0.5])
    elif name == "zvd":
        a, t = np.array([0.25, 0.5, 0.25]), np.array([0.0, 0.5, 1.0])
    elif name == "zvdd":
        a, t = np.array([1, 3, 3, 1]) / 8.0, np.array([0.0, 0.5, 1.0, 1.5])
    elif name == "mzv":
        r2 = math.sqrt(2.0)
        a, t = np.array([1 - 1 / r2, r2 - 1, 1 - 1 / r2]), np.array([0.0, 0.375, 0.75])
    elif name == "ei":
        a, t = _ei_amplitudes(tolerance), np.array([0.0, 0.5, 1.0])
    elif name == "ei2":
        a, t = _two_hump_ei(tolerance)
    else:
        raise ValueError(f"unknown shaper {name!r}; known: {', '.join(SHAPER_NAMES)}")
    a = a / a.sum()
    return Shaper(name=name, amplitudes=a, times=t * T)


def identity_shaper() -> Shaper:
    """The single unit impulse (no shaping)."""
    return Shaper(name="none", amplitudes=np.array([1.0]), times=np.array([0.0]))


def frequency_ratio_band(length_tolerance: float) -> tuple[float, float]:
    """Range of r = ω_true/ω_design for a string length known within ±tolerance (ω ∝ 1/√l)."""
    return 1.0 / math.sqrt(1.0 + length_tolerance), 1.0 / math.sqrt(max(1e-9, 1.0 - length_tolerance))


def box_residual(omega: float | np.ndarray, width: float) -> np.ndarray:
    """|sinc| residual of a normalised box (uniform distributed shaper) of ``width`` [s] at ω [rad/s]."""
    x = np.asarray(omega, dtype=float) * width / 2.0
    return np.abs(np.sinc(x / np.pi))
