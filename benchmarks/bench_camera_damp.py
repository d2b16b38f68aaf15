"""Damping with the camera in the loop (issue #33): `lbr control damp --sensor camera` on the simulator, whose camera
renders its ball (MJPEG over HTTP on loopback), tracked live, the tilt from the camera's geometry.

The default crane move (`lbr plan anti-sway --length 0.25 --a-max 2`, 5 ms) with the simulated string 20 % short and
long; the goal: at 120 fps and 15 ms camera latency, the largest tilt two swing periods after the move's end ≤ 0.1°
(open loop ≈ 0.7°), and at 30 fps and 50 ms what is reachable. The band: two camera poses (the default, 30° above and
45° around from the base's line to the move; one from the other side, 39° above, seeing a 1° tilt as half the
pixels; and a third from behind the move, 27° above, as low in pixels along y, chosen after the damper was changed
for the second), 120 fps / 15 ms, 60 fps / 30 ms and 30 fps / 50 ms, 320x240 (and 640x480 at the goal point), frames stamped
with their index (the default) and not (a frame's moment from its arrival less the camera's delay, as a camera
without a frame counter). Figures per case from the simulator's own ball (the log's ball_theta), the camera's
latency and the readings' age, the largest offset, missed FRI cycles; the open loop from `--sensor io --open-loop`.
On a loaded PC the simulator's robot sometimes stops following its commands (missed cycles) and a run fails — with any
sensor, open loop too; such a case is run again (up to ATTEMPTS times) and the failures are listed with the figures.

`python benchmarks/bench_camera_damp.py [--quick]` prints the figures and writes benchmarks/results/camera_damp.json
and docs/guides/results/camera_damp.md (the camera guide quotes that table); `--quick` runs the goal point only.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
DOCS = HERE.parent / "docs" / "guides" / "results"
OTHER_POSE = ("--sim-camera-position", "0.9,-0.9,1.0", "--sim-camera-look-at", "0.5,0,0.2", "--sim-camera-fov", "60")
# a third judge, chosen after the damper was changed for the other pose: from behind the move, low, 27° down
THIRD_POSE = ("--sim-camera-position", "0.1,0.8,0.7", "--sim-camera-look-at", "0.5,0,0.25", "--sim-camera-fov", "55")
TIMINGS = {
    "120 fps / 15 ms": ("--sim-camera-fps", "120", "--sim-camera-latency", "15"),
    "60 fps / 30 ms": ("--sim-camera-fps", "60", "--sim-camera-latency", "30", "--sim-camera-exposure", "6"),
    "30 fps / 50 ms": ("--sim-camera-fps", "30", "--sim-camera-latency", "50", "--sim-camera-exposure", "8"),
}


def _log(path: Path) -> dict[str, np.ndarray]:
    import csv

    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    data = np.array([[float(x) if x else math.nan for x in r] for r in rows[1:]])
    return {name: data[:, i] for i, name in enumerate(rows[0])}


def _crane(tmp: Path) -> tuple[Path, float]:
    out = tmp / "crane.csv"
    p = subprocess.run([sys.executable, "-m", "lbrcli", "plan", "anti-sway", "-o", str(out), "--length", "0.25",
                        "--a-max", "2", "--json"], capture_output=True, text=True, timeout=300)  # fmt: skip
    if p.returncode != 0:
        raise SystemExit(f"planning the crane move failed: {p.stderr[-500:]}")
    return out, float(json.loads(p.stdout)["motion_s"])


def _case(crane: Path, move_end: float, true_length: float, args: tuple[str, ...]) -> dict:
    """One run; the sway 1 and 2 periods after the move [deg] from the simulated ball, and the command's figures."""
    from planners.pendulum import natural_period

    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "run.csv"
        cmd = [sys.executable, "-m", "lbrcli", "control", "damp", str(crane), "--length", "0.25", "--sim-length",
               str(true_length), "--log", str(log), "--json", "--sim-lenient", "--port", "0", *args]  # fmt: skip
        load = os.getloadavg()[0]
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
        fig = json.loads(p.stdout) if p.stdout.strip().startswith("{") else {}
        d = _log(log) if log.exists() else None
    out = {
        "exit": p.returncode,
        "load": load,
        "fig": fig,
        "why": p.stderr.strip().splitlines()[-1] if p.returncode else "",
    }
    if d is not None and np.any(d["phase"] == 2):
        t, phase = d["t"], d["phase"]
        t0 = t[np.flatnonzero(phase == 2)[0]]
        for n in (1, 2):
            m = (t >= t0 + move_end + n * natural_period(true_length)) & (phase >= 2)
            out[f"sway_{n}T"] = float(np.degrees(d["ball_theta"][m].max())) if m.any() else math.nan
    return out


ATTEMPTS = 3  # a run the loaded PC spoils (the simulator's robot not following its commands) is run again


def _completed(crane: Path, move_end: float, true_length: float, args: tuple[str, ...]) -> dict:
    """The first of up to ATTEMPTS runs that completed (exit 0, its sway logged), with the reasons the runs before it
    failed (``failures``); the last run when none did."""
    failures: list[str] = []
    for _ in range(ATTEMPTS):
        r = _case(crane, move_end, true_length, args)
        if r["exit"] == 0 and math.isfinite(r.get("sway_2T", math.nan)):
            break
        failures.append(r["why"] or "the sway was not logged")
    else:
        failures.pop()  # the last failed run is the one reported
    r["failures"] = failures
    return r


def _cases(quick: bool) -> list[tuple[str, tuple[str, ...]]]:
    goal = TIMINGS["120 fps / 15 ms"]
    cases = [("default pose, 320x240, 120 fps / 15 ms", goal)]
    if quick:
        return cases
    cases += [
        ("default pose, 640x480, 120 fps / 15 ms", (*goal, "--sim-camera-size", "640x480")),
        ("default pose, 320x240, 120 fps / 15 ms, no frame stamps", (*goal, "--no-sim-camera-stamp")),
        ("other pose, 320x240, 120 fps / 15 ms", (*goal, *OTHER_POSE)),
        ("third pose, 320x240, 120 fps / 15 ms", (*goal, *THIRD_POSE)),
    ]
    for name in ("60 fps / 30 ms", "30 fps / 50 ms"):
        cases += [
            (f"default pose, 320x240, {name}", TIMINGS[name]),
            (f"other pose, 320x240, {name}", (*TIMINGS[name], *OTHER_POSE)),
            (f"third pose, 320x240, {name}", (*TIMINGS[name], *THIRD_POSE)),
        ]
    return cases


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        crane, move_end = _crane(Path(tmp))
        lengths = (0.3,) if quick else (0.2, 0.3)
        open_loop = {L: _completed(crane, move_end, L, ("--sensor", "io", "--open-loop")) for L in lengths}
        for L, o in open_loop.items():
            print(f"  open loop, string {L:g} m: exit {o['exit']}, {o.get('sway_2T', math.nan):.3f}° two periods after, "
                  f"load {o['load']:.1f}, failed before: {o['failures']}", file=sys.stderr)  # fmt: skip
        for name, args in _cases(quick):
            for L in lengths:
                r = _completed(crane, move_end, L, ("--sensor", "camera", *args))
                r.update(case=name, length=L, open_2T=open_loop[L].get("sway_2T", math.nan))
                results.append(r)
                print(f"  {name}, string {L:g} m: exit {r['exit']}, {r.get('sway_2T', math.nan):.3f}° two periods after "
                      f"(open loop {r['open_2T']:.3f}°), load {r['load']:.1f}, failed before: {r['failures']}", file=sys.stderr)  # fmt: skip
    rows: list[tuple[str, float, str]] = []
    for L in lengths:
        rows.append(
            (
                f"open loop, string {L:g} m (plan 0.25): sway 2 periods after the move",
                open_loop[L].get("sway_2T", math.nan),
                "deg",
            )
        )
    for r in results:
        f = r["fig"]
        tag = f"{r['case']}, string {r['length']:g} m"
        rows += [
            (f"{tag}: exit code", float(r["exit"]), ""),
            (f"{tag}: runs that failed before (a loaded PC)", float(len(r["failures"])), ""),
            (f"{tag}: sway 1 period after the move", r.get("sway_1T", math.nan), "deg"),
            (f"{tag}: sway 2 periods after the move", r.get("sway_2T", math.nan), "deg"),
            (f"{tag}: camera string measured", f.get("camera_string_m") or math.nan, "m"),
            (f"{tag}: a 1° tilt moves the ball (x, least)", (f.get("camera_px_per_deg") or [math.nan])[0], "px"),
            (
                f"{tag}: a 1° tilt moves the ball (y, least)",
                (f.get("camera_px_per_deg") or [math.nan, math.nan])[1],
                "px",
            ),
            (f"{tag}: capture → result p50", f.get("camera_latency_ms_p50") or math.nan, "ms"),
            (f"{tag}: reading age p50", f.get("camera_age_ms_p50") or math.nan, "ms"),
            (f"{tag}: reading age p95", f.get("camera_age_ms_p95") or math.nan, "ms"),
            (f"{tag}: frames dropped", float(f.get("camera_frames_dropped", math.nan)), ""),
            (f"{tag}: largest offset from the path", 1e3 * (f.get("max_offset_m") or math.nan), "mm"),
            (f"{tag}: missed FRI cycles", float(f.get("missed", math.nan)), ""),
            (f"{tag}: machine load (1 min) at the start", r["load"], ""),
        ]
    if not quick:
        _write_table(results, open_loop)
    return rows


def _write_table(results: list[dict], open_loop: dict) -> None:
    DOCS.mkdir(parents=True, exist_ok=True)
    md = [
        "| camera | string | sway 2 periods after the move | 1 period after | a 1° tilt moves the ball (x / y) | "
        "reading age p50 / p95 | frames dropped | largest offset | exit | runs failed before |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results:
        f = r["fig"]
        px = f.get("camera_px_per_deg") or [math.nan, math.nan]
        md.append(f"| {r['case']} | {r['length']:g} m | {r.get('sway_2T', math.nan):.3f}° | {r.get('sway_1T', math.nan):.3f}° | "
                  f"{px[0]:.2f} / {px[1]:.2f} px | {f.get('camera_age_ms_p50') or math.nan:.1f} / "
                  f"{f.get('camera_age_ms_p95') or math.nan:.1f} ms | {f.get('camera_frames_dropped', '–')} | "
                  f"{1e3 * (f.get('max_offset_m') or math.nan):.1f} mm | {r['exit']} | {len(r['failures'])} |")  # fmt: skip
    md += [
        "",
        "| open loop (the plan alone) | string | sway 2 periods after the move | runs failed before |",
        "|---|---|---|---|",
    ]
    md += [f"| `--sensor io --open-loop` | {L:g} m | {o.get('sway_2T', math.nan):.3f}° | {len(o['failures'])} |"
           for L, o in open_loop.items()]  # fmt: skip
    loads = [r["load"] for r in results]
    failed = [w for r in [*results, *open_loop.values()] for w in r["failures"]]
    md += [
        "",
        f"Machine load (1 min) at the start of the runs: {min(loads):.1f}–{max(loads):.1f} on {os.cpu_count()} cores. "
        f"{len(failed)} runs failed and were run again (up to {ATTEMPTS} per case); their reasons:",
    ]
    md += [f"- {w}" for w in failed] if failed else ["- none"]
    (DOCS / "camera_damp.md").write_text("\n".join(md) + "\n")


if __name__ == "__main__":
    import time

    sys.path.insert(0, str(HERE))
    from run_all import save_results

    quick = "--quick" in sys.argv
    t0 = time.perf_counter()
    rows = run(quick=quick)
    for name, value, unit in rows:
        print(f"{name:<95} {value:>10.4g} {unit}")
    if not quick:
        print(f"wrote {save_results('camera_damp', rows, time.perf_counter() - t0)} and {DOCS / 'camera_damp.md'}")
