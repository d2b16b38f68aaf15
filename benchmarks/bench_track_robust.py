"""Tracking hard cases (issue #16) on rendered videos with ground truth, one figure set per scenario:
found share of the frames where the ball is visible, false fixes (> 5 px off), centre and θ RMS errors,
tracking / decoding time. Goals: ≥ 99 % found and 0 false fixes on every non-adversarial video, θ ≤ 0.2° RMS
(tilted camera with calibration included), tracking ≤ 2× decoding time. Adversarial (reported only): a
swing-up at 30 fps with the shutter open the whole frame.
"""

from __future__ import annotations

import math
import tempfile
import time
from pathlib import Path

import numpy as np


def _decode(path: Path) -> float:
    from tracking.video import iter_frames

    t0 = time.perf_counter()
    for _ in iter_frames(path):
        pass
    return time.perf_counter() - t0


def _one(name: str, folder: Path, size: tuple[int, int], duration_s: float, repeats: int) -> list[tuple[str, float, str]]:
    from tracking import scenarios
    from tracking.color import color_spec
    from tracking.pipeline import track_video

    sc = scenarios.ALL[name](folder / f"{name}.mp4", size, duration_s)
    kw = dict(sc.track_kwargs)
    ball = kw.pop("ball", color_spec("red"))
    _decode(sc.path)  # warm the file cache
    decode = tracking = math.inf
    track = None
    for _ in range(repeats):  # interleaved, best of: the machine is shared
        decode = min(decode, _decode(sc.path))
        t0 = time.perf_counter()
        track = track_video(sc.path, ball, **kw)
        tracking = min(tracking, time.perf_counter() - t0)
    out = scenarios.score(sc, track)
    label = f"{sc.name}{' (adversarial)' if sc.adversarial else ''}"
    rows = [
        (f"{label}: found", out.found_percent, "%"),
        (f"{label}: false fixes", out.false_fixes, "frames"),
        (f"{label}: centre RMS", out.centre_rms_px, "px"),
        (f"{label}: track / decode time", tracking / decode, "x"),
    ]
    if math.isfinite(out.theta_rms_deg):
        rows.insert(3, (f"{label}: theta RMS", out.theta_rms_deg, "deg"))
    if name == "tilted":  # `compare` against the true motion delayed by 0.5 s: the lag must come out right
        from tracking.compare import compare_angles

        lag = 0.5
        cmp = compare_angles(sc.truth.t - lag, sc.truth.theta, track.t, track.theta)
        rows.append((f"{label}: compare lag error", abs(cmp.lag_s - lag) * sc.truth.fps, "frames"))
    return rows


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    from tracking import scenarios

    size, duration, repeats = ((640, 360), 2.0, 1) if quick else ((1280, 720), 6.0, 2)
    rows: list[tuple[str, float, str]] = [(f"videos {size[0]}x{size[1]}", duration, "s each")]
    with tempfile.TemporaryDirectory() as tmp:
        for name in scenarios.ALL:
            rows += _one(name, Path(tmp), size, duration, repeats)
        if not quick:  # whole-frame searches at 1080p: the ball invisible for the first 0.4 s
            rows += [(f"1080p {k}", v, u) for k, v, u in _one("dark_start", Path(tmp), (1920, 1080), 3.0, repeats)]
    goals = [r for r in rows if "(adversarial)" not in r[0]]
    found = [v for k, v, _ in goals if k.endswith(": found")]
    false = [v for k, v, _ in goals if k.endswith(": false fixes")]
    theta = [v for k, v, _ in goals if k.endswith(": theta RMS")]
    ratio = [v for k, v, _ in goals if k.endswith("track / decode time")]
    rows += [
        ("goal videos: worst found", float(np.min(found)), "%"),
        ("goal videos: false fixes in all", float(np.sum(false)), "frames"),
        ("goal videos: worst theta RMS", float(np.max(theta)), "deg"),
        ("goal videos: worst track / decode time", float(np.max(ratio)), "x"),
    ]
    return rows


if __name__ == "__main__":
    import sys

    for name, value, unit in run(quick="--quick" in sys.argv):
        print(f"{name:<60} {value:>12.4g} {unit}")
