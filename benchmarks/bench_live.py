"""The camera as a live sensor (issue #33): tracking time per 720p frame on one core, and the whole chain —
simulated camera (its own process, MJPEG over HTTP on loopback) → OpenCV → live tracker — at 720p 60 fps and at
320x240 120 and 240 fps: latency from capture to result, frames dropped, tilt error against the spherical
pendulum's truth (frames paired by the camera's frame counter).

Goal: ≤ 5 ms per 720p frame on one core. `python benchmarks/bench_live.py [--quick]` prints the figures and writes
docs/guides/results/live.{json,md} (the camera guide quotes that table).
"""

from __future__ import annotations

import json
import math
import os
import tempfile
import time
from pathlib import Path

import numpy as np

RESULTS = Path(__file__).resolve().parent.parent / "docs" / "guides" / "results"
PIVOT_M = np.array([0.5, 0.0, 0.6])
STRING_M = 0.3


def _per_frame_ms(size: tuple[int, int], scenario: str, duration_s: float) -> dict:
    """BallTracker.update on decoded frames in memory, this process pinned to one core [ms per frame]."""
    from tracking import scenarios
    from tracking.color import color_spec
    from tracking.tracker import BallTracker
    from tracking.video import iter_frames

    with tempfile.TemporaryDirectory() as tmp:
        sc = scenarios.ALL[scenario](Path(tmp) / "v.mp4", size, duration_s)
        frames = [(t, f) for _, t, f in iter_frames(sc.path)]
    pivot = sc.track_kwargs.get("pivot_uv")
    best = None
    for _ in range(2):
        tr = BallTracker(color_spec("red"))
        ms = []
        for t, f in frames:
            t0 = time.perf_counter()
            tr.update(f, t, pivot)
            ms.append((time.perf_counter() - t0) * 1e3)
        ms = np.array(ms)
        if best is None or np.median(ms) < np.median(best):
            best = ms
    return {
        "scenario": scenario,
        "size": f"{size[0]}x{size[1]}",
        "p50_ms": float(np.median(best)),
        "p99_ms": float(np.percentile(best, 99)),
        "max_ms": float(best.max()),
        "mean_ms": float(best.mean()),
    }


def _chain(size: tuple[int, int], fps: float, latency_s: float, seconds: float) -> dict:
    from lbrcli.lab.camera_stream import CameraConfig, CameraProcess, read_stamp
    from lbrcli.lab.testing import free_pendulum_scene
    from tracking.color import color_spec
    from tracking.live import LiveTracker, TiltSetup

    run, scene = free_pendulum_scene(PIVOT_M, STRING_M, seconds + 3.0)

    cfg = CameraConfig(
        position_m=(1.3, -0.6, 1.0),
        look_at_m=(0.5, 0.0, 0.35),
        fov_deg=45.0,
        size=size,
        fps=fps,
        exposure_s=min(0.004, 0.5 / fps),
        latency_s=latency_s,
        stamp=True,
    )
    results, stamps = [], {}
    with CameraProcess(scene, cfg) as cam:
        tilt = TiltSetup(cam.geometry, tuple(PIVOT_M), STRING_M)
        with LiveTracker(
            cam.url,
            color_spec("red"),
            tilt=tilt,
            on_result=results.append,
            on_frame=lambda seq, frame: stamps.__setitem__(seq, read_stamp(frame)),
        ) as live:
            time.sleep(seconds)
        t_start = cam.t_start
    st = live.stats
    rs = [r for r in results if r.found and math.isfinite(r.theta_x) and r.seq in stamps]
    t_frame = np.array([stamps[r.seq] / fps for r in rs])
    ex = np.array([r.theta_x for r in rs]) - np.interp(t_frame, run.t, run.theta_x)
    ey = np.array([r.theta_y for r in rs]) - np.interp(t_frame, run.t, run.theta_y)
    delay = np.array([r.t_capture for r in rs]) - (t_start + t_frame)
    lat = np.array(st.latency_s) * 1e3
    frames_sent = (max(stamps.values()) - min(stamps.values()) + 1) if stamps else 0
    return {
        "size": f"{size[0]}x{size[1]}",
        "fps": fps,
        "camera_latency_ms": latency_s * 1e3,
        "seconds": seconds,
        "frames_sent": int(frames_sent),
        "frames_read": st.read,
        "frames_tracked": st.tracked,
        "dropped": st.dropped,
        "found_percent": 100.0 * st.found / max(st.tracked, 1),
        "latency_ms_p50": float(np.percentile(lat, 50)),
        "latency_ms_p95": float(np.percentile(lat, 95)),
        "latency_ms_max": float(lat.max()),
        "track_ms_p50": float(np.median(st.track_s) * 1e3),
        "frame_to_capture_ms_p50": float(np.median(delay) * 1e3) if len(delay) else math.nan,
        "frame_to_result_ms_p50": float(np.median(delay) * 1e3 + np.percentile(lat, 50)) if len(delay) else math.nan,
        "tilt_x_rms_deg": math.degrees(math.sqrt(float(np.mean(ex**2)))) if len(ex) else math.nan,
        "tilt_y_rms_deg": math.degrees(math.sqrt(float(np.mean(ey**2)))) if len(ey) else math.nan,
    }


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    cores = os.sched_getaffinity(0)
    os.sched_setaffinity(0, {min(cores)})  # one core for the per-frame figures
    try:
        per_frame = [_per_frame_ms((1280, 720), s, 2.0 if quick else 4.0) for s in ("plain", "clutter", "dark_start")]
    finally:
        os.sched_setaffinity(0, cores)
    seconds = 2.0 if quick else 5.0
    chains = [
        _chain((1280, 720), 60.0, 0.015, seconds),
        _chain((320, 240), 120.0, 0.015, seconds),
        _chain((320, 240), 240.0, 0.0, seconds),
        _chain((640, 480), 30.0, 0.05, seconds),
    ]
    if not quick:
        RESULTS.mkdir(parents=True, exist_ok=True)
        (RESULTS / "live.json").write_text(json.dumps({"per_frame": per_frame, "chain": chains}, indent=1) + "\n")
        md = ["| tracking one 720p frame, one core | p50 | p99 | max |", "|---|---|---|---|"]
        md += [
            f"| {p['scenario']} | {p['p50_ms']:.2f} ms | {p['p99_ms']:.2f} ms | {p['max_ms']:.2f} ms |"
            for p in per_frame
        ]
        md += [
            "",
            "| camera | camera latency | frames sent / tracked / dropped | capture → result p50 / p95 | frame → result p50 | "
            "tilt RMS θx / θy |",
            "|---|---|---|---|---|---|",
        ]
        md += [
            f"| {c['size']} {c['fps']:.0f} fps | {c['camera_latency_ms']:.0f} ms | {c['frames_sent']} / {c['frames_tracked']} / "
            f"{c['dropped']} | {c['latency_ms_p50']:.2f} / {c['latency_ms_p95']:.2f} ms | {c['frame_to_result_ms_p50']:.1f} ms | "
            f"{c['tilt_x_rms_deg']:.3f}° / {c['tilt_y_rms_deg']:.3f}° |"
            for c in chains
        ]
        (RESULTS / "live.md").write_text("\n".join(md) + "\n")
    rows: list[tuple[str, float, str]] = []
    for p in per_frame:
        rows += [
            (f"720p frame, one core, {p['scenario']}: p50", p["p50_ms"], "ms"),
            (f"720p frame, one core, {p['scenario']}: p99", p["p99_ms"], "ms"),
        ]
    for c in chains:
        tag = f"{c['size']} {c['fps']:.0f} fps, camera {c['camera_latency_ms']:.0f} ms"
        rows += [
            (f"{tag}: capture → result p50", c["latency_ms_p50"], "ms"),
            (f"{tag}: capture → result p95", c["latency_ms_p95"], "ms"),
            (f"{tag}: frame → result p50", c["frame_to_result_ms_p50"], "ms"),
            (f"{tag}: dropped", c["dropped"], "frames"),
            (f"{tag}: tilt x RMS", c["tilt_x_rms_deg"], "deg"),
            (f"{tag}: tilt y RMS", c["tilt_y_rms_deg"], "deg"),
        ]
    return rows


if __name__ == "__main__":
    import sys

    for name, value, unit in run(quick="--quick" in sys.argv):
        print(f"{name:<70} {value:>12.4g} {unit}")
