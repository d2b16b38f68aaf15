"""Joint and task trajectories and what they must respect: the iiwa 7 R800 model (pinocchio), its joint limits,
the CSV file contract, inverse kinematics of whole paths and of single poses, the limit check, retiming and
resampling, and the typed errors every command turns into exit codes.

The names below are the entry points (imported on first use, so that ``import trajectories`` stays cheap).
"""

from .lazy import lazy_exports

TYPE_CHECKING = False  # typing.TYPE_CHECKING without importing typing (type checkers and griffe read it so)
if TYPE_CHECKING:
    from .check import check_trajectory
    from .csvio import read_joint_csv, read_table, read_task_csv, write_joint_csv, write_table, write_task_csv
    from .envelope import BrakingEnvelope
    from .errors import CheckFailed, CsvFormatError, IkError, InputError, LbrError, OptionError, PlanningError
    from .ik import IkOptions, solve_ik_path
    from .ik_online import OnlineIk, OnlineIkOptions
    from .limits import JointLimits, default_limits, load_limits
    from .retime import retime_within
    from .robot import Flange, Robot, RobotConfig
    from .trajectory import JointTrajectory, TaskTrajectory

__all__ = [
    "BrakingEnvelope", "CheckFailed", "CsvFormatError", "Flange", "IkError", "IkOptions", "InputError",
    "JointLimits", "JointTrajectory", "LbrError", "OnlineIk", "OnlineIkOptions", "OptionError", "PlanningError",
    "Robot", "RobotConfig", "TaskTrajectory", "check_trajectory", "default_limits", "load_limits", "read_joint_csv",
    "read_table", "read_task_csv", "retime_within", "solve_ik_path", "write_joint_csv", "write_table",
    "write_task_csv",
]  # fmt: skip
__getattr__, __dir__ = lazy_exports(__name__)
