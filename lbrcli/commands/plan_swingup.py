"""`lbr plan swing-up`: swing the ball on its string up to θ_d (cup-and-ball), as a joint CSV for the robot.

Thin wrapper over ``planners.swingup.plan_swing_up``; ``plan_swing_up_files`` is the in-process entry point
(the demo calls it). Exit 1 (after writing every output) when θ_d is not reached, a joint limit is violated, or
the string goes slack with --taut; exit 2 on bad options.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any, Optional

import typer

import numpy as np

from ..options import (DEFAULT_FLANGE, THESIS_Q_START, FlangeOpt, JointVector, JsonOpt, LimitsOpt, ToolOpt, angle, choice,
                       joints, number)  # fmt: skip

PREDICTION_COLUMNS = ("t", "theta", "theta_planned")
FLAGS = {"SwingUpRequest.theta_d": "--theta-d", "SwingUpRequest.travel": "--max-travel", "SwingUpRequest.k_p": "--kp",
         "SwingUpRequest.k_d": "--kd", "SwingUpRequest.push": "--push", "EnergyParams.push": "--push",
         "EnergyParams.theta0": "--theta0"}  # fmt: skip
"""The settings the planners name in their messages → this command's options."""
SIDES = {"any": 0, "+y": 1, "-y": -1}


# Ranges of the numeric options: physical sense, and work that ends (a 1e6 m/s² push or a 1e-9 s step would
# integrate for hours or allocate gigabytes).
MAX_PUSH = 20.0  # [m/s²] about 2 g; the arm's pivot bounds along y are a few m/s²
MAX_DURATION = 600.0  # [s]
MAX_GAIN = 1e4


def _validate(
    length,
    mass,
    theta_d,
    method,
    theta0,
    dt,
    duration,
    travel,
    k_e,
    k_p,
    k_d,
    tolerance,
    margin,
    orientation,
    push,
    side="any",
    workers=2,
) -> None:
    from trajectories.errors import OptionError

    from ..options import check_number

    check_number("--length", length, 0.01, 5.0, unit="m")
    check_number("--mass", mass, 0.0, 100.0, low_open=True, unit="kg")
    check_number("--dt", dt, 1e-4, 0.02, unit="s")
    check_number("--duration", duration, 0.0, MAX_DURATION, low_open=True, unit="s")
    check_number("--max-travel", travel, 0.0, 1.0, low_open=True, unit="m")
    check_number("--ke", k_e, 0.0, MAX_GAIN, low_open=True)
    check_number("--kp", k_p, 0.0, MAX_GAIN, unit="1/s²")
    check_number("--kd", k_d, 0.0, MAX_GAIN, unit="1/s")
    check_number("--margin", margin, 0.0, 1.0, high_open=True)
    check_number("--push", push, -MAX_PUSH, MAX_PUSH, unit="m/s²")
    check_number("--workers", workers, 1, 64)
    checks = (
        (0 < theta_d < math.pi, f"--theta-d must be in (0, 180°), got {math.degrees(theta_d):g}°"),
        (method in ("energy", "fast"), f"--method must be energy or fast, got {method!r}"),
        (abs(theta0) < math.pi / 2, f"--theta0 must be within ±90°, got {math.degrees(theta0):g}°"),
        (0 <= tolerance < theta_d, f"--tolerance must be in [0, θ_d), got {math.degrees(tolerance):g}°"),
        (
            orientation in ("auto", "fixed", "follow"),
            f"--orientation must be auto, fixed or follow, got {orientation!r}",
        ),
        (side in SIDES, f"--side must be one of {', '.join(SIDES)}, got {side!r}"),
    )
    for ok, message in checks:
        if not ok:
            raise OptionError(message)


def plan_swing_up_files(
    length: float,
    mass: float,
    theta_d: float,
    method: str = "energy",
    *,
    out: Path,
    prediction: Path | None = None,
    plot: Path | None = None,
    task_out: Path | None = None,
    theta0: float = 0.0,
    push: float = 0.0,
    duration: float | None = None,
    dt: float = 0.005,
    q_start: str | np.ndarray = THESIS_Q_START,
    k_e: float = 1.7,
    k_p: float = 0.05,
    k_d: float = 0.05,
    travel: float = 0.3,
    taut: bool = False,
    tolerance: float = math.radians(2.0),
    margin: float = 0.1,
    orientation: str = "auto",
    flange: str = DEFAULT_FLANGE,
    tool: str | None = None,
    limits: Path | None = None,
    workers: int = 2,
    side: str = "any",
    strict: bool = False,
    progress=None,
) -> dict[str, Any]:
    """Plan a swing-up and write the joint CSV (+ prediction, task CSV, plot); return the JSON figures.

    Angles in rad, lengths in m, mass in kg, times in s. The figures carry ``ok`` and ``failure`` (the reason
    θ_d is not reached / limits are violated / the string goes slack with ``taut``); with ``strict`` a failure
    raises PlanningError after the files are written.
    """
    from planners.swingup import SwingUpRequest, plan_swing_up
    from planners.swingup_fast import SearchSettings
    from trajectories.errors import PlanningError

    from ..option_groups import settings_named
    from ..options import limits_from, make_robot, within_limits
    from ..outputs import guard_outputs, require_folders
    from ..parsing import parse_joint_vector

    _validate(length, mass, theta_d, method, theta0, dt, duration, travel, k_e, k_p, k_d, tolerance, margin,
              orientation, push, side, workers)  # fmt: skip
    guard_outputs({"--limits": limits}, {"-o": out, "--prediction": prediction, "--plot": plot, "--task-out": task_out})
    require_folders({"-o": out, "--prediction": prediction, "--plot": plot, "--task-out": task_out})
    robot, lim = make_robot(flange, tool), limits_from(limits)
    q0 = within_limits(parse_joint_vector(q_start, "--q-start"), lim, "--q-start")
    request = SwingUpRequest(
        length=length,
        mass=mass,
        theta_d=theta_d,
        method=method,
        q_start=tuple(float(v) for v in q0),
        orientation=None if orientation == "auto" else orientation,
        travel=travel,
        dt=dt,
        duration=duration,
        tolerance=tolerance,
        theta0=theta0,
        push=push,
        k_e=k_e,
        k_p=k_p,
        k_d=k_d,
        taut=taut,
        limit_margin=margin,
        search=SearchSettings(workers=int(workers)),
        side=SIDES[side],
    )
    with settings_named(FLAGS):  # the planners' hints name the options
        result = plan_swing_up(request, robot, lim, progress=progress)
    figures = _write_outputs(result, robot, out, prediction, task_out, plot)
    failure = result.failure()
    figures["ok"], figures["failure"] = failure is None, failure
    if strict and failure:
        raise PlanningError(failure)
    return figures


def _write_outputs(result, robot, out: Path, prediction: Path | None, task_out: Path | None, plot: Path | None) -> dict:
    """Write the joint CSV and the outputs asked for (the predicted swing, the flange's task path, the plot); the
    figures with their paths."""
    from trajectories.csvio import write_joint_csv, write_table, write_task_csv
    from trajectories.poses import quaternions_from_matrices
    from trajectories.trajectory import TaskTrajectory

    write_joint_csv(out, result.trajectory)
    figures = {"out": str(out), **result.figures()}
    if prediction is not None:
        ver = result.verification
        planned = np.interp(ver.t, result.plan.t, result.plan.theta)
        write_table(
            prediction, PREDICTION_COLUMNS, np.column_stack([ver.t, ver.theta, planned]), fmt=["%.6f", "%.9f", "%.9f"]
        )
        figures["prediction"] = str(prediction)
    if task_out is not None:
        pos, rot = robot.fk_path(result.trajectory.q)
        write_task_csv(
            task_out, TaskTrajectory(t=result.trajectory.t, position=pos, quaternion=quaternions_from_matrices(rot))
        )
        figures["task_out"] = str(task_out)
    if plot is not None:
        from ..plots.swingup import plot_swingup

        plot_swingup(result, plot)
        figures["plot"] = str(plot)
    return figures


def _summary(rep, f: dict) -> None:
    def deg(v):
        return "—" if v is None else f"{v:.1f}°"

    def sec(v):
        return "never" if v is None else f"{v:.3f} s"

    c = f["claimed"]
    rep.print(
        f"swing-up ({f['method']}, pivot orientation {f['orientation']}): l = {f['length_m']:g} m, "
        f"m = {f['mass_kg']:g} kg, θ_d = {f['theta_d_deg']:.1f}°"
    )
    rep.print(
        f"  verified (ball simulated under the joint path): max |θ| {deg(f['max_theta_deg'])}, reached at "
        f"{sec(f['t_reach_s'])}; planned: {deg(c['max_theta_deg'])} at {sec(c['t_reach_s'])} "
        f"(|Δθ| ≤ {c['max_theta_difference_deg']:.2f}°)"
    )
    b = f["bounds"]
    rep.print(
        f"  pivot: travel ±{f['max_travel_m']:.3f} m, at rest from {f['t_rest_s']:.3f} s; bounds "
        f"{b['v_max_m_s']:.2f} m/s, {b['a_max_m_s2']:.2f} m/s², {b['j_max_m_s3']:.0f} m/s³"
    )
    slack = "" if f["taut"] else f", slack from {f['first_slack_s']:.3f} s"
    rep.print(
        f"  string: min tension/mass {f['min_tension_margin']:.2f} m/s² ({'taut' if f['taut'] else 'NOT taut'}{slack})"
    )
    if f.get("highest_taut_theta_deg") is not None:
        rep.print(f"  highest angle reachable taut: {f['highest_taut_theta_deg']:.1f}°")
    ratios = ", ".join(f"{k} {100 * v:.0f}%" for k, v in f["max_ratio"].items())
    rep.print(f"  joints: peak/limit {ratios} — {'within limits' if f['limits_ok'] else 'LIMITS VIOLATED'}")
    for note in f.get("notes", []):
        rep.print(f"  note: {note}")
    rep.print(f"  wrote {f['out']} ({f['samples']} samples, {f['duration_s']:.3f} s) in {f['planning_time_s']:.2f} s")


def swing_up(
    out: Annotated[Path, typer.Option("-o", "--out", help="Joint trajectory to write: t,q1..q7 \\[s, rad].")],
    length: Annotated[
        float, number("--length", low=0.01, high=5.0, unit="m", help="String length l \\[m] (pivot to ball centre).")
    ],
    mass: Annotated[
        float,
        number(
            "--mass",
            low=0,
            high=100,
            low_open=True,
            unit="kg",
            help="Ball mass m \\[kg] (E is in joules, as in the thesis).",
        ),
    ],
    theta_d: Annotated[
        float,
        angle(
            "--theta-d",
            low_deg=0,
            high_deg=180,
            low_open=True,
            high_open=True,
            help="Target apex angle from the hanging vertical (e.g. 115deg).",
        ),
    ],
    method: Annotated[
        str,
        choice(
            "--method",
            choices=("energy", "fast"),
            help="energy: thesis energy shaping; fast: limit-aware bang-bang pumping.",
        ),
    ] = "energy",
    theta0: Annotated[
        float,
        angle(
            "--theta0",
            low_deg=-90,
            high_deg=90,
            low_open=True,
            high_open=True,
            help="Initial ball angle toward +y (e.g. 0.1 or 5deg); the energy law needs ≠ 0 or --push.",
        ),
    ] = "0",
    push: Annotated[
        float,
        number(
            "--push",
            low=-MAX_PUSH,
            high=MAX_PUSH,
            unit="m/s²",
            help="energy: amplitude \\[m/s²] of a one-period sine start push at the natural period.",
        ),
    ] = 0.0,
    ke: Annotated[
        float,
        number("--ke", low=0, high=MAX_GAIN, low_open=True, help="energy: gain k_E on θ̇·cos θ·(E − E_d) \\[E in J]."),
    ] = 1.7,
    kp: Annotated[
        float, number("--kp", low=0, high=MAX_GAIN, unit="1/s²", help="energy: position gain k_p \\[1/s²].")
    ] = 0.05,
    kd: Annotated[
        float, number("--kd", low=0, high=MAX_GAIN, unit="1/s", help="energy: velocity gain k_d \\[1/s].")
    ] = 0.05,
    duration: Annotated[
        Optional[float],
        number(
            "--duration",
            low=0,
            high=MAX_DURATION,
            low_open=True,
            unit="s",
            help="Longest pumping time \\[s] (default 60 energy, 10 fast); then the pivot stops.",
        ),
    ] = None,
    dt: Annotated[
        float,
        number(
            "--dt",
            low=1e-4,
            high=0.02,
            unit="s",
            help="Sample step \\[s] (FRI period; 0.005 as in the thesis, or 0.001).",
        ),
    ] = 0.005,
    q_start: Annotated[
        JointVector,
        joints("--q-start", help="Start configuration (7 angles, deg/rad suffixes); thesis pose by default."),
    ] = THESIS_Q_START,
    max_travel: Annotated[
        float,
        number(
            "--max-travel",
            low=0,
            high=1,
            low_open=True,
            unit="m",
            help="The pivot must stay within ±this along base y \\[m].",
        ),
    ] = 0.3,
    taut: Annotated[
        bool,
        typer.Option(
            "--taut",
            help="Keep the string taut (tension/mass ≥ 0.5 m/s²) until θ_d is reached; report the highest angle the string holds taut.",
        ),
    ] = False,
    tolerance: Annotated[
        float,
        angle(
            "--tolerance",
            low_deg=0,
            high_deg=180,
            high_open=True,
            help="θ_d counts as reached at θ_d − tolerance (energy shaping is asymptotic; it aims at θ_d − tolerance/2).",
        ),
    ] = "2deg",
    margin: Annotated[
        float,
        number("--margin", low=0, high=1, high_open=True, help="Pivot bounds keep joints within (1 − margin)·limits."),
    ] = 0.1,
    orientation: Annotated[
        str,
        choice(
            "--orientation",
            choices=("auto", "fixed", "follow"),
            metavar="auto|fixed|follow",
            help="Pivot orientation: fixed (thesis T_start), follow (turns with y about the vertical, well conditioned), auto (fixed for energy, follow for fast).",
        ),
    ] = "auto",
    prediction: Annotated[
        Optional[Path],
        typer.Option("--prediction", help="Write t,theta\\[,theta_planned] \\[s, rad] of the verification simulation."),
    ] = None,
    plot: Annotated[
        Optional[Path],
        typer.Option("--plot", help="PNG: θ(t), pivot x(t) and u(t), tension margin, joint rates vs limits."),
    ] = None,
    task_out: Annotated[
        Optional[Path], typer.Option("--task-out", help="Write the TCP path t,x,y,z,qw,qx,qy,qz \\[s, m].")
    ] = None,
    workers: Annotated[
        int,
        number("--workers", low=1, high=64, integer=True, help="fast: processes evaluating candidates in parallel."),
    ] = 2,
    side: Annotated[
        str, choice("--side", choices=tuple(SIDES), help="Reach θ_d toward +y, -y or any (a centred plan is mirrored).")
    ] = "any",
    flange: FlangeOpt = DEFAULT_FLANGE,
    tool: ToolOpt = None,
    limits: LimitsOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Plan a swing-up of the ball to θ_d along base y from the thesis start pose (θ positive toward +y).

    Every plan ends with the pivot at rest. The figures are those of a nonlinear ball simulation driven by
    the TCP path the written joints produce (the plan's own claim under "claimed"). Exit 1 when θ_d is not
    reached, a joint limit (position, velocity, acceleration; jerk too for --method fast) is violated, or the
    string goes slack with --taut.
    """
    from trajectories.errors import PlanningError

    from ..console import Reporter

    rep = Reporter(json_out)
    with rep.progress("swing-up: plan, IK, verify", None) as update:
        figures = plan_swing_up_files(
            length,
            mass,
            theta_d,
            method,
            out=out,
            prediction=prediction,
            plot=plot,
            task_out=task_out,
            theta0=theta0,
            push=push,
            duration=duration,
            dt=dt,
            q_start=q_start,
            k_e=ke,
            k_p=kp,
            k_d=kd,
            travel=max_travel,
            taut=taut,
            tolerance=tolerance,
            margin=margin,
            orientation=orientation,
            flange=flange,
            tool=tool,
            limits=limits,
            workers=workers,
            side=side,
            progress=update,
        )
    _summary(rep, figures)
    rep.emit(figures)
    if figures["failure"]:
        raise PlanningError(figures["failure"])


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    groups["plan"].command("swing-up")(swing_up)
