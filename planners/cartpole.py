"""Planar pendulum on a cart (thesis §4.2.1, §5.2): the ball on its string driven by the pivot acceleration.

The pivot moves along one horizontal axis x (base y for the swing-up); θ is the string angle from the hanging
vertical, positive toward +x. With the pivot acceleration u = ẍ as the input (m ≪ M):
    θ̈ = −(u/l)·cos θ − (g/l)·sin θ                                   (thesis 5.1)
    E = ½·m·l²·θ̇² − m·g·l·cos θ,    Ė = −u·m·l·θ̇·cos θ                (thesis 5.2, 5.4)
Energies are in joules when ``mass`` is in kg (per unit mass with mass = 1).
"""

from __future__ import annotations

import math

import numpy as np

from .pendulum import G


def theta_ddot(theta, theta_dot, u, length: float, g: float = G):
    """θ̈ [rad/s²] for angle θ [rad], pivot acceleration u [m/s²], string length [m] (arrays broadcast)."""
    return -(np.asarray(u) / length) * np.cos(theta) - (g / length) * np.sin(theta)


def energy(theta, theta_dot, length: float, mass: float = 1.0, g: float = G):
    """Swing energy E = ½ m l² θ̇² − m g l cos θ [J] (per unit mass [J/kg] with mass = 1)."""
    return 0.5 * mass * length**2 * np.square(theta_dot) - mass * g * length * np.cos(theta)


def energy_rate(theta, theta_dot, u, length: float, mass: float = 1.0):
    """Ė = −u·m·l·θ̇·cos θ [W] (thesis 5.4): the power the pivot acceleration u [m/s²] feeds the swing."""
    return -np.asarray(u) * mass * length * np.asarray(theta_dot) * np.cos(theta)


def desired_energy(theta_d: float, length: float, mass: float = 1.0, g: float = G) -> float:
    """E_d = −m g l cos θ_d [J]: the energy of a swing whose apex (θ̇ = 0) is θ_d [rad]."""
    return -mass * g * length * math.cos(theta_d)


def apex_angle(e: float, length: float, mass: float = 1.0, g: float = G) -> float:
    """Apex angle [rad] of a free swing of energy e [J] (π when it would go over the top)."""
    c = -e / (mass * g * length)
    return math.acos(min(1.0, max(-1.0, c)))


def rhs(state: np.ndarray, u: float, length: float, g: float = G) -> np.ndarray:
    """d/dt of the state (x [m], ẋ [m/s], θ [rad], θ̇ [rad/s]) for the pivot acceleration u [m/s²]."""
    x, v, th, om = state
    return np.array([v, u, om, -(u / length) * math.cos(th) - (g / length) * math.sin(th)])
