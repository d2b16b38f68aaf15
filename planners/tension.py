"""Tension condition of the string (thesis §5.5, eqs. 5.8–5.9) for planar swings and sampled pivot paths.

Thesis 5.9 reads m·l·θ̇² + m·g·cos θ − M·ẍ·sin θ + M·ÿ·cos θ > 0 (M the pivot mass). For the ball on a string
driven by a position-controlled robot (m ≪ M) the physically meaningful form is the load's radial force
balance per unit ball mass (facts/physics.md):
    T/m = l·θ̇² + (g + ÿ)·cos θ − ẍ·sin θ > 0                                                  [m/s²]
with ẍ the pivot acceleration along the swing axis (positive in the direction of positive θ: base +y for
the swing-up) and ÿ the vertical pivot acceleration (positive up). It equals
``planners.pendulum.tension_per_mass`` for planar states; the tension in newtons is m times the margin.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .pendulum import G


def tension_margin(theta, theta_dot, acc_horizontal, acc_vertical=0.0, length: float = 1.0, g: float = G):
    """String tension per unit ball mass T/m [m/s²] (> 0 taut) for planar states (arrays broadcast).

    theta [rad] from the hanging vertical, theta_dot [rad/s], pivot accelerations [m/s²] along the swing
    axis (toward positive θ) and vertically (up), string length [m].
    """
    theta = np.asarray(theta, dtype=float)
    return (
        length * np.square(theta_dot)
        + (g + np.asarray(acc_vertical, dtype=float)) * np.cos(theta)
        - np.asarray(acc_horizontal, dtype=float) * np.sin(theta)
    )


def apex_acceleration_to_stay_taut(theta: float, g: float = G) -> float:
    """Pivot acceleration [m/s²] along the swing axis needed at an apex (θ̇ = 0, ÿ = 0) at θ [rad], 0 < θ < π.

    The string stays taut only while ẍ < g·cot θ: above 90° the pivot must accelerate away from the ball
    (ẍ < 0 for θ > 0), e.g. −4.57 m/s² at 115°.
    """
    return g * math.cos(theta) / math.sin(theta)


def fixed_pivot_slack_angle(theta_apex: float) -> float:
    """Angle [rad] at which a free swing with apex θ_apex [rad] > 90° goes slack (pivot at rest).

    With energy conservation l·θ̇² = 2g(cos θ − cos θ_apex), T/m = g(3 cos θ − 2 cos θ_apex) = 0 at
    cos θ = (2/3)·cos θ_apex (131.8° for an upright apex, 106.4° for 115°). Returns θ_apex if ≤ 90°.
    """
    if theta_apex <= math.pi / 2:
        return theta_apex
    return math.acos(2.0 / 3.0 * math.cos(theta_apex))


@dataclass(frozen=True)
class SlackReport:
    """Where the string goes slack along a sampled run: min margin [m/s²], its time [s], first slack time [s]."""

    min_margin: float  # [m/s²], tension / ball mass
    t_min: float  # [s]
    t_first_slack: float | None  # [s], None if taut throughout
    slack_fraction: float  # share of samples with margin ≤ 0 [-]

    @property
    def taut(self) -> bool:
        return self.t_first_slack is None


def slack_report(t: np.ndarray, margin: np.ndarray) -> SlackReport:
    """Summarise a sampled tension margin (T/m [m/s²] at times t [s]; NaN where the string is slack — a one-sided
    string model has no tension there — counts as slack, the minimum is over the taut samples)."""
    margin = np.asarray(margin, dtype=float)
    taut = np.isfinite(margin)
    k = int(np.nanargmin(margin)) if taut.any() else 0
    slack = np.flatnonzero(~(margin > 0.0))
    return SlackReport(
        min_margin=float(margin[k]) if taut.any() else float("nan"),
        t_min=float(t[k]),
        t_first_slack=float(t[slack[0]]) if slack.size else None,
        slack_fraction=float(slack.size / max(1, margin.size)),
    )
