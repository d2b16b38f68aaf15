"""Planning algorithms and physics: anti-sway transfers, swing-ups and the cup-and-ball game, the pendulum and
string models they are built on and judged by, input shapers, the rail of the pendulum module, obstacles.

Pure functions over numpy arrays and small frozen dataclasses — no I/O; the CLI (``lbr plan …``) is the edge. The
names below are the entry points (imported on first use); the feedback controllers are in :mod:`planners.feedback`.
"""

from trajectories.lazy import lazy_exports

TYPE_CHECKING = False  # typing.TYPE_CHECKING without importing typing (type checkers and griffe read it so)
if TYPE_CHECKING:
    from .antisway import AntiSwayOptions, plan_layout, simulate_path
    from .catch_plan import CatchRequest, plan_catch
    from .obstacles import Obstacle, clearance
    from .pendulum import PendulumRun, natural_period
    from .rail import Rail, build_rail
    from .rigid_pendulum import RigidPendulum
    from .shapers import make_shaper
    from .string_model import Ball, Cup, StringModel
    from .string_sim import PivotMotion, simulate_string
    from .string_stepper import StringStepper
    from .sway_judge import judge_sway
    from .swingup import SwingUpRequest, plan_swing_up
    from .swingup_energy import EnergyParams, plan_energy
    from .swingup_plan import TaskBounds

__all__ = [
    "AntiSwayOptions", "Ball", "CatchRequest", "Cup", "EnergyParams", "Obstacle", "PendulumRun", "PivotMotion", "Rail",
    "RigidPendulum", "StringModel", "StringStepper", "SwingUpRequest", "TaskBounds", "build_rail", "clearance",
    "judge_sway", "make_shaper", "natural_period", "plan_catch", "plan_energy", "plan_layout", "plan_swing_up",
    "simulate_path", "simulate_string",
]  # fmt: skip
__getattr__, __dir__ = lazy_exports(__name__)
