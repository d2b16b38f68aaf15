"""`lbr view` and `lbr export` on a real 60 s, 1 kHz execution log (`lbr execute` on the simulator with its ball).

Goals (issue #37): the log opens in the view in ≤ 5 s and plays at real time or faster; the demo's offline file
≤ 20 MB; export to MCAP ≤ 2× the time lbr takes to read the CSV; every message read back by independent readers
(rosbags; mcap + mcap-ros2-support) equals the log.

    python benchmarks/bench_view.py [--quick]    # figures → benchmarks/results/view_export.json (the view guide
                                                 # quotes them with lbr:bench markers)
    python benchmarks/bench_view.py --export-only  # only the export rows again (a fresh 60 s log; the view's
                                                   # figures kept from the file)
"""

from __future__ import annotations

import io
import json
import subprocess
import sys
import tempfile
import time
from contextlib import redirect_stdout
from pathlib import Path

import numpy as np
from trajectories.start_poses import THESIS_START

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results" / "view_export.json"
Q0 = np.array(THESIS_START)  # [rad]
AXES = np.array([0.35, 0.2, -0.15, 0.3, 0.1, -0.25, 0.4])  # [rad]


def _lbr(*args: str, cwd: Path, timeout: float = 900) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "lbrcli", *map(str, args)], cwd=cwd, capture_output=True, text=True, timeout=timeout
    )


def make_log(folder: Path, seconds: float) -> Path:
    """A joint path of ``seconds`` at 1 ms (slow smooth excursions, one per 10 s, at rest at both ends) executed on the
    simulator (retried: on a loaded machine the simulated controller may end a session)."""
    from trajectories.csvio import write_joint_csv
    from trajectories.trajectory import JointTrajectory

    t = np.arange(0.0, seconds + 1e-9, 0.001)
    s = (1 - np.cos(2 * np.pi * max(1, round(seconds / 10)) * t / seconds)) / 2
    write_joint_csv(folder / "path.csv", JointTrajectory(t=t, q=Q0 + s[:, None] * AXES))
    for _ in range(3):
        proc = _lbr(
            "execute",
            "path.csv",
            "--port",
            "0",
            "--log",
            "log.csv",
            "--length",
            "0.25",
            "--settle",
            "1",
            "--sim-lenient",
            "--realtime",
            "--json",
            cwd=folder,
        )
        if proc.returncode == 0:
            return folder / "log.csv"
    raise RuntimeError(f"lbr execute failed: {proc.stderr[-400:]}")


WARM_UP_S = 3.0  # [s] after the arm appears, before the play rate is measured
BROWSER_SETTLE_S = 2.0  # [s] the launched browser's own start-up finishes before the clock starts
PLAY_WINDOW_S = 10.0  # [s] over which the play rate (scene time per wall time in the page) is measured


def measure_view(log: Path, folder: Path) -> dict[str, float]:
    """Seconds from `lbr view LOG` to the arm drawn in headless Chromium; scene time per wall time while playing
    (steady: over ``PLAY_WINDOW_S`` from ``WARM_UP_S`` after the arm appeared — the first 5 s measured 0.67× at load 9,
    the page still loading)."""
    from lbrcli.view.testing import chromium_path, page, status, status_time, wait_for_scene

    if chromium_path() is None:
        return {}
    out: dict[str, float] = {}
    with page() as (pg, console):
        pg.goto("about:blank")  # the browser is up and idle, as a user's is, before `lbr view` starts
        time.sleep(BROWSER_SETTLE_S)
        t0 = time.perf_counter()
        proc = subprocess.Popen(
            [sys.executable, "-m", "lbrcli", "view", str(log), "--port", "0", "--duration", "120", "--json"],
            cwd=folder,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        try:
            lines = []
            for line in proc.stderr:
                lines.append(line)
                if line.startswith("view: "):
                    break
            else:
                raise RuntimeError("lbr view did not serve: " + "".join(lines)[-400:])
            url = lines[-1].split()[1]
            out["view_server_ready_s"] = time.perf_counter() - t0
            pg.goto(url)
            wait_for_scene(pg, "/arms/log/measured/body4", timeout=60)
            out["view_open_s"] = time.perf_counter() - t0
            time.sleep(WARM_UP_S)  # the page is still building the arm's meshes when the first body appears
            a_wall, a_scene = time.perf_counter(), status_time(status(pg))
            time.sleep(PLAY_WINDOW_S)
            b_wall, b_scene = time.perf_counter(), status_time(status(pg))
            out["view_play_rate"] = (b_scene - a_scene) / (b_wall - a_wall)
            out["view_console_errors"] = float(sum(kind in ("error", "pageerror") for kind, _ in console))
        finally:
            proc.terminate()
            proc.wait(timeout=30)
    return out


def measure_export(log: Path, folder: Path, repeats: int) -> dict[str, float]:
    """Best-of export (in-process, the command as a user runs it) against best-of strict CSV read, interleaved."""
    from lbrcli.app import main
    from lbrcli.fri.log import LOG_COLUMNS, NAN_COLUMNS
    from trajectories.csvio import read_table

    out = folder / "log.mcap"
    t_read = t_export = cpu_read = cpu_export = float("inf")
    figures = best = {}
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        read_table(log, LOG_COLUMNS, time="increasing", nan_columns=NAN_COLUMNS)
        t_read, cpu_read = min(t_read, time.perf_counter() - t0), min(cpu_read, time.process_time() - c0)
        buf = io.StringIO()
        t0, c0 = time.perf_counter(), time.process_time()
        with redirect_stdout(buf):
            try:
                main(["export", str(log), "-o", str(out), "--json"])
            except SystemExit as exc:
                if exc.code:
                    raise
        seconds, cpu_export = time.perf_counter() - t0, min(cpu_export, time.process_time() - c0)
        figures = json.loads(buf.getvalue())
        if seconds < t_export:
            t_export, best = seconds, figures
    return {
        "export_s": t_export,
        "read_csv_s": t_read,
        "export_over_read": t_export / t_read,
        # CPU time of the process (all its threads): less sensitive to the other work on the machine
        "export_cpu_s": cpu_export,
        "read_csv_cpu_s": cpu_read,
        "export_over_read_cpu": cpu_export / cpu_read,
        # of the best run: the command's own CSV read, and the rest (series, TF, CDR, chunks, compression, file)
        "export_own_read_s": best["read_s"],
        "export_write_s": best["seconds"] - best["read_s"],
        "export_us_per_message": 1e6 * t_export / figures["messages"],
        "export_messages": float(figures["messages"]),
        "export_mb": figures["size_bytes"] / 1e6,
    }


def verify_export(log: Path, mcap_path: Path) -> dict[str, float]:
    """Messages of the four JointState topics read back by both readers that equal the log, of all."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    from rosbags.highlevel import AnyReader

    from lbrcli.fri.log import LOG_COLUMNS
    from trajectories.csvio import read_table

    table = read_table(log, LOG_COLUMNS, time="increasing")

    def joints(prefix):
        return np.column_stack([table.column(f"{prefix}{i}") for i in range(1, 8)])

    stamps = table.column("stamp_sec").astype(np.int64) * 1_000_000_000 + table.column("stamp_nsec").astype(np.int64)
    want = {
        "/lbr/joint_states": ("position", joints("msr_q"), "effort", joints("msr_tau")),
        "/lbr/command/joint_states": ("position", joints("cmd_q"), "effort", joints("cmd_tau")),
        "/lbr/ipo/joint_states": ("position", joints("ipo_q"), None, None),
        "/lbr/external_torque": ("effort", joints("ext_tau"), None, None),
    }
    total = equal_rosbags = equal_mcap = 0
    seen: dict[str, int] = {}

    def check(topic, k, when, msg) -> bool:
        f1, v1, f2, v2 = want[topic]
        stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        ok = when == stamps[k] == stamp and np.array_equal(np.asarray(getattr(msg, f1)), v1[k])
        return ok and (f2 is None or np.array_equal(np.asarray(getattr(msg, f2)), v2[k]))

    with AnyReader([mcap_path]) as reader:
        conns = [c for c in reader.connections if c.topic in want]
        for conn, when, raw in reader.messages(connections=conns):
            k = seen.get(conn.topic, 0)
            seen[conn.topic] = k + 1
            total += 1
            equal_rosbags += check(conn.topic, k, when, reader.deserialize(raw, conn.msgtype))
    seen.clear()
    with open(mcap_path, "rb") as fh:
        for _, channel, message, msg in make_reader(fh, decoder_factories=[DecoderFactory()]).iter_decoded_messages(
            topics=list(want)
        ):
            k = seen.get(channel.topic, 0)
            seen[channel.topic] = k + 1
            equal_mcap += check(channel.topic, k, message.log_time, msg)
    return {
        "joint_state_messages": float(total),
        "equal_rosbags": float(equal_rosbags),
        "equal_mcap": float(equal_mcap),
        "log_rows": float(len(stamps)),
    }


def measure_offline(log: Path, folder: Path) -> dict[str, float]:
    t0 = time.perf_counter()
    proc = _lbr("view", log.name, "-o", "log_view.html", "--json", cwd=folder)
    if proc.returncode != 0:
        raise RuntimeError(proc.stderr[-400:])
    return {
        "offline_60s_mb": json.loads(proc.stdout)["size_bytes"] / 1e6,
        "offline_60s_write_s": time.perf_counter() - t0,
    }


def measure_demo(folder: Path) -> dict[str, float]:
    proc = _lbr("demo", "--out", "demo", "--json", cwd=folder, timeout=1800)
    html = folder / "demo" / "swingup_view.html"
    if not html.exists():
        raise RuntimeError(f"lbr demo wrote no swingup_view.html: {proc.stderr[-400:]}")
    return {"demo_offline_mb": html.stat().st_size / 1e6}


EXPORT_KEYS = ("export_", "read_csv", "joint_state_messages", "equal_", "log_rows")  # what --export-only measures


def run(quick: bool = False, export_only: bool = False) -> list[tuple[str, float, str]]:
    import os

    seconds = 6.0 if quick else 60.0
    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        log = make_log(folder, seconds)
        if export_only:
            fig = {k: v["value"] for k, v in json.loads(RESULTS.read_text()).items() if not k.startswith(EXPORT_KEYS)}
        else:
            fig = {"log_seconds": seconds, "load_average_at_start": load}
            fig.update(measure_view(log, folder))
        fig |= {"export_load_average_at_start": load, "export_measured_at": time.time()}
        fig.update(measure_export(log, folder, 2 if quick else 3))
        fig.update(verify_export(log, folder / "log.mcap"))
        if not export_only:
            fig.update(measure_offline(log, folder))
            if not quick:
                fig.update(measure_demo(folder))
    units = {
        "_s": "s",
        "_mb": "MB",
        "rate": "× real time",
        "over_read": "×",
        "over_read_cpu": "×",
        "_us_per_message": "µs",
        "_measured_at": "s since 1970",
    }
    return [(k, float(v), next((u for suffix, u in units.items() if k.endswith(suffix)), "")) for k, v in fig.items()]


def main() -> int:
    quick, export_only = "--quick" in sys.argv, "--export-only" in sys.argv
    rows = run(quick, export_only)
    for name, value, unit in rows:
        print(f"  {name:<28} {value:>12.4g} {unit}")
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(json.dumps({k: {"value": v, "unit": u} for k, v, u in rows}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
