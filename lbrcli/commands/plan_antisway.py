"""`lbr plan anti-sway`: carry a ball on a string through turning points and stop with no swing left.

Option parsing and printing; the pipeline (plan, IK, check, sway prediction, files) is :mod:`lbrcli.antisway`.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Optional

import typer

import numpy as np

from ..option_groups import settings_named
from ..antisway import ANTISWAY_Q0, DEFAULT_BALL_RADIUS, DEFAULT_DT, DEFAULT_POINTS_TEXT, Z_RANGE, plan_anti_sway_files
from ..options import (DEFAULT_FLANGE, FlangeOpt, JointVector, JsonOpt, LimitsOpt, MarginOpt, Points, ToolOpt, angle, joints,
                       number)  # fmt: skip


FLAGS = {f"plan_anti_sway.{field}": flag for field, flag in (
    ("z", "--z"), ("points", "--points"), ("length", "--length"), ("a_max", "--a-max"), ("dt", "--dt"),
    ("shaper", "--shaper"), ("length_tolerance", "--length-tolerance"), ("margin", "--margin"),
    ("max_sway", "--max-sway"), ("ball_radius", "--ball-radius"), ("q0", "--q0"))}  # fmt: skip
"""The settings of :func:`lbrcli.antisway.plan_anti_sway` → the options they come from (its SettingErrors)."""


def plan_anti_sway_command(
    out: Annotated[Path, typer.Option("-o", "--out", help="Joint trajectory to write: t,q1..q7 \\[s, rad].")],
    length: Annotated[
        float,
        number(
            "--length",
            low=0.01,
            high=3.0,
            unit="m",
            help="String length from the pivot (flange + --tool) to the ball centre \\[m].",
        ),
    ],
    a_max: Annotated[
        float,
        number("--a-max", low=0, high=20, low_open=True, unit="m/s²", help="Maximum pivot acceleration \\[m/s²]."),
    ],
    points: Annotated[
        np.ndarray,
        typer.Option(
            "--points",
            parser=Points(),
            metavar="X0,Y0;X1,Y1;...",
            help="Start and turning points 'x0,y0;x1,y1;...' in the base frame \\[m]; default: a thesis-like layout.",
        ),
    ] = DEFAULT_POINTS_TEXT,
    z: Annotated[
        Optional[float],
        number("--z", low=Z_RANGE[0], high=Z_RANGE[1], unit="m", help="Flange (pivot) height \\[m]; default 0.45."),
    ] = None,
    shaper: Annotated[
        str,
        typer.Option(
            "--shaper",
            help="auto (default: per segment the quickest move robust to --length-tolerance, capped at the baseline's time; other designs as fallback), robust, accel (thesis baseline), box, zv, zvd, zvdd, mzv, ei, ei2, box-zv, box-zvd, box-ei.",
        ),
    ] = "auto",
    dt: Annotated[
        float, number("--dt", low=1e-4, high=0.05, unit="s", help="Joint sample step \\[s] (thesis FRI period 0.005).")
    ] = DEFAULT_DT,
    length_tolerance: Annotated[
        float,
        number(
            "--length-tolerance",
            low=0,
            high=0.9,
            high_open=True,
            help="Relative string-length uncertainty the plan must tolerate (0.2 = ±20 %); 0: nominal length only (fastest).",
        ),
    ] = 0.1,
    max_sway: Annotated[
        Optional[float],
        angle(
            "--max-sway",
            low_deg=0,
            high_deg=90,
            low_open=True,
            high_open=True,
            default_unit="deg",
            help="Largest tilt of the string during the move, for every length in the band \\[deg; a plain number is degrees, 'rad' suffix for radians]: a planning constraint of the default design, a check for all.",
        ),
    ] = None,
    obstacles: Annotated[
        Optional[Path],
        typer.Option(
            "--obstacles",
            help="CSV of boxes on the table: name,x_min,y_min,z_min,x_max,y_max,z_max \\[m, base frame]; the ball's predicted paths (string ±tolerance) must clear them.",
        ),
    ] = None,
    ball_radius: Annotated[
        float,
        number(
            "--ball-radius",
            low=0,
            high=1,
            high_open=True,
            unit="m",
            help="Ball radius for the obstacle clearance \\[m].",
        ),
    ] = DEFAULT_BALL_RADIUS,
    no_fallback: Annotated[
        bool, typer.Option("--no-fallback", help="With auto: do not try other designs when the default cannot plan.")
    ] = False,
    j_max: Annotated[
        Optional[float],
        number(
            "--j-max",
            low=0.1,
            high=1e4,
            unit="m/s³",
            help="Pivot jerk limit of the shaped profiles \\[m/s³]; default a_max/(0.04·T): jerk ramps of 4 % of the period.",
        ),
    ] = None,
    v_max: Annotated[
        Optional[float],
        number("--v-max", low=0.01, high=10, unit="m/s", help="Pivot speed limit \\[m/s]; default none."),
    ] = None,
    no_tune: Annotated[
        bool, typer.Option("--no-tune", help="Skip the per-segment nonlinear tuning of the period.")
    ] = False,
    task_out: Annotated[
        Optional[Path], typer.Option("--task-out", help="Planned pivot path t,x,y,z,qw,qx,qy,qz \\[s, m].")
    ] = None,
    prediction: Annotated[
        Optional[Path], typer.Option("--prediction", help="Predicted sway t,theta,phi,theta_x,theta_y \\[s, rad].")
    ] = None,
    plot: Annotated[
        Optional[Path], typer.Option("--plot", help="PNG: top view, pivot acceleration, predicted sway.")
    ] = None,
    q0: Annotated[
        Optional[JointVector],
        joints(
            "--q0",
            help=f"IK reference configuration (7 angles, deg/rad; inside the position limits); default {ANTISWAY_Q0}.",
        ),
    ] = None,
    margin: MarginOpt = 0.0,
    jerk: Annotated[bool, typer.Option("--jerk", help="Fail on joint jerk too (always reported).")] = False,
    flange: FlangeOpt = DEFAULT_FLANGE,
    tool: ToolOpt = None,
    limits: LimitsOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Anti-sway crane move through turning points, stopping at each with no swing left.

    The flange points straight down at height --z; the ball hangs --length below the pivot. The default design
    leaves little swing for any string length within ±--length-tolerance. Exit 1 when the plan exceeds the
    joint limits (naming the segment and the largest a_max that plans, verified), swings more than --max-sway,
    or the ball touches an obstacle (naming it and the time); with auto other designs are tried first. The plan
    is never re-timed.
    """
    from ..console import Reporter

    rep = Reporter(json_out)
    inputs = _plan_inputs(
        length,
        a_max,
        points,
        z,
        shaper,
        dt,
        length_tolerance=length_tolerance,
        max_sway=max_sway,
        obstacles=obstacles,
        ball_radius=ball_radius,
        no_fallback=no_fallback,
        j_max=j_max,
        v_max=v_max,
        no_tune=no_tune,
        q0=q0,
        margin=margin,
        jerk=jerk,
        flange=flange,
        tool=tool,
        limits=limits,
    )
    with rep.progress("IK", None) as update, settings_named(FLAGS):
        figs = plan_anti_sway_files(
            **inputs, out=out, task_out=task_out, prediction=prediction, plot=plot, progress=update
        )
    if figs["fallback"]:
        fb = figs["fallback"]
        rep.print(f"fallback: {fb['from']} could not plan ({fb['reason']}); used {fb['to']}")
    designs = ", ".join(f"{s['index']}:{s['design']}" for s in figs["segments"])
    rep.print(
        f"wrote {out}: {figs['samples']} samples, {figs['duration_s']:.3f} s (moving {figs['motion_s']:.3f} s; "
        f"thesis baseline {figs['baseline_motion_s']:.3f} s); shaper {figs['shaper']} [{designs}]"
    )
    rep.print(
        f"predicted sway: peak {figs['peak_sway_deg']:.2f}°, residual after the last stop "
        f"{figs['residual_sway_deg']:.3f}°; max IK error {figs['max_ik_error_m']:.1e} m"
    )
    if len(figs["band_lengths_m"]) > 1:
        rep.print(
            f"string {min(figs['band_lengths_m']):.3f}–{max(figs['band_lengths_m']):.3f} m "
            f"(±{figs['length_tolerance'] * 100:g} %): worst residual {figs['worst_residual_sway_deg']:.3f}°, "
            f"worst peak {figs['worst_peak_sway_deg']:.2f}°"
        )
    if figs["nearest_obstacle"] is not None:
        nb = figs["nearest_obstacle"]
        rep.print(
            f"obstacles: least clearance {figs['min_clearance_m'] * 1000:.1f} mm ({nb['name']} at t = {nb['t_s']:.2f} s)"
        )
    jr = figs["jerk_ratio"]
    rep.print(
        f"limits: {'OK' if figs['limits_ok'] else 'FAILED'}; peak joint jerk {jr * 100:.0f} % of the limit"
        + ("" if jr <= 1 or jerk else " (not enforced; --jerk to fail on it)")
    )
    for name in ("task_out", "prediction", "plot"):
        if figs[name] is not None:
            rep.print(f"{name.replace('_', ' ')}: {figs[name]}")
    rep.emit(figs)


def anti_sway_inputs(
    length: float,
    a_max: float,
    points: str = DEFAULT_POINTS_TEXT,
    z: float | None = None,
    shaper: str = "auto",
    dt: float = DEFAULT_DT,
    *,
    length_tolerance: float = 0.1,
    max_sway: str | None = None,
    obstacles: Path | None = None,
    ball_radius: float = DEFAULT_BALL_RADIUS,
    no_fallback: bool = False,
    j_max: float | None = None,
    v_max: float | None = None,
    no_tune: bool = False,
    q0: str | None = None,
    margin: float = 0.0,
    jerk: bool = False,
    flange: str = DEFAULT_FLANGE,
    tool: str | None = None,
    limits: Path | None = None,
) -> dict:
    """The options of `lbr plan anti-sway` as typed (text, or numbers as a study file gives them), checked by the
    command's own parse-time validators (:func:`lbrcli.options.parse_as_command`) → keyword arguments of
    :func:`lbrcli.antisway.plan_anti_sway`; OptionError/InputError (exit 2) on a bad one. ``lbr sweep`` calls it,
    so a study's run plans exactly what the command line would."""
    from ..options import parse_as_command

    typed = dict(length=length, a_max=a_max, points=points, z=z, shaper=shaper, dt=dt,
                 length_tolerance=length_tolerance, max_sway=max_sway, obstacles=obstacles, ball_radius=ball_radius,
                 no_fallback=no_fallback, j_max=j_max, v_max=v_max, no_tune=no_tune, q0=q0, margin=margin, jerk=jerk,
                 flange=flange, tool=tool, limits=limits)  # fmt: skip
    parsed = parse_as_command(plan_anti_sway_command, typed)
    return _plan_inputs(**parsed)


def _plan_inputs(
    length: float,
    a_max: float,
    points,
    z,
    shaper: str,
    dt: float,
    *,
    length_tolerance: float,
    max_sway: float | None,
    obstacles: Path | None,
    ball_radius: float,
    no_fallback: bool,
    j_max: float | None,
    v_max: float | None,
    no_tune: bool,
    q0,
    margin: float,
    jerk: bool,
    flange: str,
    tool,
    limits: Path | None,
) -> dict:
    """The parsed options (as the command's validators give them) → keyword arguments of
    :func:`lbrcli.antisway.plan_anti_sway`: the limits and obstacles read, --q0 checked against the limits."""
    from ..obstacle_file import read_obstacles
    from ..options import limits_from, within_limits

    lim = limits_from(limits)
    return dict(
        points=points,
        length=length,
        a_max=a_max,
        z=z,
        shaper=shaper,
        dt=dt,
        flange=flange,
        tool=tool,
        q0=within_limits(q0, lim, "--q0"),
        limits=lim,
        margin=margin,
        jerk=jerk,
        j_max=j_max,
        v_max=math.inf if v_max is None else v_max,
        length_tolerance=length_tolerance,
        tune=not no_tune,
        max_sway=max_sway,
        obstacles=read_obstacles(obstacles) if obstacles is not None else (),
        ball_radius=ball_radius,
        fallback=not no_fallback,
    )


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    groups["plan"].command("anti-sway")(plan_anti_sway_command)
