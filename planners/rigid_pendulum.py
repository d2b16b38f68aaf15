"""The thesis's pendulum module (ch. 6) as a rigid pendulum: a rod on a bearing whose axis is horizontal, driven by
the pivot's acceleration in the plane of the swing.

φ is the rod's angle from hanging straight down [rad], positive toward the plane's horizontal axis e (φ = π:
upright). With the pivot acceleration a_h along e and a_v upward [m/s²], the rod (mass m, centre of mass at l_c from
the axis, inertia J about the axis) obeys
    J·φ̈ = −m·l_c·((g + a_v)·sin φ + a_h·cos φ) − b·φ̇ − c·tanh(φ̇/ω_c)
(viscous b and smoothed Coulomb c bearing friction). Dividing by m·l_c: φ̈ = −((g + a_v)·sin φ + a_h·cos φ)/l_eq − …
with the equivalent length l_eq = J/(m·l_c) (2L/3 for a uniform rod of length L). The swing energy per m·l_c is
E = ½·l_eq·φ̇² − g·cos φ [m/s²]: −g hanging at rest, +g upright at rest; Ė = −a_h·φ̇·cos φ without friction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .pendulum import G

_COULOMB_SMOOTHING = 0.01  # [rad/s] ω_c: the Coulomb torque is c·tanh(φ̇/ω_c)


@dataclass(frozen=True)
class RigidPendulum:
    """A uniform rod of ``rod_length`` [m] and ``rod_mass`` [kg] with an optional ``tip_mass`` [kg] at its end,
    hung on a bearing with ``viscous`` [N·m·s/rad] and ``coulomb`` [N·m] friction."""

    rod_length: float = 0.5  # [m]
    rod_mass: float = 0.1  # [kg]
    tip_mass: float = 0.0  # [kg]
    viscous: float = 2e-4  # [N·m·s/rad]
    coulomb: float = 1e-3  # [N·m]

    def validate(self) -> None:
        """ValueError naming the bad parameter."""
        if not (math.isfinite(self.rod_length) and 0.05 <= self.rod_length <= 2.0):
            raise ValueError(f"rod length must be 0.05..2 m, got {self.rod_length:g}")
        if not (math.isfinite(self.rod_mass) and self.rod_mass >= 0 and math.isfinite(self.tip_mass)
                and self.tip_mass >= 0 and self.rod_mass + self.tip_mass > 0):  # fmt: skip
            raise ValueError(
                f"rod mass and tip mass must be >= 0 kg and not both 0, got {self.rod_mass:g}, {self.tip_mass:g}"
            )
        if not (
            math.isfinite(self.viscous) and self.viscous >= 0 and math.isfinite(self.coulomb) and self.coulomb >= 0
        ):
            raise ValueError(f"bearing friction must be >= 0, got {self.viscous:g} N·m·s/rad, {self.coulomb:g} N·m")

    @property
    def mass(self) -> float:
        """[kg]"""
        return self.rod_mass + self.tip_mass

    @property
    def com(self) -> float:
        """l_c: distance of the centre of mass from the axis [m]."""
        return (self.rod_mass * self.rod_length / 2 + self.tip_mass * self.rod_length) / self.mass

    @property
    def inertia(self) -> float:
        """J about the axis [kg·m²]."""
        return self.rod_mass * self.rod_length**2 / 3 + self.tip_mass * self.rod_length**2

    @property
    def equivalent_length(self) -> float:
        """l_eq = J/(m·l_c) [m]: the string length of a ball pendulum with the same swing."""
        return self.inertia / (self.mass * self.com)

    @property
    def natural_period(self) -> float:
        """Small-swing period 2π·√(l_eq/g) [s]."""
        return 2 * math.pi * math.sqrt(self.equivalent_length / G)

    def angular_acceleration(self, phi: float, omega: float, a_h: float, a_v: float = 0.0) -> float:
        """φ̈ [rad/s²] at angle φ [rad], rate ω [rad/s], pivot acceleration a_h along e, a_v up [m/s²]."""
        ml = self.mass * self.com
        torque = (-ml * ((G + a_v) * math.sin(phi) + a_h * math.cos(phi)) - self.viscous * omega
                  - self.coulomb * math.tanh(omega / _COULOMB_SMOOTHING))  # fmt: skip
        return torque / self.inertia


def swing_energy(phi: float, omega: float, equivalent_length: float) -> float:
    """E = ½·l_eq·φ̇² − g·cos φ [m/s²] (the energy per m·l_c): −g hanging at rest, +g upright at rest."""
    return 0.5 * equivalent_length * omega * omega - G * math.cos(phi)


def wrap_angle(x: float) -> float:
    """x wrapped to (−π, π] [rad]."""
    y = math.fmod(x + math.pi, 2 * math.pi)
    if y <= 0.0:
        y += 2 * math.pi
    return y - math.pi


def rk4_step(p: RigidPendulum, phi: float, omega: float, a0: tuple[float, float], a1: tuple[float, float],
             h: float) -> tuple[float, float]:  # fmt: skip
    """One RK4 step of length h [s] from (φ, φ̇) with the pivot acceleration (a_h, a_v) [m/s²] going linearly from
    ``a0`` to ``a1`` over the step."""
    am = (0.5 * (a0[0] + a1[0]), 0.5 * (a0[1] + a1[1]))
    f = p.angular_acceleration
    k1p, k1w = omega, f(phi, omega, *a0)
    k2p, k2w = omega + 0.5 * h * k1w, f(phi + 0.5 * h * k1p, omega + 0.5 * h * k1w, *am)
    k3p, k3w = omega + 0.5 * h * k2w, f(phi + 0.5 * h * k2p, omega + 0.5 * h * k2w, *am)
    k4p, k4w = omega + h * k3w, f(phi + h * k3p, omega + h * k3w, *a1)
    return (phi + h / 6 * (k1p + 2 * k2p + 2 * k3p + k4p), omega + h / 6 * (k1w + 2 * k2w + 2 * k3w + k4w))
