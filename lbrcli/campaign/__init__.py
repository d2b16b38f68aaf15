"""lbr's fault campaign over every surface that moves the robot: the CSV player (``lbr execute``), the point-to-point
move, the bridge's follower and its sources, the damper and its ball sensor, the upright controller and its encoder,
TORQUE and WRENCH overlays and a user's own clients — each against the scripted controller
(:mod:`lbrcli.fri.testing`) under the controller's faults and its own. ``python benchmarks/bench_safety.py`` prints
the table per surface; the test suite runs a subset."""

from __future__ import annotations

from lbrcli.fri.testing.campaign import Case

from .execute import execute_cases
from .surfaces import all_surfaces, surface_cases

__all__ = ["all_cases", "execute_cases"]


def all_cases() -> list[Case]:
    """Every case of every surface (≥ 250)."""
    out = execute_cases()
    for s in all_surfaces():
        out += surface_cases(s)
    return out
