"""Feedback control of a pendulum on the robot's flange at the FRI rate: the cart (the arm on its rail), the
delay-compensating observer, LQR gains, the swing-up and balance of the rigid pendulum, and the sway damper.
Pure algorithms: no FRI, no I/O."""

from .cart import Cart
from .correction import CorrectionPlan, correction_plan
from .damping import DampingOptions, SwayDamper, simulate_damping, sway_reference
from .observer import DelayedObserver
from .upright import Mode, UprightController, UprightOptions

__all__ = [
    "Cart",
    "CorrectionPlan",
    "DampingOptions",
    "DelayedObserver",
    "Mode",
    "SwayDamper",
    "UprightController",
    "UprightOptions",
    "correction_plan",
    "simulate_damping",
    "sway_reference",
]
