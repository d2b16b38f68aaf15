"""Cup-and-ball: the whole game, judged on the written joint CSVs (`python benchmarks/bench_catch.py [--quick]`).

For strings of 0.15–0.35 m with the thesis ball (13.9 g) each plan comes from the full `lbr plan cup-and-ball`
pipeline on ONE worker process (planning time on one core), robust by default and with --max-time 3 s. Each written
joint file is then judged again:
- on the string model stepped at 1 ms (the simulator's integrator) over the whole band map — string length ±3 %
  (13 lengths) × ball mass ±20 % (3) × the cup's motion after the release one FRI period early / on time / late;
- how the map's missed cases fail (their first crossing of the rim plane outside the opening, or entered and lost
  again) and the spread of the landing points of 13 lengths across the band (no cup): what one cup must catch;
- by the independent penalty-force judge (``planners.string_penalty``: Cartesian, stiff springs, spline anchor, its
  own cup geometry, semi-implicit Euler at 40 µs) on 5 lengths of the band as planned, and (at 0.1 ms) over its own
  band of a model the plan was not made for (48 cases): the cup's radius 10 % smaller and larger × restitution and friction
  20 % lower and higher × the cup's motion after the release one FRI period early and late × 3 string lengths (−3 %,
  0, +3 %); and (the robust 0.25 m plan) on held-out cases: a 15 % wider and a 15 % narrower cup, restitution 0.3
  and 0.7.

`python benchmarks/bench_catch.py --lengths 0.3,0.35 --modes 3,none` plans only those (while iterating: a partial or
`--quick` run prints its rows, only a whole run writes the results files).
Writes the figures and the map of the 0.25 m plan to ``benchmarks/results/catch.md`` (quoted by the docs).
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).parent
LENGTHS = (0.15, 0.2, 0.25, 0.3, 0.35)
MAP_LENGTHS = 13
PENALTY_STEP = 1e-4  # [s] the penalty judge's step over its own band (12 steps per contact period; 40 µs as planned)


def _plan(length: float, folder: Path, max_time: float | None) -> dict:
    from lbrcli.commands.plan_catch import plan_catch_files

    out = folder / f"catch_{length:g}_{max_time}.csv"
    t0, c0 = time.perf_counter(), time.process_time()
    figures = plan_catch_files(length, out=out, max_time=max_time, workers=1)
    figures["wall_s"] = time.perf_counter() - t0
    figures["cpu_s"] = (
        time.process_time() - c0
    )  # one worker: the planning's CPU time (a shared machine's wall time is not)
    figures["csv"] = str(out)
    return figures


def _band_map(csv: str, length: float, n_length: int) -> tuple[np.ndarray, list]:
    """Success (length, mass, timing) of the written plan on the string model stepped at 1 ms."""
    from planners.catch_move import BandMember, judge_band, prepare_band
    from planners.string_model import StringModel
    from planners.string_sim import PivotMotion
    from trajectories.csvio import read_joint_csv
    from trajectories.robot import Robot

    traj = read_joint_csv(csv)
    model = StringModel(length)
    pos, rot = Robot().fk_path(traj.q)
    pivot = PivotMotion(traj.t, pos, rot @ np.asarray(model.axis_flange))
    lengths = length * (1 + 0.03 * np.linspace(-1, 1, n_length))
    masses = model.ball.mass * np.array([0.8, 1.0, 1.2])
    shifts = (-traj.dt, 0.0, traj.dt)
    members = tuple(BandMember(float(ln), float(m), s) for ln in lengths for m in masses for s in shifts)
    band = prepare_band(model, members, pivot, 0.0, substeps=5)
    outs = judge_band(model, band, pivot, float(traj.t[-1]), substeps=5)
    grid = np.array([o.caught for o in outs], dtype=float).reshape(len(lengths), len(masses), len(shifts))
    return grid, outs


def _failures(outs: list) -> dict:
    """How the map's missed cases fail: the ball's first crossing of the rim plane passes outside the opening (rim),
    it enters and leaves again or ends on the rim (bounce), or it never comes down into the rim plane at all."""
    missed = [o for o in outs if not o.caught]
    rim = sum(o.t_entry is None and o.margin is not None for o in missed)
    bounce = sum(o.t_entry is not None for o in missed)
    return {"rim": rim, "bounce": bounce, "other": len(missed) - rim - bounce}


def _landing_spread(csv: str, length: float) -> float:
    """[m] Spread along base y of where the balls of 13 string lengths across ±3 % come down through the rim height
    (the written path, no cup in the way): what one cup position must catch."""
    from planners.catch_plan import band_landings
    from planners.string_model import StringModel
    from planners.string_sim import PivotMotion
    from trajectories.csvio import read_joint_csv
    from trajectories.robot import Robot

    traj = read_joint_csv(csv)
    model = StringModel(length)
    pos, rot = Robot().fk_path(traj.q)
    pivot = PivotMotion(traj.t, pos, rot @ np.asarray(model.axis_flange))
    ys = [y for _, y, _ in band_landings(model, pivot, length * (1 + 0.03 * np.linspace(-1, 1, MAP_LENGTHS)))]
    return float(np.ptp(ys)) if len(ys) > 1 else math.nan


def _penalty(csv: str, length: float, variants: dict) -> dict:
    """Per variant of the model: caught (5,) by the penalty judge on 5 lengths across the band."""
    from planners.string_model import StringModel
    from planners.string_penalty import judge
    from trajectories.csvio import read_joint_csv
    from trajectories.robot import Robot

    traj = read_joint_csv(csv)
    pos, rot = Robot().fk_path(traj.q)
    out = {}
    for name, change in variants.items():
        base = change(StringModel(length))
        models = [dataclasses.replace(base, length=length * f) for f in (0.97, 0.985, 1.0, 1.015, 1.03)]
        axes = rot @ np.asarray(base.axis_flange)
        run = judge(models, traj.t, pos, axes, float(traj.t[-1]))
        out[name] = run.caught.astype(bool)
    return out


def _penalty_band(csv: str, length: float) -> np.ndarray:
    """Caught (48,) by the penalty judge over its own band: cup radius × 0.9 / 1.1, restitution and friction × 0.8 /
    1.2, the cup's motion after the release one period early / late, string length × 0.97 / 1 / 1.03."""
    from planners.string_model import StringModel
    from planners.string_penalty import judge
    from trajectories.csvio import read_joint_csv
    from trajectories.robot import Robot

    traj = read_joint_csv(csv)
    pos, rot = Robot().fk_path(traj.q)
    base = StringModel(length)
    axes = rot @ np.asarray(base.axis_flange)
    caught = []
    for radius in (0.9, 1.1):  # one run per cup (the cases of a run share it)
        cup = dataclasses.replace(base.cup, inner_radius=base.cup.inner_radius * radius)
        cases = [
            (dataclasses.replace(base, cup=cup, length=length * fl, restitution=base.restitution * fe,
                                 friction=base.friction * fm), s)
            for fl in (0.97, 1.0, 1.03) for fe in (0.8, 1.2) for fm in (0.8, 1.2) for s in (-traj.dt, traj.dt)
        ]  # fmt: skip
        shifts = np.array([s for _, s in cases])
        run = judge([m for m, _ in cases], traj.t, pos, axes, float(traj.t[-1]), dt=PENALTY_STEP, shifts=shifts)
        caught += run.caught.astype(bool).tolist()
    return np.array(caught)


def run(
    quick: bool = False, lengths: tuple[float, ...] | None = None, modes=(3.0, None)
) -> list[tuple[str, float, str]]:
    from planners.string_model import Cup

    rows: list[tuple[str, float, str]] = []
    lengths = lengths or ((0.25,) if quick else LENGTHS)
    report = {"plans": {}, "map": None}
    wide = Cup(inner_radius=0.0345, depth=0.045, rim_height=0.05)
    narrow = Cup(inner_radius=0.0255, depth=0.045, rim_height=0.05)
    variants = {
        "as planned": lambda m: m,
        "cup 15 % wider": lambda m: dataclasses.replace(m, cup=wide),
        "cup 15 % narrower": lambda m: dataclasses.replace(m, cup=narrow),
        "restitution 0.3": lambda m: dataclasses.replace(m, restitution=0.3),
        "restitution 0.7": lambda m: dataclasses.replace(m, restitution=0.7),
    }
    done = 0
    partial = lengths != LENGTHS or tuple(modes) != (3.0, None)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for max_time in modes:  # the goal's 3 s first
            for length in lengths:
                tag = f"l={length:g} m, {'robust' if max_time is None else '--max-time 3'}"
                load = os.getloadavg()[0]  # the machine's 1-minute load before the plan (its times depend on it)
                try:
                    f = _plan(length, folder, max_time)
                except Exception as exc:  # a plan that cannot be made is a figure too
                    rows.append((f"{tag}: planning failed ({type(exc).__name__})", math.nan, "-"))
                    report["plans"][tag] = {"error": str(exc)}
                    continue
                rob = f["robustness"]
                rows += [
                    (f"{tag}: caught (nominal)", float(f["caught"]), "-"),
                    (f"{tag}: enters the cup", f["catch_time_s"] if f["catch_time_s"] else math.nan, "s"),
                    (f"{tag}: band caught (planner's {rob['members']} cases)", rob["success_fraction"], "-"),
                    (f"{tag}: relative entry speed", f["relative_entry_speed_m_s"] or math.nan, "m/s"),
                    (f"{tag}: limits ok", float(f["limits_ok"]), "-"),
                    (f"{tag}: planning time, one worker", f["wall_s"], "s"),
                    (f"{tag}: planning CPU time, one worker", f["cpu_s"], "s"),
                    (f"{tag}: load average before planning (2 cores)", load, "-"),
                ]
                entry = {
                    k: f[k]
                    for k in (
                        "caught",
                        "catch_time_s",
                        "rest_in_cup_s",
                        "entry_margin_m",
                        "relative_entry_speed_m_s",
                        "limits_ok",
                        "planning_time_s",
                    )
                }
                entry["planning_cpu_s"] = f["cpu_s"]
                entry["load_1min"] = load
                entry["band_success"] = rob["success_fraction"]
                if not quick or max_time is None:
                    grid, outs = _band_map(f["csv"], length, 5 if quick else MAP_LENGTHS)
                    entry["map_success"] = float(grid.mean())
                    entry["map_failures"] = _failures(outs)
                    entry["landing_spread_m"] = _landing_spread(f["csv"], length)
                    rows += [
                        (f"{tag}: band map caught ({grid.size} cases, 1 ms steps)", float(grid.mean()), "-"),
                        (f"{tag}: map cases missed at the rim", entry["map_failures"]["rim"], "-"),
                        (
                            f"{tag}: map cases entered, then lost (bounce-out, rim)",
                            entry["map_failures"]["bounce"],
                            "-",
                        ),
                        (f"{tag}: landing spread over the length band (no cup)", entry["landing_spread_m"], "m"),
                    ]
                    if length == 0.25 and max_time is None:
                        report["map"] = {
                            "lengths": list(length * (1 + 0.03 * np.linspace(-1, 1, grid.shape[0]))),
                            "success_by_length": grid.mean(axis=(1, 2)).tolist(),
                            "success_by_mass": grid.mean(axis=(0, 2)).tolist(),
                            "success_by_timing": grid.mean(axis=(0, 1)).tolist(),
                        }
                    held_out = length == 0.25 and max_time is None and not quick
                    judged = _penalty(
                        f["csv"], length, variants if held_out else {"as planned": variants["as planned"]}
                    )
                    entry["penalty"] = {k: v.tolist() for k, v in judged.items()}
                    for name, caught in judged.items():
                        rows.append((f"{tag}: penalty judge, {name} (5 lengths)", float(np.mean(caught)), "-"))
                    same = grid[np.linspace(0, grid.shape[0] - 1, 5).astype(int), 1, 1].astype(bool)
                    agree = float(np.mean(judged["as planned"] == same))
                    entry["penalty_agreement"] = agree
                    rows.append((f"{tag}: penalty judge agrees with the model (5 lengths)", agree, "-"))
                    other = _penalty_band(f["csv"], length)
                    entry["penalty_band_success"] = float(other.mean())
                    rows.append(
                        (f"{tag}: penalty judge band caught ({other.size} cases: cup, e, μ, timing)", other.mean(), "-")
                    )
                report["plans"][tag] = entry
                for name, value, unit in rows[done:]:
                    print(f"{name:70s} {value:12.4g} {unit}", flush=True)
                done = len(rows)
    if not partial:  # a quick or partial run prints its rows only
        _write(report, rows)
    return rows


def _write(report: dict, rows: list) -> None:
    out = HERE / "results"
    out.mkdir(exist_ok=True)
    lines = [
        "# Cup-and-ball benchmark (`python benchmarks/bench_catch.py`)",
        "",
        "| figure | value | unit |",
        "|---|---|---|",
    ]
    lines += [f"| {k} | {v:.4g} | {u} |" for k, v, u in rows]
    if report["map"]:
        m = report["map"]
        lines += [
            "",
            "Map of the robust plan for l = 0.25 m (share caught, stepped model at 1 ms):",
            "",
            "| string length [m] | " + " | ".join(f"{x:.4f}" for x in m["lengths"]) + " |",
            "|---|" + "---|" * len(m["lengths"]),
            "| caught | " + " | ".join(f"{x:.2f}" for x in m["success_by_length"]) + " |",
            "",
            f"By mass 0.8 / 1.0 / 1.2 × 13.9 g: {', '.join(f'{x:.2f}' for x in m['success_by_mass'])}; by the cup's "
            f"timing −1 / 0 / +1 period: {', '.join(f'{x:.2f}' for x in m['success_by_timing'])}.",
        ]
    (out / "catch.md").write_text("\n".join(lines) + "\n")
    (out / "catch.json").write_text(json.dumps(report, indent=1, default=float))


def _arg(name: str) -> str | None:
    return sys.argv[sys.argv.index(name) + 1] if name in sys.argv else None


if __name__ == "__main__":
    only = _arg("--lengths")
    modes = _arg("--modes")
    partial = dict(
        lengths=tuple(float(x) for x in only.split(",")) if only else None,
        modes=tuple(None if x == "none" else float(x) for x in modes.split(",")) if modes else (3.0, None),
    )
    rows = run(quick="--quick" in sys.argv, **partial)  # prints each plan's rows as they come
