"""Options shared by several commands, the one mechanism that validates every value option at parse time, and the
objects built from them.

Every numeric option of every command is declared with :func:`number` (or, for values that carry numbers in text,
:func:`angle`, :func:`floats`, :func:`joints`, :func:`grid`, :func:`choice`): a typer ``parser`` checks the syntax
(plain decimals, :mod:`trajectories.numbers`), finiteness and the range while click parses the command line, so a
bad value is a one-line usage error (exit 2) naming the option before any work starts, and the range appears in
the option's help. ``tests/lbrcli/test_app_bad_inputs.py`` checks that no numeric option escapes it.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any, Optional, Sequence

import numpy as np
import typer

from trajectories.start_poses import THESIS_START

# ---------------------------------------------------------------- parse-time validation


def _fmt(v: float) -> str:
    """1e-4 → '0.0001', 4294967295 → '4294967295', 1e300 → '1e+300'."""
    if float(v).is_integer() and abs(v) < 1e15:
        return str(int(v))
    return f"{v:g}"


class Number:
    """typer ``parser`` of a numeric option: plain decimal syntax, finite, inside [low, high] (open at an end with
    ``low_open``/``high_open``; None: unbounded); ``integer`` for whole numbers."""

    def __init__(self, low: float | None = None, high: float | None = None, *, low_open: bool = False,
                 high_open: bool = False, unit: str = "", integer: bool = False) -> None:  # fmt: skip
        self.low, self.high, self.low_open, self.high_open = low, high, low_open, high_open
        self.unit, self.integer = unit, integer

    def describe(self) -> str:
        """The range in words, e.g. 'in [0, 1)', '> 0 s', 'in [1, 100] ms' (what the value 'must be')."""
        u = f" {self.unit}" if self.unit else ""
        whole = "a whole number " if self.integer else ""
        if self.low is not None and self.high is not None:
            lo, hi = "(" if self.low_open else "[", ")" if self.high_open else "]"
            return f"{whole}in {lo}{_fmt(self.low)}, {_fmt(self.high)}{hi}{u}"
        if self.low is not None:
            return f"{whole}{'>' if self.low_open else '≥'} {_fmt(self.low)}{u}"
        if self.high is not None:
            return f"{whole}{'<' if self.high_open else '≤'} {_fmt(self.high)}{u}"
        return f"a finite {'whole ' if self.integer else ''}number{u}"

    def check(self, value: float) -> float:
        """``value`` if inside the range, else BadParameter ('must be in [0, 1), got 2')."""
        ok = math.isfinite(value)
        if ok and self.low is not None:
            ok = value > self.low if self.low_open else value >= self.low
        if ok and self.high is not None:
            ok = value < self.high if self.high_open else value <= self.high
        if not ok:
            raise typer.BadParameter(f"must be {self.describe()}, got {_fmt(value)}")
        return value

    def __call__(self, value: Any) -> float | int | None:
        from trajectories.numbers import DECIMAL, NotANumber, plain_float, plain_int

        if value is None:
            return None
        if isinstance(value, (int, float)) and not isinstance(value, bool):  # a default
            return self.check(value)
        try:
            v = plain_int(value) if self.integer else plain_float(value)
        except NotANumber:
            text = str(value).strip()
            if text.lower().lstrip("+-") in ("nan", "inf", "infinity") or (DECIMAL.match(text) and not self.integer):
                raise typer.BadParameter(f"must be {self.describe()}, got {text}") from None
            kind = "a whole number" if self.integer else "a plain decimal number"
            raise typer.BadParameter(f"must be {kind} ({self.describe()}), got {text!r}") from None
        return self.check(v)


class StringLength(Number):
    """typer ``parser`` of a ball's string length [m]: the one rule of every such option (and of the simulated ball,
    :data:`lbrcli.plants.ball.STRING_LENGTH_M`); with ``zero_is_none`` also 0 for "no ball"."""

    def __init__(self, zero_is_none: bool = False) -> None:
        from lbrcli.plants.ball import STRING_LENGTH_M

        super().__init__(*STRING_LENGTH_M, unit="m")
        self.zero_is_none = zero_is_none

    def describe(self) -> str:
        return f"0 (no ball) or {super().describe()}" if self.zero_is_none else super().describe()

    def check(self, value: float) -> float:
        return 0.0 if self.zero_is_none and value == 0 else super().check(value)


class Angle:
    """typer ``parser`` of an angle: a number with an optional deg/°/rad suffix (``default_unit`` without one),
    finite, inside (low_deg, high_deg) [deg]; returns radians."""

    def __init__(self, low_deg: float, high_deg: float, *, low_open: bool = False, high_open: bool = False,
                 default_unit: str = "rad") -> None:  # fmt: skip
        self.range = Number(low_deg, high_deg, low_open=low_open, high_open=high_open, unit="°")
        self.default_unit = default_unit

    def describe(self) -> str:
        return self.range.describe().replace(" °", "°").replace("]°", "°]").replace(")°", "°)")

    def __call__(self, value: Any) -> float | None:
        from trajectories.errors import OptionError

        from .parsing import parse_angle

        if value is None:
            return None
        if isinstance(value, (int, float)) and not isinstance(value, bool):  # a default [rad]
            rad = float(value)
        else:
            text = str(value).strip().lower()
            if self.default_unit == "deg" and not text.endswith(("deg", "rad", "°")):
                text += "deg"
            try:
                rad = parse_angle(text, "")
            except OptionError:
                raise typer.BadParameter(f"must be an angle {self.describe()} (a plain number, optionally with deg "
                                         f"or rad), got {str(value)!r}") from None  # fmt: skip
        try:
            self.range.check(math.degrees(rad))
        except typer.BadParameter:
            raise typer.BadParameter(f"must be {self.describe()}, got {_fmt(math.degrees(rad))}°") from None
        return rad


class Floats:
    """typer ``parser`` of ``count`` comma-separated numbers, each inside ``low..high`` [unit]; returns a tuple."""

    def __init__(self, count: int, low: float, high: float, unit: str = "", sep: str = ",") -> None:
        self.count, self.sep = count, sep
        self.range = Number(low, high, unit=unit)

    def describe(self) -> str:
        return f"{self.count} numbers, each {self.range.describe()}"

    def __call__(self, value: Any) -> tuple[float, ...] | None:
        from trajectories.numbers import NotANumber, plain_float

        if value is None:
            return None
        parts = list(value) if isinstance(value, (tuple, list, np.ndarray)) else str(value).split(self.sep)
        if len(parts) != self.count:
            raise typer.BadParameter(f"must be {self.describe()} separated by '{self.sep}', got {len(parts)} in "
                                     f"{value!r}")  # fmt: skip
        out = []
        for p in parts:
            try:
                v = float(p) if isinstance(p, (int, float, np.floating)) else plain_float(p)
                out.append(self.range.check(v))
            except (NotANumber, typer.BadParameter):
                raise typer.BadParameter(f"must be {self.describe()}, got {value!r}") from None
        return tuple(out)


class Points:
    """typer ``parser`` of points 'x0,y0;x1,y1;...' [m], each coordinate within ±``bound``; returns (n, dims)."""

    def __init__(self, dims: int = 2, bound: float = 5.0) -> None:
        self.dims = dims
        self.each = Floats(dims, -bound, bound, "m")

    def __call__(self, value: Any) -> np.ndarray | None:
        if value is None or isinstance(value, np.ndarray):
            return value
        pts = [p for p in str(value).split(";") if p.strip()]
        if not pts:
            raise typer.BadParameter("must be points 'x0,y0;x1,y1;...'")
        return np.array([self.each(p) for p in pts])


class JointVector(np.ndarray):
    """(7,) joint angles [rad]: the type of joint-vector options and arguments (what --help shows)."""


class Joints:
    """typer ``parser`` of 7 joint angles (deg/rad suffixes, radians without), each within ±360°; returns a (7,)
    array [rad]. Whether they are inside the joint limits is for the command to check (see :func:`within_limits`)."""

    def __call__(self, value: Any) -> np.ndarray | None:
        from trajectories.errors import OptionError

        from .parsing import parse_joint_vector

        if value is None:
            return None
        try:
            q = parse_joint_vector(value, "")
        except OptionError as exc:
            raise typer.BadParameter(str(exc)) from None
        if np.any(np.abs(q) > 2 * math.pi):
            j = int(np.argmax(np.abs(q) > 2 * math.pi))
            raise typer.BadParameter(f"A{j + 1} = {math.degrees(q[j]):g}° is beyond ±360° (a radian value with a "
                                     "deg suffix?)")  # fmt: skip
        return q


class Grid:
    """typer ``parser`` of 'AxB' (two whole numbers, each low..high); returns (a, b)."""

    def __init__(self, low: int, high: int, unit: str = "") -> None:
        self.range = Number(low, high, unit=unit, integer=True)

    def __call__(self, value: Any) -> tuple[int, int] | None:
        from trajectories.numbers import NotANumber, plain_int

        if value is None or isinstance(value, tuple):
            return value
        parts = str(value).lower().replace("×", "x").split("x")
        try:
            a, b = (plain_int(p) for p in parts)
        except (ValueError, NotANumber):
            raise typer.BadParameter(f"must be AxB with two whole numbers (e.g. 1280x720), got {value!r}") from None
        return int(self.range.check(a)), int(self.range.check(b))


class Choice:
    """typer ``parser`` of one word out of ``choices`` (``fold``, e.g. ``str.upper``, applied first)."""

    def __init__(self, choices: Sequence[str], fold=None) -> None:
        self.choices = tuple(choices)
        self.fold = fold

    def __call__(self, value: Any) -> str | None:
        if value is None:
            return None
        text = str(getattr(value, "value", value))
        text = self.fold(text) if self.fold is not None else text
        if text not in self.choices:
            raise typer.BadParameter(f"must be one of {', '.join(self.choices)}, got {text!r}")
        return text


def _escaped(text: str) -> str:
    return text.replace("[", "\\[")


def number(*decls: str, help: str, low: float | None = None, high: float | None = None, low_open: bool = False,
           high_open: bool = False, unit: str = "", integer: bool = False, **kwargs: Any) -> Any:  # fmt: skip
    """A numeric typer option validated at parse time; its range is appended to the help."""
    spec = Number(low, high, low_open=low_open, high_open=high_open, unit=unit, integer=integer)
    return typer.Option(*decls, help=f"{help} \\[{_escaped(spec.describe())}]", parser=spec, **kwargs)


def string_length(*decls: str, help: str, zero_is_none: bool = False, **kwargs: Any) -> Any:
    """A ball's string length option [m] (:class:`StringLength`), validated at parse time; its range in the help."""
    spec = StringLength(zero_is_none)
    return typer.Option(*decls, help=f"{help} \\[{_escaped(spec.describe())}]", parser=spec, **kwargs)


def angle(*decls: str, help: str, low_deg: float, high_deg: float, low_open: bool = False, high_open: bool = False,
          default_unit: str = "rad", **kwargs: Any) -> Any:  # fmt: skip
    """An angle option (deg/rad suffixes) validated at parse time; the command receives radians."""
    spec = Angle(low_deg, high_deg, low_open=low_open, high_open=high_open, default_unit=default_unit)
    return typer.Option(*decls, help=f"{help} \\[{_escaped(spec.describe())}]", parser=spec,
                        metavar=kwargs.pop("metavar", "ANGLE"), **kwargs)  # fmt: skip


def floats(*decls: str, help: str, count: int, low: float, high: float, unit: str = "", metavar: str = "X,Y",
           **kwargs: Any) -> Any:  # fmt: skip
    """An option of ``count`` comma-separated numbers validated at parse time; the command receives a tuple."""
    spec = Floats(count, low, high, unit)
    return typer.Option(*decls, help=f"{help} \\[{_escaped(spec.describe())}]", parser=spec, metavar=metavar,
                        **kwargs)  # fmt: skip


def joints(*decls: str, help: str, argument: bool = False, **kwargs: Any) -> Any:
    """A joint-vector option (or argument) validated at parse time; the command receives a (7,) array [rad]."""
    make = typer.Argument if argument else typer.Option
    return make(*decls, help=help, parser=Joints(), metavar=kwargs.pop("metavar", "Q1,...,Q7"), **kwargs)


def grid(*decls: str, help: str, low: int, high: int, metavar: str = "AxB", **kwargs: Any) -> Any:
    """An 'AxB' option of two whole numbers validated at parse time; the command receives (a, b)."""
    return typer.Option(*decls, help=f"{help} \\[each {low}..{high}]", parser=Grid(low, high), metavar=metavar,
                        **kwargs)  # fmt: skip


def choice(*decls: str, help: str, choices: Sequence[str], fold=None, **kwargs: Any) -> Any:
    """An option taking one of ``choices`` (after ``fold``, e.g. ``str.lower``), validated at parse time."""
    return typer.Option(*decls, help=help, parser=Choice(choices, fold), metavar=kwargs.pop("metavar", "|".join(choices)),
                        **kwargs)  # fmt: skip


def within_limits(q: np.ndarray | None, lim, option: str) -> np.ndarray | None:
    """``q`` [rad] when inside the joint position limits; OptionError (exit 2) naming the joint otherwise."""
    from trajectories.errors import OptionError

    if q is None:
        return None
    over = np.flatnonzero(np.abs(q) > lim.position)
    if over.size:
        j = int(over[0])
        raise OptionError(f"{option}: A{j + 1} = {q[j]:.4f} rad ({math.degrees(q[j]):.1f}°) is outside the position "
                          f"limit ±{lim.position[j]:.4f} rad ({math.degrees(lim.position[j]):.0f}°)")  # fmt: skip
    return q


# ---------------------------------------------------------------- options shared by several commands

FLANGES = ("touch-electric", "standard", "touch-pneumatic")
MAX_TOOL_OFFSET = 2.0  # [m], as trajectories.robot.parse_tool

JsonOpt = Annotated[
    bool, typer.Option("--json", help="Print one JSON object with the figures on stdout; text goes to stderr.")
]
FlangeOpt = Annotated[
    str,
    choice(
        "--flange",
        choices=FLANGES,
        metavar="FLANGE",
        help="Media flange: touch-electric (d7 = 0.152 m), standard (0.126 m), touch-pneumatic (0.187 m).",
    ),
]
ToolOpt = Annotated[
    Optional[tuple],
    floats(
        "--tool",
        count=3,
        low=-MAX_TOOL_OFFSET,
        high=MAX_TOOL_OFFSET,
        unit="m",
        metavar="X,Y,Z",
        help="Tool offset x,y,z \\[m] in the flange frame (e.g. the string attachment).",
    ),
]
LimitsOpt = Annotated[
    Optional[Path], typer.Option("--limits", help="TOML file overriding the limit tables (see trajectories/data).")
]
DtOpt = Annotated[
    Optional[float],
    number(
        "--dt", low=1e-4, high=1.0, unit="s", help="Sample step \\[s] of a headerless 7-column joint file."
    ),  # fmt: skip
]
MarginOpt = Annotated[
    float,
    number(
        "--margin", low=0.0, high=1.0, high_open=True, help="Check against the limits scaled by (1 − margin)."
    ),  # fmt: skip
]

DEFAULT_FLANGE = "touch-electric"
THESIS_Q_START = ",".join(f"{v:g}" for v in THESIS_START)  # [rad] as an option's text, thesis §5.3.2 start pose


def robot_config(flange: str, tool: Sequence[float] | str | None):
    """RobotConfig from --flange and --tool."""
    from trajectories.robot import RobotConfig, parse_flange, parse_tool

    return RobotConfig(flange=parse_flange(flange), tool=parse_tool(tool))


def make_robot(flange: str, tool: Sequence[float] | str | None):
    """Robot from --flange and --tool."""
    from trajectories.robot import Robot

    return Robot(robot_config(flange, tool))


def limits_from(path: Path | None):
    from trajectories.limits import load_limits

    return load_limits(path)


def check_number(
    option: str,
    value: float | None,
    low: float | None = None,
    high: float | None = None,
    *,
    low_open: bool = False,
    high_open: bool = False,
    unit: str = "",
) -> float | None:
    """``value`` if it is a finite number inside the range, else OptionError (exit 2) in one line — for values
    derived from options or files (e.g. a step taken from the input); options themselves use :func:`number`.

    The range is [low, high] (open at an end with ``low_open``/``high_open``; None: unbounded). NaN and ±inf are
    always refused; None (an option not given) passes through.
    """
    from trajectories.errors import OptionError

    if value is None:
        return None
    try:
        return Number(low, high, low_open=low_open, high_open=high_open, unit=unit).check(value)
    except typer.BadParameter as exc:
        raise OptionError(f"{option} {exc.message}") from None


def parse_as_command(fn, values: dict[str, Any]) -> dict[str, Any]:
    """``values`` by parameter name of the command function ``fn``, as a user types them (text, or a number a study
    file gives: written as on the command line, so a plain number of an angle option means what its --help says)
    → what the command receives from its parse-time validators; OptionError (exit 2) naming the option. Values of
    parameters without a validator, and None, pass unchanged. In-process callers (``lbr sweep``) check their
    values by this, with the command's own ranges."""
    import typing

    import typer.models

    from trajectories.errors import OptionError

    hints = typing.get_type_hints(fn, include_extras=True)
    out = dict(values)
    for name, value in values.items():
        hint = hints.get(name)
        if value is None or typing.get_origin(hint) is not typing.Annotated:
            continue
        for m in typing.get_args(hint)[1:]:
            if isinstance(m, typer.models.ParameterInfo) and m.parser is not None:
                first = (m.default,) if isinstance(m.default, str) else ()  # typer.Option("--x", ...) in Annotated
                decls = [d for d in (*first, *(m.param_decls or ())) if d.startswith("-")]
                shown = max(decls, key=len) if decls else name
                typed = str(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else value
                try:
                    out[name] = m.parser(typed)
                except typer.BadParameter as exc:
                    raise OptionError(f"{shown} {exc.message}") from None  # as check_number says it
    return out
