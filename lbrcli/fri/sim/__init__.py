"""The FRI controller simulator: the robot side of an FRI session on real UDP, a KUKA controller running a
PositionHold application with an FRI overlay (position, torque, wrench or — FRI 2.7 — Cartesian pose command
mode; 2.7 transformation requests), plants attached to the
flange plugged in from outside (``Plant``/``PlantSpec``)."""

from .config import IO_PRESETS, THESIS_Q0, IoChannel, SimConfig, lenient_quality, parse_io
from .plant import Plant, PlantContext, PlantSpec
from .process import SimulatorProcess
from .simulator import Simulator
from .stats import SimStats

__all__ = [
    "IO_PRESETS",
    "THESIS_Q0",
    "IoChannel",
    "Plant",
    "PlantContext",
    "PlantSpec",
    "SimConfig",
    "SimStats",
    "lenient_quality",
    "Simulator",
    "SimulatorProcess",
    "parse_io",
]
