"""Typed exceptions of lbr, in one place.

Every exception carries the process exit code the CLI uses: 2 for bad input (a file, a row, a column or an
option the user must fix), 1 for a check that failed (limits violated, target not reached, robot refused).
"""

from __future__ import annotations

from pathlib import Path


class LbrError(Exception):
    """Base of all lbr errors."""

    exit_code = 1


class InputError(LbrError):
    """Bad input: a malformed file or option. Exit code 2."""

    exit_code = 2

    def __init__(
        self,
        message: str,
        *,
        file: str | Path | None = None,
        row: int | None = None,
        column: int | None = None,
        column_name: str | None = None,
    ) -> None:
        self.message = message
        self.file = str(file) if file is not None else None
        self.row = row  # 1-based line number in the file
        self.column = column  # 1-based column number
        self.column_name = column_name
        super().__init__(self.__str__())

    def __str__(self) -> str:
        where = []
        if self.file is not None:
            where.append(self.file)
        if self.row is not None:
            where.append(f"row {self.row}")
        if self.column is not None:
            name = f" ({self.column_name})" if self.column_name else ""
            where.append(f"column {self.column}{name}")
        return (", ".join(where) + ": " if where else "") + self.message


class CsvFormatError(InputError):
    """A CSV file does not follow the lbr file contract."""


class OptionError(InputError):
    """A command-line option value is malformed or out of range."""


class SettingError(OptionError):
    """A field of a settings object is out of range or does not go with the others. ``setting`` names it as
    ``Class.field`` (e.g. ``BallSpec.length``): library code never names a command-line flag, the CLI edge maps the
    setting to the option it came from (:mod:`lbrcli.option_groups`). Exit code 2."""

    def __init__(self, owner: type | str, field: str, message: str) -> None:
        self.setting = f"{owner if isinstance(owner, str) else owner.__name__}.{field}"
        super().__init__(message)

    def __str__(self) -> str:
        return f"{self.setting}: {self.message}"


class OutputRefused(InputError):
    """An output path the commands do not replace: a symbolic link, a device, a FIFO or a socket. Exit code 2."""


class OutputError(LbrError):
    """An output could not be written (disk full, quota, I/O error); nothing is left under its name. Exit code 1."""

    def __init__(self, message: str, *, file: str | Path) -> None:
        self.file = str(file)
        super().__init__(f"{self.file}: {message}")


class CheckFailed(LbrError):
    """A check found violations (limits, start distance, ...). Exit code 1."""


class IkError(LbrError):
    """Inverse kinematics did not reach a pose within tolerance. Exit code 1.

    ``reason`` is "out of reach" (no joint configuration reaches the pose), "position limit" (reachable only
    beyond a joint's position limit), "velocity limit" (reachable only faster than a joint's speed limit) or
    "not converged"; ``joint`` (0-based) and ``needed`` [rad] or [rad/s] name the limiting joint and the value
    it would need. ``kind`` says whose fact it is: "pose" (no configuration of the pose is inside the limits),
    "path" (the speed a joint set by the poses alone needs), "start" (the path lbr followed from its start ran
    into a limit there; the pose itself is reachable) or "" (not known).
    """

    def __init__(
        self,
        message: str,
        *,
        index: int,
        t: float,
        position_error: float,
        rotation_error: float,
        reason: str = "not converged",
        joint: int | None = None,
        needed: float | None = None,
        kind: str = "",
    ):
        self.index = index
        self.t = t
        self.position_error = position_error  # [m]
        self.rotation_error = rotation_error  # [rad]
        self.reason = reason
        self.joint = joint
        self.needed = needed
        self.kind = kind
        super().__init__(message)

    def figures(self) -> dict:
        """The refusal as JSON figures."""
        return {
            "index": self.index,
            "t_s": self.t,
            "reason": self.reason,
            "kind": self.kind,
            "joint": None if self.joint is None else self.joint + 1,
            "needed": self.needed,
            "position_error_m": None if self.position_error != self.position_error else self.position_error,
            "rotation_error_rad": None if self.rotation_error != self.rotation_error else self.rotation_error,
        }


class PlanningError(LbrError):
    """A planner cannot produce the requested plan (e.g. a_max does not fit the limits). Exit code 1."""


class FriError(LbrError):
    """An FRI session could not be run or ended abnormally. Exit code 1."""


class FriDecodeError(LbrError):
    """A datagram is not a valid FRI message of the expected version."""


class FriForeignMessage(FriDecodeError):
    """A well-formed FRI datagram of another message type (foreign message identifier)."""
