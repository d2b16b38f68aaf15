"""Things attached to the robot's flange, simulated with it: the Plant protocol.

A ``PlantSpec`` is a small picklable description (frozen dataclass) that crosses into the simulator process and
builds its ``Plant`` there (``build(context)``). Every cycle the simulator calls ``plant.step(t, tcp)`` with the
simulated time t [s] and the TCP position [m] (base frame) of the robot's MEASURED pose after that cycle's
motion (a plant with ``uses_rotation = True`` also gets the TCP's rotation matrix, base frame); the plant answers the values of its analog input channels (``inputs``, in order), which the controller
reports in the monitoring message's readIORequest like any other configured input.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol, Sequence, runtime_checkable


@dataclass
class PlantContext:
    """What a plant is built with inside the simulator process."""

    period_s: float  # [s] the simulator's cycle
    robot: Any  # trajectories.robot.Robot (pinocchio model with the configured TCP)
    q0: tuple[float, ...]  # [rad] the robot's start position
    plants: list = field(default_factory=list)  # the plants built before this one (in SimConfig.plants order)
    lockstep: bool = False  # the simulator runs in lock-step: what a plant hands the client must be there each cycle


@runtime_checkable
class Plant(Protocol):
    """A simulated thing hanging from (or attached to) the TCP."""

    name: str  # key of its figures in SimStats.plants
    inputs: tuple[str, ...]  # analog INPUT channels it drives [their units: the plant's documentation]

    def step(self, t: float, tcp: Sequence[float]) -> Sequence[float]:
        """Advance one cycle to time t [s] with the TCP at ``tcp`` [m]; the values of ``inputs``."""
        ...

    def info(self) -> dict:
        """Facts for whoever started the simulator (e.g. a device path), known right after build."""
        ...

    def figures(self) -> dict:
        """End-of-session figures (JSON-able)."""
        ...

    def close(self) -> None: ...


@runtime_checkable
class PlantSpec(Protocol):
    """Picklable recipe of a plant."""

    def build(self, context: PlantContext) -> Plant: ...
