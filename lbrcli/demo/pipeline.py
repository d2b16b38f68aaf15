"""The demo's steps: each one is the `lbr` command a user would type (run as a subprocess with --json), so the
demo exercises exactly the user's path and `summary.md` can list the commands to reproduce every file.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

BALL_LENGTH = 0.25  # [m] string of the demo ball (thesis l = 0.25 m)
BALL_MASS = 0.0139  # [kg] thesis ball
CRANE_A_MAX = 2.0  # [m/s²]
SWING_THETA_D = "115deg"
CUP = "default"  # the cup-and-ball toy of the catch (`lbr plan cup-and-ball` defaults)


@dataclass
class StepResult:
    name: str
    argv: list[str] | None
    returncode: int
    seconds: float
    figures: dict[str, Any] = field(default_factory=dict)
    error: str = ""

    @property
    def ok(self) -> bool:
        return self.returncode == 0


@dataclass(frozen=True)
class Step:
    name: str
    title: str
    argv: tuple[str, ...] | None = None  # an `lbr` command line
    action: Callable[[Path, dict[str, StepResult]], dict[str, Any]] | None = None  # in-process work
    needs: tuple[str, ...] = ()


def run_lbr_step(step: Step, out: Path) -> StepResult:
    """Run `lbr <argv> --json` in ``out``; its stderr (the human report) goes to ``out/logs/<step>.txt``."""
    argv = ["lbr", *step.argv, "--json"]
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "lbrcli", *argv[1:]], cwd=out, capture_output=True, text=True)
    seconds = time.perf_counter() - t0
    (out / "logs").mkdir(exist_ok=True)
    (out / "logs" / f"{step.name}.txt").write_text(f"$ {' '.join(argv)}\n{proc.stderr}")
    figures: dict[str, Any] = {}
    try:
        figures = json.loads(proc.stdout) if proc.stdout.strip() else {}
    except json.JSONDecodeError:
        pass
    error = ""
    if proc.returncode != 0:
        lines = [l for l in proc.stderr.strip().splitlines() if l.strip()]
        error = lines[-1] if lines else f"exit {proc.returncode}"
    return StepResult(step.name, argv, proc.returncode, seconds, figures, error)


def _tracking_error(out: Path, results: dict[str, StepResult]) -> dict[str, Any]:
    """Tracked centre and θ against what was drawn (the ground truth of the rendered video)."""
    import numpy as np

    from trajectories.csvio import read_table

    track = read_table(
        out / "swingup_track.csv",
        ("t", "frame", "u", "v", "found"),
        time="increasing",
        nan_columns=("u", "v", "theta", "pivot_u", "pivot_v"),
    )
    truth = np.loadtxt(out / "swingup_video_truth.csv", delimiter=",", skiprows=1)
    n = min(len(truth), len(track.data))
    found = track.column("found")[:n] > 0.5
    du = track.column("u")[:n][found] - truth[:n, 1][found]
    dv = track.column("v")[:n][found] - truth[:n, 2][found]
    theta = track.column("theta")[:n]
    with_theta = found & np.isfinite(theta)  # no θ where the string was slack (the ball flying near the pivot)
    dth = np.degrees(theta[with_theta] - truth[:n, 5][with_theta])
    return {
        "found_fraction": float(found.mean()),
        "centre_rms_px": float(np.sqrt(np.mean(du**2 + dv**2))),
        "theta_rms_deg": float(np.sqrt(np.mean(dth**2))),
        "theta_max_deg": float(np.abs(dth).max()),
        "theta_fraction": float(with_theta.mean()),
    }


def lbr_argv(*words: str, **options: str | bool) -> tuple[str, ...]:
    """An `lbr` command line: ``words``, then each option in order (``a_max="2"`` → ``--a-max 2``, one letter → ``-o``;
    True: the bare flag, False: left out)."""
    argv = list(words)
    for key, value in options.items():
        flag = ("-" if len(key) == 1 else "--") + key.replace("_", "-")
        if value is True:
            argv.append(flag)
        elif value is not False:
            argv += [flag, value]
    return tuple(argv)


def _execute_on_sim(csv: str, realtime: bool, settle: str, log: str, plot: str, **extra: str) -> tuple[str, ...]:
    """`lbr execute` of a demo file on the built-in simulator (port 0, lenient quality, the demo ball)."""
    return lbr_argv(
        "execute",
        csv,
        port="0",
        realtime=realtime,
        sim_lenient=True,
        length=str(BALL_LENGTH),
        **extra,
        settle=settle,
        log=log,
        plot=plot,
    )


def _crane_steps(realtime: bool) -> list[Step]:
    """Plan, check and execute the crane move twice: plain acceleration profile, then input-shaped."""
    steps = []
    for name, shaper in (("baseline", "accel"), ("shaped", "auto")):
        plan = lbr_argv(
            "plan",
            "anti-sway",
            length=str(BALL_LENGTH),
            a_max=str(CRANE_A_MAX),
            shaper=shaper,
            o=f"crane_{name}.csv",
            prediction=f"crane_{name}_prediction.csv",
            task_out=f"crane_{name}_pivot.csv",
            plot=f"crane_{name}_plan.png",
        )
        check = lbr_argv("check", f"crane_{name}.csv", plot=f"crane_{name}_check.png")
        execute = _execute_on_sim(
            f"crane_{name}.csv", realtime, "3", f"crane_{name}_log.csv", f"crane_{name}_execution.png"
        )
        steps += [
            Step(f"plan_{name}", f"plan crane move ({shaper})", plan),
            Step(f"check_{name}", f"check crane move ({shaper})", check, needs=(f"plan_{name}",)),
            Step(
                f"execute_{name}", f"execute crane move ({shaper}) on the simulator", execute, needs=(f"check_{name}",)
            ),
        ]
    return steps


def _swing_up_steps(realtime: bool) -> list[Step]:
    """Plan and execute the swing-up, film the simulated ball, track it and compare with the model."""
    L = str(BALL_LENGTH)
    plan = lbr_argv(
        "plan",
        "swing-up",
        method="fast",
        length=L,
        mass=str(BALL_MASS),
        theta_d=SWING_THETA_D,
        side="+y",
        o="swingup.csv",
        prediction="swingup_prediction.csv",
        plot="swingup_plan.png",
    )
    execute = _execute_on_sim("swingup.csv", realtime, "1.5", "swingup_log.csv", "swingup_execution.png")
    film = lbr_argv("track", "film", "swingup_log.csv", o="swingup.mp4", length=L, truth="swingup_video_truth.csv")
    track = lbr_argv(
        "track",
        "video",
        "swingup.mp4",
        o="swingup_track.csv",
        pivot_color="green",
        plot="swingup_track.png",
        preview="swingup_preview.mp4",
    )
    compare = lbr_argv("compare", "swingup_prediction.csv", "swingup_track.csv", plot="swingup_compare.png")
    view = lbr_argv(
        "view",
        "swingup.csv",
        "swingup_log.csv",
        "swingup_prediction.csv",
        "swingup_track.csv",
        length=L,
        o="swingup_view.html",
    )
    return [
        Step("plan_swingup", "plan swing-up (fast)", plan),
        Step("execute_swingup", "execute swing-up on the simulator", execute, needs=("plan_swingup",)),
        Step("film", "film the simulated ball (render swingup.mp4)", film, needs=("execute_swingup",)),
        Step("track", "track the ball in the video", track, needs=("film",)),
        Step("tracking_error", "tracked ball vs what was drawn", action=_tracking_error, needs=("track",)),
        Step("compare", "compare model and experiment", compare, needs=("track",)),
        Step("view", "3D replay of the swing-up (one offline HTML file)", view, needs=("track",)),
    ]


def _catch_steps(realtime: bool) -> list[Step]:
    """Plan and execute the cup-and-ball catch, film it with the cup, track the flight and compare."""
    L = str(BALL_LENGTH)
    plan = lbr_argv(
        "plan",
        "cup-and-ball",
        length=L,
        min_success="0",
        o="catch.csv",
        prediction="catch_prediction.csv",
        plot="catch_plan.png",
    )
    execute = _execute_on_sim("catch.csv", realtime, "1", "catch_log.csv", "catch_execution.png", cup=CUP)
    film = lbr_argv(
        "track",
        "film",
        "catch_log.csv",
        o="catch.mp4",
        length=L,
        cup=CUP,
        size="960x540",
        truth="catch_video_truth.csv",
    )
    track = lbr_argv("track", "video", "catch.mp4", o="catch_track.csv", pivot_color="green")
    compare = lbr_argv("compare", "catch_prediction.csv", "catch_track.csv", plot="catch_compare.png")
    return [
        Step("plan_catch", "plan the cup-and-ball catch", plan),
        Step(
            "execute_catch",
            "execute the catch on the simulator (ball and cup simulated)",
            execute,
            needs=("plan_catch",),
        ),
        Step("film_catch", "film the catch (render catch.mp4 with the cup)", film, needs=("execute_catch",)),
        Step("track_catch", "track the ball through the flight", track, needs=("film_catch",)),
        Step("compare_catch", "compare model and experiment, positions in the flight", compare, needs=("track_catch",)),
    ]


def demo_steps() -> list[Step]:
    """Every step of the demo in order: the crane move, the swing-up with its video, the catch."""
    from lbrcli.fri.realtime import permitted

    realtime = permitted()  # steadier where the system grants it; refused (exit 2) elsewhere
    return _crane_steps(realtime) + _swing_up_steps(realtime) + _catch_steps(realtime)


def run_demo(
    out: Path,
    on_step: Callable[[Step, int], None] | None = None,
    on_done: Callable[[Step, StepResult], None] | None = None,
) -> dict[str, StepResult]:
    """Run every step in order (skipping those whose inputs failed); results by step name."""
    out.mkdir(parents=True, exist_ok=True)
    results: dict[str, StepResult] = {}
    for k, step in enumerate(demo_steps()):
        if on_step:
            on_step(step, k)
        failed = [n for n in step.needs if n in results and not results[n].ok]
        if failed:
            res = StepResult(step.name, None, 1, 0.0, error=f"skipped: {', '.join(failed)} failed")
        elif step.argv is not None:
            res = run_lbr_step(step, out)
        else:
            t0 = time.perf_counter()
            try:
                res = StepResult(step.name, None, 0, 0.0, step.action(out, results))
            except Exception as exc:  # a demo step failing must not hide the others' results
                res = StepResult(step.name, None, 1, 0.0, error=f"{type(exc).__name__}: {exc}")
            res.seconds = time.perf_counter() - t0
        results[step.name] = res
        if on_done:
            on_done(step, res)
    return results


def _get(results: dict[str, StepResult], step: str, key: str) -> Any:
    r = results.get(step)
    return None if r is None else r.figures.get(key)


def summary_figures(results: dict[str, StepResult]) -> dict[str, Any]:
    """The demo's headline figures (None where a step failed)."""
    f: dict[str, Any] = {}
    for name in ("baseline", "shaped"):
        f[f"crane_{name}"] = {
            "duration_s": _get(results, f"plan_{name}", "duration_s"),
            "predicted_peak_sway_deg": _get(results, f"plan_{name}", "peak_sway_deg"),
            "predicted_residual_sway_deg": _get(results, f"plan_{name}", "residual_sway_deg"),
            "executed_peak_sway_deg": _get(results, f"execute_{name}", "max_ball_theta_deg"),
            "executed_residual_sway_deg": _get(results, f"execute_{name}", "residual_ball_theta_deg"),
            "limits_ok": _get(results, f"check_{name}", "limits_ok"),
            "fri_cycles": _get(results, f"execute_{name}", "cycles"),
            "fri_missed": _get(results, f"execute_{name}", "missed"),
        }
    f["swingup"] = {
        "max_theta_deg": _get(results, "plan_swingup", "max_theta_deg"),
        "t_reach_s": _get(results, "plan_swingup", "t_reach_s"),
        "reached": _get(results, "plan_swingup", "reached"),
        "executed_max_theta_deg": _get(results, "execute_swingup", "max_ball_theta_deg"),
        "fri_cycles": _get(results, "execute_swingup", "cycles"),
        "fri_missed": _get(results, "execute_swingup", "missed"),
    }
    rob = _get(results, "plan_catch", "robustness") or {}
    cup = _get(results, "execute_catch", "cup") or {}
    flight = _get(results, "compare_catch", "slack_position") or {}
    f["catch"] = {
        "caught": _get(results, "plan_catch", "caught"),
        "catch_time_s": _get(results, "plan_catch", "catch_time_s"),
        "entry_margin_m": _get(results, "plan_catch", "entry_margin_m"),
        "relative_entry_speed_m_s": _get(results, "plan_catch", "relative_entry_speed_m_s"),
        "band_success": rob.get("success_fraction"),
        "executed_entered_s": cup.get("entered_after_start_s"),
        "executed_stayed": cup.get("stayed"),
        "flight_position_rms_m": flight.get("rms_m"),
        "fri_missed": _get(results, "execute_catch", "missed"),
    }
    f["tracking"] = dict(results["tracking_error"].figures) if "tracking_error" in results else {}
    f["compare"] = {k: _get(results, "compare", k) for k in ("lag_s", "rms_deg", "max_deg", "overlap_s")}
    missed = [f[k]["fri_missed"] for k in ("crane_baseline", "crane_shaped", "swingup", "catch")]
    f["fri_missed_total"] = (
        sum(m for m in missed if isinstance(m, (int, float)))
        if any(isinstance(m, (int, float)) for m in missed)
        else None
    )
    f["steps_failed"] = [n for n, r in results.items() if not r.ok]
    f["ok"] = not f["steps_failed"]
    return f


def fmt(value: Any, spec: str = ".2f", unit: str = "") -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "—"
    if isinstance(value, bool):
        return "yes" if value else "no"
    return f"{value:{spec}}{unit}"


def summary_rows(f: dict[str, Any]) -> list[tuple[str, str]]:
    """(figure, value) rows of the closing table."""
    b, s, sw, tr, cp = f["crane_baseline"], f["crane_shaped"], f["swingup"], f["tracking"], f["compare"]
    ct = f["catch"]
    found = tr.get("found_fraction")
    missed = f["fri_missed_total"]
    return [
        ("crane duration, baseline / shaped [s]", f"{fmt(b['duration_s'])} / {fmt(s['duration_s'])}"),
        (
            "crane peak sway (simulated), baseline / shaped [°]",
            f"{fmt(b['executed_peak_sway_deg'])} / {fmt(s['executed_peak_sway_deg'])}",
        ),
        (
            "crane residual sway (simulated), baseline / shaped [°]",
            f"{fmt(b['executed_residual_sway_deg'], '.3f')} / {fmt(s['executed_residual_sway_deg'], '.3f')}",
        ),
        (
            "crane residual sway (plan's prediction), baseline / shaped [°]",
            f"{fmt(b['predicted_residual_sway_deg'], '.3f')} / {fmt(s['predicted_residual_sway_deg'], '.3f')}",
        ),
        (
            "swing-up max θ, planned / simulated [°]",
            f"{fmt(sw['max_theta_deg'], '.1f')} / {fmt(sw['executed_max_theta_deg'], '.1f')}",
        ),
        ("swing-up time to θ_d − 2° [s]", fmt(sw["t_reach_s"])),
        (
            "tracking: found / centre RMS / θ RMS",
            f"{fmt(100 * found if found is not None else None, '.1f', ' %')} / "
            f"{fmt(tr.get('centre_rms_px'), '.2f', ' px')} / {fmt(tr.get('theta_rms_deg'), '.3f', '°')}",
        ),
        ("model vs experiment: θ RMS / max error [°]", f"{fmt(cp['rms_deg'])} / {fmt(cp['max_deg'])}"),
        ("model vs experiment: lag [s]", fmt(cp["lag_s"], ".3f")),
        ("cup-and-ball: caught / enters the cup (plan) [s]", f"{fmt(ct['caught'])} / {fmt(ct['catch_time_s'])}"),
        (
            "cup-and-ball: share of the robustness band caught",
            fmt(100 * ct["band_success"] if ct["band_success"] is not None else None, ".0f", " %"),
        ),
        (
            "cup-and-ball executed: enters (after the first row) [s] / stayed",
            f"{fmt(ct['executed_entered_s'])} / {fmt(ct['executed_stayed'])}",
        ),
        (
            "cup-and-ball: flight position model vs video, RMS",
            fmt(1e3 * ct["flight_position_rms_m"] if ct["flight_position_rms_m"] is not None else None, ".1f", " mm"),
        ),
        ("FRI cycles missed (all runs)", fmt(missed, ".0f")),
    ]


def write_summary(out: Path, results: dict[str, StepResult], f: dict[str, Any], seconds: float) -> Path:
    """`summary.md`: the table, every step with its command, time and outcome, and the files."""
    lines = [
        "# lbr demo",
        "",
        f"The user's loop on the built-in FRI simulator, {seconds:.0f} s in all.",
        "",
        "| figure | value |",
        "|---|---|",
    ]
    lines += [f"| {a} | {b} |" for a, b in summary_rows(f)]
    lines += ["", "## Steps", "", "| step | command | time [s] | outcome |", "|---|---|---|---|"]
    for name, r in results.items():
        cmd = f"`{' '.join(r.argv)}`" if r.argv else "(in-process)"
        outcome = "ok" if r.ok else f"FAILED: {r.error}"
        lines.append(f"| {name} | {cmd} | {r.seconds:.1f} | {outcome} |")
    lines += ["", "Each command's report is in `logs/<step>.txt`. Files:", ""]
    lines += [f"- `{p.name}`" for p in sorted(out.iterdir()) if p.is_file() and p.name != "summary.md"]
    path = out / "summary.md"
    path.write_text("\n".join(lines) + "\n")
    return path
