"""Tracking hard cases (issues #16 and #35) on rendered videos with exact ground truth, one figure set per video:
found share of the frames where the ball is visible, false fixes (> 5 px off), centre and θ RMS errors, tracking /
decoding time in wall and in CPU time (this process's, all threads). The kinds: dark start, a static red disc (and --start), tilted camera with calibration, swing-ups at
60 and 30 fps, orange ball beside a hand, occluding rod, moving pivot with marker, slow motion, heavy JPEG, clutter in
the ball's colour (labels, cables, a tool), H.264 at 100 kbit/s (alone and with clutter), an oblique camera with a
sharp ball, 30 fps with whole-frame searches, a 3 px ball, a ball a quarter of the frame — and held-out variations
(orange clutter on VP9, H.264 60 kbit/s, clutter on HEVC, a 2.6 px ball on H.264, a ball a third of the frame, an
oblique view from the other side at 30 fps; clutter on H.264 80 kbit/s, H.264 200 kbit/s, a 5 px ball, a ball a fifth of
the frame) that were not used to tune the tracker; and a second judge made after the model look and the smoothing were
written (H.264 at 50, 70 and 90 kbit/s, clutter, a larger and a smaller ball, a slower swing, HEVC at 60 kbit/s);
and a third made after the pendulum check was written (H.264 at 40 kbit/s, a ball half as large at 120 kbit/s, clutter
on HEVC 80 kbit/s, a 45° swing of 0.8 s at 60 kbit/s, VP9 70 kbit/s with a larger ball, an oblique camera on H.264);
and a fourth whose ball swings as a real pendulum (nonlinear, damped, released from 45–80°) rather than a decaying
sinusoid, made after track10's code (H.264 70 and 100 kbit/s, VP9 80 kbit/s); and a fifth made after the model look's
long runs (real pendulums on H.264 60 and 90 kbit/s, HEVC 70 kbit/s, balls 0.7-0.9x; its 70° swing led to the rule for
runs at the video's start and end); and a sixth made after that rule (H.264 50 kbit/s, VP9 60 kbit/s with a smaller ball); and a seventh made after the
model look's rule for a ball smeared along its motion (real pendulums from 60-85° on H.264 55 and 80 kbit/s and HEVC
50 kbit/s, balls 0.75-1.2x); and an eighth made before the model look's fit bound for low-bitrate HEVC was tried
(real pendulums on HEVC 55, VP9 50 and H.264 45 kbit/s); and a tenth made after the regained-lock rule and the
pendulum check's robust fit (real pendulums on HEVC 50 and 40 kbit/s, VP9 60 and 45 kbit/s, H.264 50 and 65 kbit/s).

Visible: the whole ball inside the frame, clear of objects of its colour (colour alone cannot separate them), and
for low-bitrate codecs shown by the decoded frame (≥ 30 % of its disc in its colour: the encoder sometimes drops a
moving ball's blocks). Goals (issue #35): ≥ 99 % found, 0 false fixes, centre ≤ 0.5 px RMS, θ ≤ 0.1° with
calibration; tracking ≤ 1.5× decoding at 720p, ≤ 2× at 4K. Adversarial cases are reported, not counted.

`python benchmarks/bench_track_robust.py [--quick]` prints the figures and writes them to
docs/guides/results/track_robust.{json,md} (the tracking guide quotes that table).
"""

from __future__ import annotations

import json
import math
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

RESULTS = Path(__file__).resolve().parent.parent / "docs" / "guides" / "results"


def _cpu_s() -> float:
    """CPU time of this process, all threads (the decoder's and the prefetch thread's included) [s]."""
    t = os.times()
    return t.user + t.system


def _decode(path: Path) -> tuple[float, float]:
    """(wall, CPU) time [s] of decoding every frame."""
    from tracking.video import iter_frames

    t0, c0 = time.perf_counter(), _cpu_s()
    for _ in iter_frames(path):
        pass
    return time.perf_counter() - t0, _cpu_s() - c0


def _one(name: str, folder: Path, size: tuple[int, int], duration_s: float, repeats: int, held_out: bool) -> dict:
    from tracking import scenarios
    from tracking.color import color_spec
    from tracking.pipeline import track_video

    make = {
        **scenarios.ALL,
        **scenarios.HELD_OUT,
        **scenarios.JUDGE2,
        **scenarios.JUDGE3,
        **scenarios.JUDGE4,
        **scenarios.JUDGE5,
        **scenarios.JUDGE6,
        **scenarios.JUDGE7,
        **scenarios.JUDGE8,
        **scenarios.JUDGE9,
        **scenarios.JUDGE10,
    }[name]
    sc = make(folder / f"{name}_{size[0]}.mp4", size, duration_s)
    kw = dict(sc.track_kwargs)
    ball = kw.pop("ball", color_spec("red"))
    _decode(sc.path)  # warm the file cache
    decode = tracking = decode_cpu = tracking_cpu = math.inf
    track = None
    for _ in range(repeats):  # interleaved, best of: the machine is shared
        wall, cpu = _decode(sc.path)
        decode, decode_cpu = min(decode, wall), min(decode_cpu, cpu)
        t0, c0 = time.perf_counter(), _cpu_s()
        track = track_video(sc.path, ball, **kw)
        tracking, tracking_cpu = min(tracking, time.perf_counter() - t0), min(tracking_cpu, _cpu_s() - c0)
    shown = scenarios.ball_shown(sc) if sc.lossy else np.ones(len(sc.counted), bool)
    counted = sc.counted & shown
    from dataclasses import replace

    out = scenarios.score(replace(sc, counted=counted), track)
    row = {
        "name": sc.name,
        "key": name,
        "held_out": held_out,
        "adversarial": sc.adversarial,
        "size": f"{size[0]}x{size[1]}",
        "frames": int(len(sc.truth.t)),
        "counted": int(counted.sum()),
        "erased_by_codec": int((sc.counted & ~shown).sum()),
        "found_percent": out.found_percent,
        "false_fixes": out.false_fixes,
        "centre_rms_px": out.centre_rms_px,
        "theta_rms_deg": out.theta_rms_deg,
        "unsure_frames": int(track.unsure.sum()) if track.unsure is not None else 0,
        "second_look_frames": track.second_look_frames,
        "model_look_frames": track.model_look_frames,
        "outlier_frames": track.outlier_frames,
        "smoothed_frames": track.smoothed_frames,
        "off_pendulum_frames": track.off_pendulum_frames,
        "on_pendulum_frames": track.on_pendulum_frames,
        "judge2": name in scenarios.JUDGE2,
        "judge3": name in scenarios.JUDGE3,
        "judge4": name in scenarios.JUDGE4,
        "judge5": name in scenarios.JUDGE5,
        "judge6": name in scenarios.JUDGE6,
        "judge7": name in scenarios.JUDGE7,
        "judge8": name in scenarios.JUDGE8,
        "judge9": name in scenarios.JUDGE9,
        "judge10": name in scenarios.JUDGE10,
        "track_over_decode": tracking / decode,
        "decode_fps": len(sc.truth.t) / decode,
        "track_over_decode_cpu": tracking_cpu / decode_cpu,
        "load_1min": os.getloadavg()[0],
    }
    print(  # progress (the run takes long on a busy machine)
        f"{name} {size[0]}x{size[1]}: found {row['found_percent']:.2f} %, false {row['false_fixes']}, "
        f"centre {row['centre_rms_px']:.2f} px, CPU {row['track_over_decode_cpu']:.2f}x, load {row['load_1min']:.1f}",
        file=sys.stderr,
        flush=True,
    )
    if name == "tilted":  # `compare` against the true motion delayed by 0.5 s: the lag must come out right
        from tracking.compare import compare_angles

        cmp = compare_angles(sc.truth.t - 0.5, sc.truth.theta, track.t, track.theta)
        row["compare_lag_error_ms"] = abs(cmp.lag_s - 0.5) * 1e3
    return row


def _table(rows: list[dict]) -> str:
    head = (
        "| video | size | counted frames | found | false fixes (> 5 px) | centre RMS | θ RMS | track / decode (wall) "
        "| track / decode (CPU) |\n"
    )
    head += "|---|---|---|---|---|---|---|---|---|\n"

    def f(x, fmt):  # noqa: ANN001
        return "—" if x is None or (isinstance(x, float) and not math.isfinite(x)) else format(x, fmt)

    lines = []
    for r in rows:
        tag = " (held out)" if r["held_out"] else (" (adversarial)" if r["adversarial"] else "")
        erased = f", {r['erased_by_codec']} erased by the codec" if r["erased_by_codec"] else ""
        lines.append(
            f"| {r['name']}{tag} | {r['size']} | {r['counted']}{erased} | {f(r['found_percent'], '.1f')} % | "
            f"{r['false_fixes']} | {f(r['centre_rms_px'], '.2f')} px | {f(r['theta_rms_deg'], '.3f')}° | "
            f"{f(r['track_over_decode'], '.2f')}× | {f(r['track_over_decode_cpu'], '.2f')}× |"
        )
    return head + "\n".join(lines) + "\n"


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    from tracking import scenarios

    size, duration, repeats = ((640, 360), 2.0, 1) if quick else ((1280, 720), 4.0, 2)
    rows: list[dict] = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in scenarios.ALL:
            rows.append(_one(name, Path(tmp), size, duration, repeats, False))
        for name in [
            *scenarios.HELD_OUT,
            *scenarios.JUDGE2,
            *scenarios.JUDGE3,
            *scenarios.JUDGE4,
            *scenarios.JUDGE5,
            *scenarios.JUDGE6,
            *scenarios.JUDGE7,
            *scenarios.JUDGE8,
            *scenarios.JUDGE9,
            *scenarios.JUDGE10,
        ]:
            rows.append(_one(name, Path(tmp), size, duration, repeats, True))
        big = (1920, 1080) if quick else (3840, 2160)
        for name in ("plain", "clutter"):  # the time budget at 4K (whole-frame searches at the start)
            rows.append(_one(name, Path(tmp), big, 1.5 if quick else 2.5, repeats, False))
    RESULTS.mkdir(parents=True, exist_ok=True)
    if not quick:
        (RESULTS / "track_robust.json").write_text(json.dumps(rows, indent=1) + "\n")
        (RESULTS / "track_robust.md").write_text(_table(rows))
    figures: list[tuple[str, float, str]] = [(f"videos {size[0]}x{size[1]}", duration, "s each")]
    for r in rows:
        label = f"{r['name']} {r['size']}" + (
            " (held out)" if r["held_out"] else " (adversarial)" if r["adversarial"] else ""
        )
        figures += [
            (f"{label}: found", r["found_percent"], "%"),
            (f"{label}: false fixes", r["false_fixes"], "frames"),
            (f"{label}: centre RMS", r["centre_rms_px"], "px"),
            (f"{label}: track / decode", r["track_over_decode"], "x"),
            (f"{label}: track / decode CPU", r["track_over_decode_cpu"], "x"),
        ]
        if math.isfinite(r["theta_rms_deg"]):
            figures.append((f"{label}: theta RMS", r["theta_rms_deg"], "deg"))
    goal = [r for r in rows if not r["adversarial"] and not r["held_out"]]
    judged = ("judge2", "judge3", "judge4", "judge5", "judge6", "judge7", "judge8", "judge9")
    held = [r for r in rows if r["held_out"] and not any(r[k] for k in judged)]
    judge2 = [r for r in rows if r["judge2"]]
    judge3 = [r for r in rows if r["judge3"]]
    judge4 = [r for r in rows if r["judge4"]]
    judge5 = [r for r in rows if r["judge5"]]
    judge6 = [r for r in rows if r["judge6"]]
    judge7 = [r for r in rows if r["judge7"]]
    judge8 = [r for r in rows if r["judge8"]]
    judge9 = [r for r in rows if r["judge9"]]
    sets = (
        ("goal videos", goal),
        ("held-out videos", held),
        ("judge 2 videos", judge2),
        ("judge 3 videos", judge3),
        ("judge 4 videos (a real pendulum)", judge4),
        ("judge 5 videos (a real pendulum, made after the model look's long runs)", judge5),
        ("judge 6 videos (a real pendulum, made after the rule for runs at the start and end)", judge6),
        ("judge 7 videos (a real pendulum, made after the rule for a smeared ball)", judge7),
        ("judge 8 videos (a real pendulum, made before the look's fit bound for HEVC)", judge8),
        ("judge 9 videos (a real pendulum, made after the tentative lock's fresh search)", judge9),
    )
    for tag, sel in sets:
        figures += [
            (f"{tag}: videos", len(sel), ""),
            (f"{tag}: worst found", float(np.nanmin([r["found_percent"] for r in sel])), "%"),
            (f"{tag}: false fixes in all", float(np.sum([r["false_fixes"] for r in sel])), "frames"),
            (f"{tag}: worst centre RMS", float(np.nanmax([r["centre_rms_px"] for r in sel])), "px"),
            (f"{tag}: worst theta RMS", float(np.nanmax([r["theta_rms_deg"] for r in sel])), "deg"),
        ]
    big = "4K" if not quick else "1080p"
    for key, tag in (("track_over_decode", ""), ("track_over_decode_cpu", " CPU")):
        small = [r[key] for r in goal if r["size"] == f"{size[0]}x{size[1]}"]
        large = [r[key] for r in rows if r["size"] in ("3840x2160", "1920x1080")]
        figures += [
            (f"worst track / decode{tag} at {size[0]}x{size[1]}", float(np.max(small)), "x"),
            (f"median track / decode{tag} at {size[0]}x{size[1]}", float(np.median(small)), "x"),
            (f"worst track / decode{tag} at {big}", float(np.max(large)), "x"),
        ]
    figures.append(("machine load (1 min) during the run", float(np.mean([r["load_1min"] for r in rows])), ""))
    return figures


if __name__ == "__main__":
    for name, value, unit in run(quick="--quick" in sys.argv):
        print(f"{name:<75} {value:>12.4g} {unit}")
