"""Plants for the FRI simulator: things hanging from the robot's flange, simulated with it (the ball on its string,
the thesis's pendulum module on a pseudo-terminal). Each is a picklable spec whose ``build`` makes the plant inside
the simulator process (see ``lbrcli.fri.sim.plant``)."""

from __future__ import annotations

from .ball import BALL_IO_NAMES, BallSpec
from .pendulum_module import PendulumModuleSpec

__all__ = ["BALL_IO_NAMES", "BallSpec", "PendulumModuleSpec", "default_plants"]


def default_plants(
    ball_length: float | None,
    ball_damping: float = 0.0,
    pendulum_pty: bool = False,
    pendulum_rate_hz: float = 200.0,
    model=None,
) -> tuple:
    """The plants of a lab session for ``SimConfig.plants``: a ball on a string of ``ball_length`` [m] (None or
    0: none) with damping [1/s] hanging from the TCP, optionally the pendulum module emulated on a pty at
    ``pendulum_rate_hz`` [Hz]. The ball hangs from the simulator's TCP: the tool offset is ``SimConfig.tool``;
    ``model`` (``planners.string_model.StringModel``) gives another ball and the cup on the flange.
    SettingError naming the field of a bad value."""
    from trajectories.errors import SettingError

    if not ball_length:
        if pendulum_pty:
            raise SettingError("default_plants", "ball_length", "the pendulum module emulation needs a simulated ball")
        return ()
    plants: tuple = (BallSpec(ball_length, ball_damping, model=model),)
    if pendulum_pty:
        plants += (PendulumModuleSpec(pendulum_rate_hz),)
    for spec in plants:
        spec.validate()
    return plants
