"""`lbr plan cup-and-ball`: swing the ball up, let it go, catch it in the cup on the flange — as a joint CSV.

Thin wrapper over ``planners.catch_plan.plan_catch``; ``plan_catch_files`` is the in-process entry point. Exit 1
(after writing every output) when the nominal ball is not caught, a joint limit is violated, or less of the
robustness band than --min-success is caught; exit 2 on bad options.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Optional

import typer

if TYPE_CHECKING:
    import numpy as np

from ..cup_options import (
    _BALL,
    _CUP,
    _MODEL,
    BallRadiusOpt,
    CupAxisOpt,
    CupDepthOpt,
    CupRadiusOpt,
    CupRimOpt,
    CupWallOpt,
    DragOpt,
    FrictionOpt,
    RestitutionOpt,
    RetensionOpt,
    model_number,
)
from ..options import (
    DEFAULT_FLANGE,
    THESIS_Q_START,
    FlangeOpt,
    JointVector,
    JsonOpt,
    LimitsOpt,
    ToolOpt,
    joints,
    number,
)

PREDICTION_COLUMNS = ("t", "theta", "phase", "ball_x", "ball_y", "ball_z", "anchor_x", "anchor_y", "anchor_z")


CATCH_FLAGS = {
    "CatchRequest.max_time": "--max-time",
    "CatchRequest.q_start": "--q-start",
    "CatchRequest.length_tol": "--length-tol",
    "CatchRequest.mass_tol": "--mass-tol",
    "CatchRequest.min_success": "--min-success",
    "Cup.axis": "--cup-axis",
}
"""The settings :func:`planners.catch_plan.plan_catch` names in its messages → the options they come from."""


def plan_catch_files(
    length: float,
    *,
    out: Path,
    model_options: dict[str, Any] | None = None,
    prediction: Path | None = None,
    plot: Path | None = None,
    max_time: float | None = None,
    length_tol: float = 0.03,
    mass_tol: float = 0.2,
    timing: bool = True,
    min_success: float = 0.95,
    dt: float = 0.005,
    q_start: "str | np.ndarray" = THESIS_Q_START,  # 7 angles (text, or [rad])
    travel: float = 0.3,
    margin: float = 0.1,
    workers: int = 2,
    flange: str = DEFAULT_FLANGE,
    tool: str | None = None,
    limits: Path | None = None,
    progress=None,
) -> dict[str, Any]:
    """Plan a catch and write the joint CSV (+ prediction, plot); the JSON figures (with ``ok`` and ``failure``)."""
    from planners.catch_plan import CatchRequest, plan_catch
    from planners.swingup_fast import SearchSettings

    from ..cup_options import build_model
    from ..option_groups import settings_named
    from ..options import limits_from, make_robot, within_limits
    from ..outputs import guard_outputs
    from ..parsing import parse_joint_vector

    model = build_model(length, **(model_options or {}))
    _validate(max_time, length_tol, mass_tol, min_success, dt, travel, margin, workers)
    guard_outputs({"--limits": limits}, {"-o": out, "--prediction": prediction, "--plot": plot}, folders=True)
    lim = limits_from(limits)
    q0 = within_limits(parse_joint_vector(q_start, "--q-start"), lim, "--q-start")
    robot = make_robot(flange, tool)
    _check_axis(robot, model, q0)
    request = CatchRequest(
        model=model,
        q_start=tuple(float(v) for v in q0),
        dt=dt,
        max_time=max_time,
        length_tol=length_tol,
        mass_tol=mass_tol,
        timing=timing,
        min_success=min_success,
        travel=travel,
        limit_margin=margin,
        search=SearchSettings(popsize=6, maxiter=14, workers=int(workers)),
    )
    with settings_named(CATCH_FLAGS):  # the planner's messages name the options
        result = plan_catch(request, robot, lim, progress=progress)
    return _write_outputs(result, length, out, prediction, plot)


def _validate(max_time, length_tol, mass_tol, min_success, dt, travel, margin, workers) -> None:
    """OptionError naming the first option out of its range."""
    from ..options import check_number

    check_number("--max-time", max_time, 0.5, 30.0, unit="s")
    check_number("--length-tol", length_tol, 0.0, 0.2)
    check_number("--mass-tol", mass_tol, 0.0, 0.9)
    check_number("--min-success", min_success, 0.0, 1.0)
    check_number("--dt", dt, 1e-3, 0.02, unit="s")
    check_number("--max-travel", travel, 0.05, 0.5, unit="m")
    check_number("--margin", margin, 0.0, 1.0, high_open=True)
    check_number("--workers", workers, 1, 64)


def _write_outputs(result, length: float, out: Path, prediction: Path | None, plot: Path | None) -> dict[str, Any]:
    """Write the joint CSV and the outputs asked for (the predicted ball and anchor, the plot); the JSON figures, the
    failure naming the options."""
    import numpy as np

    from trajectories.csvio import write_joint_csv, write_table

    from ..cup_options import cup_spec
    from ..option_groups import name_text

    model = result.request.model
    write_joint_csv(out, result.trajectory)
    figures: dict[str, Any] = {"out": str(out), **result.figures(), "cup_spec": cup_spec(model)}
    if figures["failure"]:
        figures["failure"] = name_text(figures["failure"], CATCH_FLAGS)
    figures["rehearse"] = f"lbr execute {out} --length {length:g} --cup {cup_spec(model)} --log LOG.csv"
    if prediction is not None:
        run = result.prediction
        write_table(
            prediction,
            PREDICTION_COLUMNS,
            np.column_stack([run.t, run.theta_y, run.phase, run.position, run.pivot]),
            fmt=["%.6f", "%.9f", "%d"] + ["%.7f"] * 6,
        )
        figures["prediction"] = str(prediction)
    if plot is not None:
        from ..plots.catch import plot_catch

        plot_catch(result, plot)
        figures["plot"] = str(plot)
    figures["ok"] = result.failure() is None
    return figures


def _check_axis(robot, model, q0) -> None:
    """OptionError when the cup does not open upward at the start pose (--cup-axis, --q-start)."""
    import math

    from planners.catch_plan import MAX_AXIS_TILT, cup_axis_at_start
    from trajectories.errors import OptionError

    tilt = math.degrees(math.acos(max(-1.0, min(1.0, float(cup_axis_at_start(robot, model, q0)[2])))))
    if tilt > math.degrees(MAX_AXIS_TILT):
        raise OptionError(
            f"--cup-axis: the cup opens {tilt:.0f}° away from straight up at the start pose; the catch "
            f"needs it within {math.degrees(MAX_AXIS_TILT):.0f}° (--cup-axis, --q-start)"
        )


def _summary(rep, f: dict) -> None:
    def sec(v):
        return "—" if v is None else f"{v:.3f} s"

    rb = f["robustness"]
    rep.print(
        f"cup-and-ball: l = {f['length_m']:g} m, ball {1e3 * f['mass_kg']:.1f} g r = {1e3 * f['ball_radius_m']:.0f} mm, "
        f"cup r = {1e3 * f['cup']['inner_radius_m']:.0f} mm deep {1e3 * f['cup']['depth_m']:.0f} mm, "
        f"restitution {f['restitution']:g}"
    )
    if f["caught"]:
        rep.print(
            f"  caught: released {sec(f['release_time_s'])}, enters the cup {sec(f['catch_time_s'])} "
            f"(margin to the rim {1e3 * f['entry_margin_m']:.1f} mm, relative speed "
            f"{f['relative_entry_speed_m_s']:.2f} m/s), at rest in it {sec(f['rest_in_cup_s'])}"
        )
    else:
        rep.print(f"  NOT caught: {f['nominal_failure']}")
    w = rb["worst"]
    rep.print(
        f"  band (string ±{100 * rb['length_tolerance']:g} %, mass ±{100 * rb['mass_tolerance']:g} %, timing "
        f"±{1e3 * rb['timing_error_s']:g} ms; {rb['members']} cases): {100 * rb['success_fraction']:.0f} % caught; "
        f"worst l = {w['length_m']:.4f} m, m = {1e3 * w['mass_kg']:.1f} g, {1e3 * w['timing_s']:+.0f} ms: "
        f"{w['failure'] or 'caught, margin %.1f mm' % (1e3 * w['entry_margin_m'])}"
    )
    ratios = ", ".join(
        f"{k} {100 * v:.0f}%" for k, v in f["max_ratio"].items() if k in ("velocity", "acceleration", "jerk")
    )
    rep.print(f"  joints: peak/limit {ratios} — {'within limits' if f['limits_ok'] else 'LIMITS VIOLATED'}")
    rep.print(f"  wrote {f['out']} ({f['samples']} samples, {f['duration_s']:.2f} s) in {f['planning_time_s']:.1f} s")
    rep.print(f"  rehearse: {f['rehearse']}")


def cup_and_ball(
    out: Annotated[Path, typer.Option("-o", "--out", help="Joint trajectory to write: t,q1..q7 \\[s, rad].")],
    length: Annotated[
        float,
        model_number("--length", help="String length \\[m], anchor (the TCP, at the cup's bottom) to ball centre."),
    ],
    mass: Annotated[
        float, model_number("--mass", help="Ball mass \\[kg] (thesis 0.0139); it acts through the air drag.")
    ] = 0.0139,
    ball_radius: BallRadiusOpt = _BALL.radius,
    cup_radius: CupRadiusOpt = _CUP.inner_radius,
    cup_depth: CupDepthOpt = _CUP.depth,
    cup_rim: CupRimOpt = _CUP.rim_height,
    cup_wall: CupWallOpt = _CUP.wall,
    cup_axis: CupAxisOpt = "-1,0,0",
    restitution: RestitutionOpt = _MODEL.restitution,
    retension: RetensionOpt = _MODEL.retension,
    friction: FrictionOpt = _MODEL.friction,
    drag: DragOpt = _BALL.drag_coefficient,
    max_time: Annotated[
        Optional[float],
        number(
            "--max-time",
            low=0.5,
            high=30.0,
            unit="s",
            help=(
                "The ball must enter the cup within this time from rest \\[s] (default: within 3 s when a plan that "
                "quick catches --min-success of the band, else as soon as the band allows)."
            ),
        ),
    ] = None,
    length_tol: Annotated[
        float,
        number("--length-tol", low=0.0, high=0.2, help="Robustness band: string length ± this share (0.03 = ±3 %)."),
    ] = 0.03,
    mass_tol: Annotated[
        float, number("--mass-tol", low=0.0, high=0.9, help="Robustness band: ball mass ± this share.")
    ] = 0.2,
    timing: Annotated[
        bool,
        typer.Option(
            "--timing/--no-timing",
            help="Robustness band: the cup's motion after the release one FRI period early or late.",
        ),
    ] = True,
    min_success: Annotated[
        float,
        number("--min-success", low=0.0, high=1.0, help="Exit 1 unless at least this share of the band is caught."),
    ] = 0.95,
    dt: Annotated[
        float, number("--dt", low=1e-3, high=0.02, unit="s", help="Sample step \\[s] (the FRI period).")
    ] = 0.005,
    q_start: Annotated[
        JointVector,
        joints(
            "--q-start",
            help="Start configuration (7 angles, deg/rad suffixes; inside the position limits); thesis pose by default.",
        ),
    ] = THESIS_Q_START,
    max_travel: Annotated[
        float,
        number("--max-travel", low=0.05, high=0.5, unit="m", help="The pivot stays within ±this along base y \\[m]."),
    ] = 0.3,
    margin: Annotated[
        float,
        number(
            "--margin", low=0.0, high=1.0, high_open=True, help="Pivot bounds keep joints within (1 − margin)·limits."
        ),
    ] = 0.1,
    prediction: Annotated[
        Optional[Path],
        typer.Option(
            "--prediction",
            help="Write t,theta,phase,ball_x,ball_y,ball_z,anchor_x,anchor_y,anchor_z \\[s, rad, 0 taut / 1 slack / 2 in the cup, m].",
        ),
    ] = None,
    plot: Annotated[
        Optional[Path],
        typer.Option(
            "--plot",
            help="PNG: side view of the ball and cup paths with the phases, and the joint rates against their limits.",
        ),
    ] = None,
    workers: Annotated[
        int,
        number("--workers", low=1, high=64, integer=True, help="Processes evaluating swing-up candidates in parallel."),
    ] = 2,
    flange: FlangeOpt = DEFAULT_FLANGE,
    tool: ToolOpt = None,
    limits: LimitsOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Plan the cup-and-ball game from the ball hanging at rest to the ball resting in the cup (thesis ch. 5).

    The swing-up pumps along base y with the string taut, the pivot then cruises at a constant velocity or rests (both
    are planned, the one catching more of the band is kept) and the free swing releases the ball; the catch move
    brings the cup (an open cylinder on the flange, the string tied at its bottom) under the falling ball and stops. Chosen to catch across the band of string length, ball mass and timing, judged on the nonlinear
    string-and-cup model (one-sided string, impacts with the rim, walls and bottom) driven by the TCP path the written
    joints produce. JSON: caught, catch time, entry margin to the rim, relative entry speed, the band's success
    fraction and worst case. Exit 1 when no catch is found (saying where the ball went), a joint limit is violated
    (jerk included), or less than --min-success of the band is caught.
    """
    from trajectories.errors import PlanningError

    from ..console import Reporter

    rep = Reporter(json_out)
    options = dict(
        mass=mass,
        ball_radius=ball_radius,
        cup_radius=cup_radius,
        cup_depth=cup_depth,
        cup_rim=cup_rim,
        cup_wall=cup_wall,
        cup_axis=cup_axis,
        restitution=restitution,
        retension=retension,
        friction=friction,
        drag=drag,
    )
    with rep.progress("cup-and-ball: swing-up, catch, IK, judge", None) as update:
        figures = plan_catch_files(
            length,
            out=out,
            model_options=options,
            prediction=prediction,
            plot=plot,
            max_time=max_time,
            length_tol=length_tol,
            mass_tol=mass_tol,
            timing=timing,
            min_success=min_success,
            dt=dt,
            q_start=q_start,
            travel=max_travel,
            margin=margin,
            workers=workers,
            flange=flange,
            tool=tool,
            limits=limits,
            progress=update,
        )
    _summary(rep, figures)
    rep.emit(figures)
    if figures["failure"]:
        raise PlanningError(figures["failure"])


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    groups["plan"].command("cup-and-ball")(cup_and_ball)
