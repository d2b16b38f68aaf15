"""Compatibility shim: the simulator moved to ``lbrcli.fri.sim`` (plants to ``lbrcli.plants``)."""

from ..plants.ball import BALL_IO_NAMES  # noqa: F401
from .sim import SimConfig, SimStats, Simulator, SimulatorProcess  # noqa: F401
from .sim.config import OPERATION_MODES, THESIS_Q0  # noqa: F401
