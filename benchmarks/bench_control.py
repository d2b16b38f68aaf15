"""Closed loop on the FRI simulator (issue #19): `lbr control upright` swings the pendulum module's rod up and
balances it for 60 s with a 10° push, rods 0.3–0.75 m, encoder delay 5 and 10 ms (+1 ms jitter), 1 ms FRI period.

Figures per case, from the log's simulated truth (``pendulum_phi``) and commands: swing-up time, falls, the largest
angle from upright while balancing (before the push and in the last 10 s), the largest joint velocity and
acceleration of the commands as a share of the limits, missed FRI cycles, and the controller's per-cycle cost.
`python benchmarks/bench_control.py [--quick]` (quick: 0.5 m rod, 5 ms, 15 s hold).
"""

from __future__ import annotations

import csv
import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np


def _log(path: Path) -> dict[str, np.ndarray]:
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    head = rows[0]
    data = np.array([[float(x) if x else math.nan for x in r] for r in rows[1:]])
    return {n: data[:, i] for i, n in enumerate(head)}


def case(rod: float, delay_ms: float, hold: float, push_at: float) -> list[tuple[str, float, str]]:
    from trajectories.limits import default_limits

    tag = f"rod {rod:g} m, delay {delay_ms:g} ms"
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "run.csv"
        cmd = [sys.executable, "-m", "lbrcli", "control", "upright", "--rod-length", str(rod), "--hold", str(hold),
               "--sim-delay", str(delay_ms), "--push", f"10deg@{push_at}", "--log", str(log), "--json"]
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=hold + 200)
        fig = json.loads(p.stdout) if p.stdout.strip().startswith("{") else {}
        d = _log(log) if log.exists() else None
    out = [(f"{tag}: exit code", float(p.returncode), "")]
    if d is None or not fig:
        return out
    t = d["t"]
    up = np.degrees(np.abs(np.angle(np.exp(1j * (d["pendulum_phi"] - np.pi)))))
    mode = d["mode"]
    bal = np.flatnonzero(mode == 1)
    lim = default_limits()
    active = d["state"] == 4
    q = np.column_stack([d[f"cmd_q{j}"] for j in range(1, 8)])[active]
    dt = float(np.median(np.diff(t)))
    v = np.abs(np.diff(q, axis=0)) / dt
    a = np.abs(np.diff(q, 2, axis=0)) / dt**2
    out += [
        (f"{tag}: swing-up (start to first catch)", fig.get("swing_up_s") or math.nan, "s"),
        (f"{tag}: balanced in total", fig.get("balanced_s", 0.0), "s"),
        (f"{tag}: falls after the first catch", float(fig.get("falls", -1)), ""),
    ]
    if bal.size:
        t0 = t[bal[0]]
        settled = (t > t0 + 2.0) & (t < push_at)
        last = (t > t[bal[-1]] - 10.0) & (t <= t[bal[-1]])
        after = (t > push_at) & (t <= t[bal[-1]])

        def peak(mask):
            return float(up[mask].max()) if mask.any() else math.nan

        out += [
            (f"{tag}: max |angle from upright| balancing, before the push", peak(settled), "deg"),
            (f"{tag}: max |angle from upright| after the push", peak(after), "deg"),
            (f"{tag}: max |angle from upright| in the last 10 s", peak(last), "deg"),
        ]
    out += [
        (f"{tag}: max joint velocity / limit", float(np.max(v / lim.velocity)), ""),
        (f"{tag}: max joint acceleration / limit (2nd differences)", float(np.max(a / lim.acceleration)), ""),
        (f"{tag}: missed FRI cycles", float(fig.get("missed", -1)), ""),
        (f"{tag}: min tracking performance", float(fig.get("min_tracking", math.nan) or math.nan), ""),
        (f"{tag}: controller per cycle p50", fig.get("controller_us_p50") or math.nan, "µs"),
        (f"{tag}: controller per cycle p99", fig.get("controller_us_p99") or math.nan, "µs"),
        (f"{tag}: reply latency p99", fig.get("latency_p99_ms") or math.nan, "ms"),
    ]
    return out


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    if quick:
        return case(0.5, 5.0, 15.0, 12.0)
    out: list[tuple[str, float, str]] = []
    for rod in (0.3, 0.5, 0.75):
        for delay in (5.0, 10.0):
            out += case(rod, delay, 60.0, 40.0)
    return out


if __name__ == "__main__":
    for k, v, u in run(quick="--quick" in sys.argv):
        print(f"{k:<75} {v:>10.4g} {u}")
