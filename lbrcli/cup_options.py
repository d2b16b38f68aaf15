"""The cup-and-ball toy on the command line: ball, cup and contact options, and the compact ``--cup`` spec.

`lbr plan cup-and-ball` takes them one by one (``--cup-radius`` …); `lbr execute`, `lbr sim` and `lbr track film`
take the same values as one ``--cup`` spec (``radius=0.03,depth=0.045,...``; ``default`` for the defaults), which
the plan prints for its rehearsal. Defaults: ``planners.string_model`` (the thesis ball, 13.9 g, taken as 20 mm
across; the thesis's 3D-printed cup has no published dimensions, so the cup is a plausible one for that ball).
"""

from __future__ import annotations

from typing import Annotated, Any

import typer

from planners.string_model import Ball, Cup, StringModel

from .options import number
from .plants.ball import STRING_LENGTH_M

_BALL, _CUP, _MODEL = Ball(), Cup(), StringModel(0.25)

# option → (low, high, low_open, unit): the one range of each value, for the options (parse time) and build_model
RANGES: dict[str, tuple[float, float, bool, str]] = {
    "--length": (*STRING_LENGTH_M, False, "m"), "--mass": (0.0, 10.0, True, "kg"), "--ball-radius": (0.0, 0.5, True, "m"),
    "--cup-radius": (0.0, 0.5, True, "m"), "--cup-depth": (0.0, 0.5, True, "m"), "--cup-rim": (0.0, 0.5, True, "m"),
    "--cup-wall": (0.0, 0.1, True, "m"), "--restitution": (0.0, 1.0, False, ""), "--retension": (0.0, 1.0, False, ""),
    "--friction": (0.0, 10.0, False, ""), "--drag": (0.0, 10.0, False, ""),
}  # fmt: skip


def model_number(option: str, help: str) -> Any:
    """A typer option of one of the model's values, validated at parse time over its range in RANGES."""
    low, high, low_open, unit = RANGES[option]
    return number(option, low=low, high=high, low_open=low_open, unit=unit, help=help)


def _axis(text: Any) -> tuple[float, float, float]:
    """typer ``parser`` of --cup-axis (see :func:`parse_axis`)."""
    from trajectories.errors import OptionError

    if isinstance(text, tuple):
        return text
    try:
        return parse_axis(str(text), "")
    except OptionError as exc:
        raise typer.BadParameter(str(exc).lstrip(": ")) from None


def _spec(text: Any) -> str:
    """typer ``parser`` of --cup: the spec's syntax, numbers and the ranges that do not depend on the string length
    (checked with the longest string); the command builds the model with its own length."""
    from trajectories.errors import OptionError

    if text is None:
        return None  # type: ignore[return-value]
    try:
        parse_cup_spec(str(text), RANGES["--length"][1], option="")
    except OptionError as exc:
        raise typer.BadParameter(str(exc).lstrip(": ")) from None
    return str(text)


BallRadiusOpt = Annotated[float, model_number("--ball-radius", help="Ball radius \\[m].")]
CupRadiusOpt = Annotated[float, model_number("--cup-radius", help="Inner radius of the cup \\[m].")]
CupDepthOpt = Annotated[float, model_number("--cup-depth", help="Inside depth of the cup, bottom to rim \\[m].")]
CupRimOpt = Annotated[
    float,
    model_number(
        "--cup-rim", help="Height of the rim above the string anchor at the cup's bottom \\[m] (≥ --cup-depth)."
    ),
]
CupWallOpt = Annotated[float, model_number("--cup-wall", help="Wall thickness \\[m].")]
CupAxisOpt = Annotated[
    tuple,
    typer.Option(
        "--cup-axis",
        parser=_axis,
        metavar="X,Y,Z",
        help="Opening direction of the cup in the flange frame x,y,z (-1,0,0: straight up at the thesis start pose).",
    ),
]
RestitutionOpt = Annotated[float, model_number("--restitution", help="Ball–cup restitution.")]
RetensionOpt = Annotated[
    float,
    model_number("--retension", help="Restitution of the jerk when the slack string tightens, 0 (inelastic) .. 1."),
]
FrictionOpt = Annotated[float, model_number("--friction", help="Ball–cup Coulomb friction.")]
DragOpt = Annotated[float, model_number("--drag", help="Drag coefficient C_d of the ball in air (0: no drag).")]
CupSpecOpt = Annotated[
    str | None,
    typer.Option(
        "--cup",
        parser=_spec,
        metavar="SPEC",
        help="Simulate the cup-and-ball toy: 'default', or comma-separated key=value in metres/SI — radius, depth, rim, "
        "wall, axis (x:y:z in the flange frame), ball (radius), mass, e (restitution), retension, mu, cd "
        "(`lbr plan cup-and-ball` prints the spec of its plan).",
    ),
]

SPEC_KEYS = ("radius", "depth", "rim", "wall", "axis", "ball", "mass", "e", "retension", "mu", "cd")


def build_model(
    length: float,
    mass: float = _BALL.mass,
    ball_radius: float = _BALL.radius,
    cup_radius: float = _CUP.inner_radius,
    cup_depth: float = _CUP.depth,
    cup_rim: float = _CUP.rim_height,
    cup_wall: float = _CUP.wall,
    cup_axis: tuple[float, float, float] = _CUP.axis,
    restitution: float = _MODEL.restitution,
    retension: float = _MODEL.retension,
    friction: float = _MODEL.friction,
    drag: float = _BALL.drag_coefficient,
) -> StringModel:
    """The string model from the options (SI units); OptionError naming the option when a value is out of range."""
    from trajectories.errors import OptionError

    from .options import check_number

    values = {"--length": length, "--mass": mass, "--ball-radius": ball_radius, "--cup-radius": cup_radius,
              "--cup-depth": cup_depth, "--cup-rim": cup_rim, "--cup-wall": cup_wall, "--restitution": restitution,
              "--retension": retension, "--friction": friction, "--drag": drag}  # fmt: skip
    for option, value in values.items():
        low, high, low_open, unit = RANGES[option]
        check_number(option, value, low, high, low_open=low_open, unit=unit)
    model = StringModel(
        length,
        Ball(ball_radius, mass, drag),
        Cup(cup_radius, cup_depth, cup_rim, cup_wall, cup_axis),
        retension,
        restitution,
        friction,
    )
    try:
        model.validate()
    except ValueError as exc:
        raise OptionError(str(exc)) from None
    return model


def parse_axis(text: str, option: str = "--cup-axis") -> tuple[float, float, float]:
    """'x,y,z' or 'x:y:z' → a direction (3 finite plain decimals, not all 0)."""
    import math

    from trajectories.errors import OptionError
    from trajectories.numbers import NotANumber, plain_float

    try:
        v = tuple(plain_float(p) for p in text.replace(":", ",").split(","))
    except NotANumber:
        v = ()
    if len(v) != 3 or not all(math.isfinite(x) for x in v) or math.hypot(*v) < 1e-6:
        raise OptionError(f"{option}: expected a direction x,y,z in the flange frame, got {text!r}")
    return v  # type: ignore[return-value]


def cup_spec(model: StringModel) -> str:
    """The ``--cup`` spec of a model (round trip with ``parse_cup_spec``)."""
    c, b = model.cup, model.ball
    axis = ":".join(f"{x:g}" for x in c.axis)
    return (
        f"radius={c.inner_radius:g},depth={c.depth:g},rim={c.rim_height:g},wall={c.wall:g},axis={axis},"
        f"ball={b.radius:g},mass={b.mass:g},e={model.restitution:g},retension={model.retension:g},"
        f"mu={model.friction:g},cd={b.drag_coefficient:g}"
    )


def parse_cup_spec(text: str, length: float, option: str = "--cup") -> StringModel:
    """A ``--cup`` spec ('default' or key=value,...) with the string ``length`` [m] → the model; OptionError."""
    from trajectories.errors import OptionError
    from trajectories.numbers import NotANumber, plain_float

    values: dict[str, object] = {}
    if text.strip().lower() != "default":
        for part in text.split(","):
            key, sep, value = part.partition("=")
            key = key.strip().lower()
            if not sep or key not in SPEC_KEYS:
                raise OptionError(f"{option}: expected key=value with keys {', '.join(SPEC_KEYS)}, got {part!r}")
            if key == "axis":
                values[key] = parse_axis(value, f"{option} axis")
                continue
            try:
                values[key] = plain_float(value)
            except NotANumber:
                raise OptionError(f"{option}: {key} must be a number, got {value!r}") from None
    names = {
        "radius": "cup_radius",
        "depth": "cup_depth",
        "rim": "cup_rim",
        "wall": "cup_wall",
        "axis": "cup_axis",
        "ball": "ball_radius",
        "mass": "mass",
        "e": "restitution",
        "retension": "retension",
        "mu": "friction",
        "cd": "drag",
    }
    try:
        return build_model(length, **{names[k]: v for k, v in values.items()})  # type: ignore[arg-type]
    except OptionError as exc:
        raise OptionError(f"{option}: {exc}") from None


def cup_model(spec: str | None, length: float | None) -> StringModel | None:
    """The simulated ball's string model with the cup of ``spec`` (--cup) for a string of ``length`` [m] (None
    without --cup); OptionError when there is no simulated ball."""
    from trajectories.errors import OptionError

    if spec is None:
        return None
    if not length:
        raise OptionError("--cup needs the simulated ball (--length > 0)")
    return parse_cup_spec(spec, length)
