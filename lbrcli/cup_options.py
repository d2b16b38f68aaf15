"""The cup-and-ball toy on the command line: ball, cup and contact options, and the compact ``--cup`` spec.

`lbr plan cup-and-ball` takes them one by one (``--cup-radius`` …); `lbr execute`, `lbr sim` and `lbr track film`
take the same values as one ``--cup`` spec (``radius=0.03,depth=0.045,...``; ``default`` for the defaults), which
the plan prints for its rehearsal. Defaults: ``planners.string_model`` (the thesis ball, 13.9 g, taken as 20 mm
across; the thesis's 3D-printed cup has no published dimensions, so the cup is a plausible one for that ball).
"""

from __future__ import annotations

from typing import Annotated

import typer

from planners.string_model import Ball, Cup, StringModel

_BALL, _CUP, _MODEL = Ball(), Cup(), StringModel(0.25)

BallRadiusOpt = Annotated[float, typer.Option("--ball-radius", help="Ball radius \\[m].")]
CupRadiusOpt = Annotated[float, typer.Option("--cup-radius", help="Inner radius of the cup \\[m].")]
CupDepthOpt = Annotated[float, typer.Option("--cup-depth", help="Inside depth of the cup, bottom to rim \\[m].")]
CupRimOpt = Annotated[float, typer.Option("--cup-rim", help="Height of the rim above the string anchor at the cup's bottom \\[m] (≥ --cup-depth).")]
CupWallOpt = Annotated[float, typer.Option("--cup-wall", help="Wall thickness \\[m].")]
CupAxisOpt = Annotated[str, typer.Option("--cup-axis", help="Opening direction of the cup in the flange frame x,y,z (-1,0,0: straight up at the thesis start pose).")]
RestitutionOpt = Annotated[float, typer.Option("--restitution", help="Ball–cup restitution, 0..1.")]
RetensionOpt = Annotated[float, typer.Option("--retension", help="Restitution of the jerk when the slack string tightens, 0 (inelastic) .. 1.")]
FrictionOpt = Annotated[float, typer.Option("--friction", help="Ball–cup Coulomb friction.")]
DragOpt = Annotated[float, typer.Option("--drag", help="Drag coefficient C_d of the ball in air (0: no drag).")]
CupSpecOpt = Annotated[
    str | None,
    typer.Option(
        "--cup",
        help="Simulate the cup-and-ball toy: 'default', or comma-separated key=value in metres/SI — radius, depth, rim, "
        "wall, axis (x:y:z in the flange frame), ball (radius), mass, e (restitution), retension, mu, cd "
        "(`lbr plan cup-and-ball` prints the spec of its plan).",
    ),
]

SPEC_KEYS = ("radius", "depth", "rim", "wall", "axis", "ball", "mass", "e", "retension", "mu", "cd")


def build_model(length: float, mass: float = _BALL.mass, ball_radius: float = _BALL.radius,
                cup_radius: float = _CUP.inner_radius, cup_depth: float = _CUP.depth, cup_rim: float = _CUP.rim_height,
                cup_wall: float = _CUP.wall, cup_axis: tuple[float, float, float] = _CUP.axis,
                restitution: float = _MODEL.restitution, retension: float = _MODEL.retension,
                friction: float = _MODEL.friction, drag: float = _BALL.drag_coefficient) -> StringModel:
    """The string model from the options (SI units); OptionError naming the option when a value is out of range."""
    from trajectories.errors import OptionError

    from .options import check_number

    check_number("--length", length, 0.01, 5.0, unit="m")
    check_number("--mass", mass, 0.0, 10.0, low_open=True, unit="kg")
    check_number("--ball-radius", ball_radius, 0.0, 0.5, low_open=True, unit="m")
    check_number("--cup-radius", cup_radius, 0.0, 0.5, low_open=True, unit="m")
    check_number("--cup-depth", cup_depth, 0.0, 0.5, low_open=True, unit="m")
    check_number("--cup-rim", cup_rim, 0.0, 0.5, low_open=True, unit="m")
    check_number("--cup-wall", cup_wall, 0.0, 0.1, low_open=True, unit="m")
    check_number("--restitution", restitution, 0.0, 1.0)
    check_number("--retension", retension, 0.0, 1.0)
    check_number("--friction", friction, 0.0, 10.0)
    check_number("--drag", drag, 0.0, 10.0)
    model = StringModel(length, Ball(ball_radius, mass, drag), Cup(cup_radius, cup_depth, cup_rim, cup_wall, cup_axis),
                        retension, restitution, friction)
    try:
        model.validate()
    except ValueError as exc:
        raise OptionError(str(exc)) from None
    return model


def parse_axis(text: str, option: str = "--cup-axis") -> tuple[float, float, float]:
    """'x,y,z' or 'x:y:z' → a direction (3 finite numbers, not all 0)."""
    import math

    from trajectories.errors import OptionError

    try:
        v = tuple(float(p) for p in text.replace(":", ",").split(","))
    except ValueError:
        v = ()
    if len(v) != 3 or not all(math.isfinite(x) for x in v) or math.hypot(*v) < 1e-6:
        raise OptionError(f"{option}: expected a direction x,y,z in the flange frame, got {text!r}")
    return v  # type: ignore[return-value]


def cup_spec(model: StringModel) -> str:
    """The ``--cup`` spec of a model (round trip with ``parse_cup_spec``)."""
    c, b = model.cup, model.ball
    axis = ":".join(f"{x:g}" for x in c.axis)
    return (f"radius={c.inner_radius:g},depth={c.depth:g},rim={c.rim_height:g},wall={c.wall:g},axis={axis},"
            f"ball={b.radius:g},mass={b.mass:g},e={model.restitution:g},retension={model.retension:g},"
            f"mu={model.friction:g},cd={b.drag_coefficient:g}")


def parse_cup_spec(text: str, length: float, option: str = "--cup") -> StringModel:
    """A ``--cup`` spec ('default' or key=value,...) with the string ``length`` [m] → the model; OptionError."""
    from trajectories.errors import OptionError

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
                values[key] = float(value)
            except ValueError:
                raise OptionError(f"{option}: {key} must be a number, got {value!r}") from None
    names = {"radius": "cup_radius", "depth": "cup_depth", "rim": "cup_rim", "wall": "cup_wall", "axis": "cup_axis",
             "ball": "ball_radius", "mass": "mass", "e": "restitution", "retension": "retension", "mu": "friction",
             "cd": "drag"}
    try:
        return build_model(length, **{names[k]: v for k, v in values.items()})  # type: ignore[arg-type]
    except OptionError as exc:
        raise OptionError(f"{option}: {exc}") from None
