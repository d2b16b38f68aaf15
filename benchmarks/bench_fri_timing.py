"""1 ms FRI sessions on a busy PC: our clients against KUKA's own C++ client, in interleaved rounds on `lbr sim`.

`lbr sim` plays the controller at 1 ms with real-time priority (`--realtime`) and judges the connection quality as
KUKA's controller does (50-cycle window, 90 % timely replies for GOOD; below GOOD while commanding ends the session).
Each round runs every client once for ``--seconds`` of COMMANDING_ACTIVE, at default priority, in a rotating order:

- KUKA's LBRJointSineOverlayApp (C++, FRI client SDK 1.15), built from lbr-stack/fri's copy of the SDK with this
  machine's cmake and g++ outside the repository (``--kuka-src PATH``: a checkout of https://github.com/lbr-stack/fri;
  or the environment variable LBR_KUKA_FRI_SRC); skipped with the reason in the results when there is no source or
  no compiler (no KUKA code is committed here);
- `lbr execute` (with `--log`; also with `--busy-wait 0.1`, sleep-then-spin), `lbr serve` (holding while no target arrives), `lbr control damp` (the simulated
  ball's angle fed back), `lbr ptp`, and `examples/joint_sine_overlay.py` (a user's LBRClient) — all with defaults.

Two conditions, each its own set of rounds: ``quiet`` (whatever else the machine runs; the load average is
recorded) and ``busy`` (two more processes spinning at default priority beside everything). Then a third: `lbr
execute --realtime` for ``--realtime-seconds`` with the two busy processes (the goal: no session dropped, ≤ 0.1 %
late replies).

First each client once against a lenient simulator (1 s quality window, 50 % timely), so that its session lasts and
its CPU per message in steady commanding can be measured. Per session: kept (the simulator ended it by its duration, not by the quality rule), reply latency p50/p99/p99.9
[ms] (the simulator's send → the reply's arrival), late or missed replies (share of cycles), and CPU per answered
message [µs]: the client's process tree (threads and, for `--log`, the log writer process) from when it waits for the
first message until the simulator ends, over the replies the simulator received. Ratios to KUKA's client are taken
within each round (the VM's noise comes and goes over minutes) and reported as medians over the rounds.

Writes benchmarks/results/fri_timing.json and its tables, benchmarks/results/fri_timing.md (:func:`markdown`; the FRI
timing page includes them). Run: `python benchmarks/bench_fri_timing.py [--quick] [--rounds N]
[--seconds S] [--kuka-src PATH] [--clients damp,serve]` or `python benchmarks/run_all.py fri_timing [--quick]`
(``--clients``: a smaller run of some clients beside KUKA's, without the ``--realtime`` run; results not written).
"""

from __future__ import annotations

import argparse
import datetime
import glob
import json
import os
import platform
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np
from trajectories.start_poses import THESIS_START

ROOT = Path(__file__).resolve().parent.parent
RESULTS = Path(__file__).resolve().parent / "results" / "fri_timing.json"
KUKA_PORT = 30200  # KUKA's example clients bind it (no option)
KUKA_NAME = "KUKA LBRJointSineOverlayApp (C++)"
BUILD_DIR = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "lbr-bench" / "kuka-fri-1.15"
Q0 = np.array(THESIS_START)  # [rad] the simulator's default start
PY = [sys.executable]
LBR = [sys.executable, "-m", "lbrcli"]


# -- KUKA's client ---------------------------------------------------------------------------------------------------
def build_kuka(src: str | None) -> tuple[str | None, str]:
    """(path of LBRJointSineOverlayApp built from KUKA's SDK 1.15 in lbr-stack/fri at ``src``, how) or (None, why)."""
    src = src or os.environ.get("LBR_KUKA_FRI_SRC")
    exe = BUILD_DIR / "build" / "LBRJointSineOverlayApp"
    if exe.exists():
        return str(exe), f"cached build {exe}"
    if not src:
        return (
            None,
            "no KUKA SDK source: pass --kuka-src PATH (a checkout of github.com/lbr-stack/fri) or set LBR_KUKA_FRI_SRC",
        )
    missing = [t for t in ("cmake", "g++", "git") if shutil.which(t) is None]
    if missing:
        return None, f"cannot build KUKA's client: {', '.join(missing)} not found"
    tree = BUILD_DIR / "src"
    shutil.rmtree(BUILD_DIR, ignore_errors=True)
    tree.mkdir(parents=True)
    git = subprocess.run(
        f"git -C {src} archive fri-1.15 | tar -x -C {tree}", shell=True, capture_output=True, text=True
    )
    if git.returncode != 0:  # not a git checkout: take the tree as it is
        shutil.rmtree(tree)
        shutil.copytree(src, tree)
    steps = [["cmake", "-S", str(tree), "-B", str(BUILD_DIR / "build"), "-DBUILD_FRI_APPS=ON", "-DCMAKE_BUILD_TYPE=Release"],
             ["cmake", "--build", str(BUILD_DIR / "build"), "-j2", "--target", "LBRJointSineOverlayApp"]]  # fmt: skip
    for step in steps:
        r = subprocess.run(step, capture_output=True, text=True)
        if r.returncode != 0:
            return None, f"building KUKA's client failed: {(r.stderr or r.stdout).strip().splitlines()[-1:]}"
    return (str(exe), f"built from {src} (fri-1.15) in {BUILD_DIR}") if exe.exists() else (None, "no executable built")


# -- processes -------------------------------------------------------------------------------------------------------
def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _port_free(port: int) -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        try:
            s.bind(("", port))
            return True
        except OSError:
            return False


def tree_pids(pid: int) -> list[int]:
    """Process ``pid`` and its descendants (the log writer)."""
    children: dict[int, list[int]] = {}
    for stat in glob.glob("/proc/[0-9]*/stat"):
        try:
            fields = open(stat).read().rsplit(")", 1)[1].split()
            children.setdefault(int(fields[1]), []).append(int(stat.split("/")[2]))
        except (OSError, IndexError, ValueError):
            continue
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        out.append(p)
        todo += children.get(p, [])
    return out


def cpu_ns(pids: list[int]) -> int:
    """CPU time [ns] of the processes ``pids`` and all their threads (/proc schedstat)."""
    return sum(_pid_cpu_ns(p) for p in pids)


def _pid_cpu_ns(pid: int) -> int:
    total = 0
    for task in glob.glob(f"/proc/{pid}/task/*/schedstat"):
        try:
            total += int(open(task).read().split()[0])
        except (OSError, ValueError, IndexError):
            pass
    return total


class TreeCpu:
    """CPU time of a process tree as it changes: each process's last reading (a process that ended keeps it)."""

    def __init__(self, pid: int) -> None:
        self.pid = pid
        self.seen: dict[int, int] = {}
        self._scanned = 0.0
        self.total()

    def total(self) -> int:
        """[ns] the tree's CPU time so far (new descendants looked for at most once a second)."""
        if time.monotonic() - self._scanned > 1.0:
            for p in tree_pids(self.pid):
                self.seen.setdefault(p, 0)
            self._scanned = time.monotonic()
        for p in self.seen:
            self.seen[p] = max(self.seen[p], _pid_cpu_ns(p))
        return sum(self.seen.values())


def _wait_idle(proc: subprocess.Popen, limit_s: float = 60.0) -> None:
    """Until the client has started and waits (its CPU stands still for 0.4 s)."""
    t0 = time.monotonic()
    last = cpu_ns(tree_pids(proc.pid))
    time.sleep(0.5)
    while time.monotonic() - t0 < limit_s and proc.poll() is None:
        time.sleep(0.4)
        now = cpu_ns(tree_pids(proc.pid))
        if now - last < 8_000_000:  # < 2 % of a core
            return
        last = now


def _stop(proc: subprocess.Popen, grace_s: float = 5.0) -> None:
    try:
        proc.wait(grace_s)
    except subprocess.TimeoutExpired:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(5.0)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


class Busy:
    """``n`` processes spinning at default priority (the load beside the session)."""

    def __init__(self, n: int) -> None:
        self.procs = [subprocess.Popen(PY + ["-c", "while True: pass"], start_new_session=True) for _ in range(n)]

    def __enter__(self) -> "Busy":
        return self

    def __exit__(self, *exc: object) -> None:
        for p in self.procs:
            p.kill()
            p.wait()


# -- one session -----------------------------------------------------------------------------------------------------
def _trajectory(path: Path, seconds: float) -> None:
    from trajectories.csvio import write_joint_csv
    from trajectories.trajectory import JointTrajectory

    seconds = 10.0 * np.ceil(seconds / 10.0)  # whole 10 s swings: it starts and ends at rest
    t = np.arange(0.0, seconds + 1e-9, 1e-3)
    s = (1 - np.cos(2 * np.pi * t / 10.0)) / 2
    write_joint_csv(path, JointTrajectory(t=t, q=Q0 + s[:, None] * np.array([0.2, 0.1, -0.1, 0.15, 0.1, -0.2, 0.3])))


def clients(kuka: str | None, work: Path, seconds: float) -> dict[str, Callable[[int], list[str]]]:
    """Name → argv for a client on local port P (KUKA's binds 30200 itself)."""
    traj = work / "traj.csv"
    _trajectory(traj, seconds + 30.0)  # longer than the session: the simulator ends it
    robot = ["--robot", "127.0.0.1", "--wait", "60"]
    target = ",".join(f"{v:.4f}" for v in Q0 + np.array([0.3, 0.1, -0.2, 0.2, 0.2, -0.2, 0.3]))
    out: dict[str, Callable[[int], list[str]]] = {}
    if kuka:
        out[KUKA_NAME] = lambda p: [kuka]
    out["lbr execute --log"] = lambda p: (
        LBR + ["execute", str(traj), *robot, "--port", str(p), "--log", str(work / f"log{p}.csv"), "--json"]
    )
    out["lbr execute --log --busy-wait 0.1"] = lambda p: LBR + ["execute", str(traj), *robot, "--port", str(p), "--log",
                                                                str(work / f"log{p}.csv"), "--busy-wait", "0.1", "--json"]  # fmt: skip
    out["lbr serve"] = lambda p: LBR + ["serve", *robot, "--port", str(p), "--listen", f"127.0.0.1:{_free_port()}",
                                        "--first-target", "600", "--json"]  # fmt: skip
    out["lbr control damp"] = lambda p: (
        LBR + ["control", "damp", str(traj), *robot, "--port", str(p), "--length", "0.5", "--json"]
    )
    out["lbr ptp"] = lambda p: LBR + ["ptp", target, "--time", str(seconds + 30.0), *robot, "--port", str(p), "--json"]
    out["examples/joint_sine_overlay.py"] = lambda p: PY + [str(ROOT / "examples" / "joint_sine_overlay.py"), "--robot",
                                                            "127.0.0.1", "--port", str(p), "--duration", "600"]  # fmt: skip
    return out


LENIENT = ("--quality-window", "1000", "--quality-good", "0.5")  # a session that lasts, to measure the CPU


def session(argv: Callable[[int], list[str]], kuka: bool, seconds: float, ball: bool, sim_args=()) -> dict[str, Any]:
    """One client against `lbr sim --realtime` for ``seconds`` of COMMANDING_ACTIVE: the figures."""
    port = KUKA_PORT if kuka else _free_port()
    # every process in its own session (as from its own terminal: Linux's autogroups share the CPU by session)
    client = subprocess.Popen(
        argv(port), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=ROOT, start_new_session=True
    )
    try:
        _wait_idle(client)
        tree = TreeCpu(client.pid)
        cpu0 = tree.total()
        sim = subprocess.Popen(LBR + ["sim", "--realtime", "--json", "--period", "1", "--client", f"127.0.0.1:{port}",
                                      "--duration", str(seconds), "--timeout", str(seconds + 60), *sim_args]
                               + (["--length", "0.5"] if ball else []), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, start_new_session=True)  # fmt: skip
        states: list[tuple[float, str]] = []  # (time.monotonic(), state) as the simulator reports them

        def follow() -> None:
            for line in sim.stderr:  # type: ignore[union-attr]
                words = line.split()
                if len(words) > 2 and words[1] == "s" and words[2].isupper():
                    states.append((time.monotonic(), words[2]))

        reader = threading.Thread(target=follow, daemon=True)
        reader.start()
        cpu1 = cpu0
        steady: list[tuple[float, int]] = []  # (time, CPU [ns]) from 1 s into COMMANDING_ACTIVE while it lasts
        while sim.poll() is None:  # the client's CPU until the simulator ends (or the client does)
            if client.poll() is not None:  # the client gave up: the simulator closes the session
                time.sleep(1.0)
                sim.send_signal(signal.SIGINT)
                break
            cpu1 = tree.total()
            now = time.monotonic()
            if states and states[-1][1] == "COMMANDING_ACTIVE" and now - states[-1][0] >= 1.0:
                steady.append((now, cpu1))
            time.sleep(0.1)
        sim.wait()
        out = sim.stdout.read()  # type: ignore[union-attr]
        reader.join(5.0)
    finally:
        _stop(client)
    s = json.loads(out)
    replies = max(1, s["replies"])
    return {
        "kept": s["end_reason"] == "duration",
        "end_reason": s["end_reason"],
        "active_cycles": s["active_cycles"],
        "cycles": s["cycles"],
        # COMMANDING_ACTIVE cycles without a timely reply (late or missing): what the quality rule judges
        "late_share": s["untimely_active_cycles"] / max(1, s["active_cycles"]),
        "p50_ms": s["reply_latency_ms_p50"],
        "p99_ms": s["reply_latency_ms_p99"],
        "p999_ms": s.get("reply_latency_ms_p999"),
        "cpu_us_per_message": (cpu1 - cpu0) * 1e-3 / replies,  # the whole session, its start included
        # in COMMANDING_ACTIVE from 1 s after it began (one message per 1 ms period); None if it did not last 2 s
        "cpu_us_per_message_steady": (
            (steady[-1][1] - steady[0][1]) * 1e-3 / ((steady[-1][0] - steady[0][0]) * 1e3) if len(steady) > 10 else None
        ),
        "sim_realtime": s["realtime"],
        "sim_cpu_fraction": s["cpu_fraction"],  # of one core: the simulator's own load (the ball adds to it)
        "sim_period_ms_max": s["period_ms_max"],
    }


def condition(names: dict[str, Callable[[int], list[str]]], rounds: int, seconds: float) -> dict[str, Any]:
    """``rounds`` interleaved rounds of every client (rotating order); per client its sessions and summary."""
    load = [os.getloadavg()]
    per: dict[str, list[dict[str, Any]]] = {n: [] for n in names}
    order = list(names)
    for r in range(rounds):
        for name in order[r % len(order) :] + order[: r % len(order)]:
            res = session(names[name], name == KUKA_NAME, seconds, ball=name == "lbr control damp")
            res["round"] = r
            per[name].append(res)
            print(f"  round {r + 1}/{rounds} {name:<34} kept {res['kept']!s:<5} ({res['end_reason']}) "
                  f"p50 {res['p50_ms'] or 0:.3f} p99 {res['p99_ms'] or 0:.3f} p99.9 {res['p999_ms'] or 0:.3f} ms, "
                  f"late {res['late_share'] * 100:.2f} %, CPU {res['cpu_us_per_message']:.0f} µs/msg (steady "
                  f"{res['cpu_us_per_message_steady'] or float('nan'):.0f}), load "
                  f"{os.getloadavg()[0]:.2f}", flush=True)  # fmt: skip
    load.append(os.getloadavg())
    out: dict[str, Any] = {"load_average_1_5_15_start": load[0], "load_average_1_5_15_end": load[1], "clients": {}}
    kuka = per.get(KUKA_NAME)
    for name, runs in per.items():
        summary: dict[str, Any] = {
            "sessions_kept": sum(r["kept"] for r in runs),
            "sessions": len(runs),
            "p50_ms_median": _median(r["p50_ms"] for r in runs),
            "p99_ms_median": _median(r["p99_ms"] for r in runs),
            "p999_ms_median": _median(r["p999_ms"] for r in runs),
            "late_share_median": _median(r["late_share"] for r in runs),
            "cpu_us_per_message_median": _median(r["cpu_us_per_message"] for r in runs),
            "cpu_us_per_message_steady_median": _median(r["cpu_us_per_message_steady"] for r in runs),
            "runs": runs,
        }
        if kuka and name != KUKA_NAME:
            for q in ("p50", "p99", "p999"):
                ratios = [a[f"{q}_ms"] / b[f"{q}_ms"] for a, b in zip(runs, kuka) if a[f"{q}_ms"] and b[f"{q}_ms"]]
                summary[f"{q}_ratio_to_kuka_median"] = _median(ratios)
                summary[f"{q}_ratio_to_kuka_range"] = [min(ratios), max(ratios)] if ratios else None
        out["clients"][name] = summary
    return out


def cpu_condition(names: dict[str, Callable[[int], list[str]]], seconds: float) -> dict[str, Any]:
    """CPU per message of each client in a session that lasts (the simulator's quality rule relaxed to a 1 s window
    and 50 % timely replies), from 1 s into COMMANDING_ACTIVE to its end."""
    out: dict[str, Any] = {"load_average_1_5_15_start": os.getloadavg(), "clients": {}}
    for name, argv in names.items():
        res = session(argv, name == KUKA_NAME, seconds, ball=name == "lbr control damp", sim_args=LENIENT)
        out["clients"][name] = res
        print(f"  {name:<34} CPU {res['cpu_us_per_message_steady'] or float('nan'):.0f} µs per message in steady "
              f"commanding ({res['end_reason']}), load {os.getloadavg()[0]:.2f}", flush=True)  # fmt: skip
    out["load_average_1_5_15_end"] = os.getloadavg()
    return out


def _median(values) -> float | None:
    v = [x for x in values if x is not None]
    return float(np.median(v)) if v else None


def realtime_run(seconds: float) -> dict[str, Any]:
    """`lbr execute --realtime` for ``seconds`` with two busy processes beside it."""
    with tempfile.TemporaryDirectory() as tmp, Busy(2):
        work = Path(tmp)
        traj = work / "traj.csv"
        _trajectory(traj, seconds + 30.0)
        load0 = os.getloadavg()
        res = session(lambda p: LBR + ["execute", str(traj), "--robot", "127.0.0.1", "--wait", "60", "--port", str(p),
                                       "--log", str(work / "log.csv"), "--realtime", "--json"],
                      False, seconds, ball=False)  # fmt: skip
        res["load_average_1_5_15_start"], res["load_average_1_5_15_end"] = load0, os.getloadavg()
    return res


def _ms(v) -> str:
    return "—" if v is None else f"{v:.3f}"


def _loads(values) -> str:
    return ", ".join(f"{v:.2f}" for v in values)


def markdown(results: dict[str, Any]) -> str:
    """The tables of a results file (``fri_timing.json``), as the FRI timing page shows them."""
    lines = [f"Run of {results['date']} ({results['machine']['cpus']} cores, Linux {results['machine']['kernel']}, "
             f"Python {results['machine']['python']}), {results['rounds']} interleaved rounds × "
             f"{results['seconds_per_session']:g} s of COMMANDING_ACTIVE per client and condition; KUKA's client: "
             f"{'measured' if results['kuka_client']['path'] else 'skipped — ' + results['kuka_client']['how']}.", "",
             "| client | CPU per message, steady commanding [µs] | COMMANDING_ACTIVE cycles without a timely reply [%] |",
             "|---|---|---|"]  # fmt: skip
    for name, r in results["cpu"]["clients"].items():
        cpu = r["cpu_us_per_message_steady"]
        shown = f"{cpu:.0f}" if cpu is not None else f"session did not last ({r['end_reason']})"
        lines.append(f"| {name} | {shown} | {r['late_share'] * 100:.2f} |")
    lines += [
        "",
        f"Load average (1, 5, 15 min) at the start of that part: {_loads(results['cpu']['load_average_1_5_15_start'])}.",
    ]
    titles = {
        "quiet": "Quiet (nothing added; other work on the machine as it was)",
        "busy": "Busy (two spinning processes added)",
    }
    for cond, c in results["conditions"].items():
        lines += ["", f"**{titles.get(cond, cond)}** — load average at start {_loads(c['load_average_1_5_15_start'])}, at end "
                  f"{_loads(c['load_average_1_5_15_end'])}", "",
                  "| client | sessions kept | COMMANDING_ACTIVE cycles reached (per round) | reply p50 / p99 / p99.9 [ms] "
                  "(medians) | p50 / p99 / p99.9 ÷ KUKA's (median of rounds) |", "|---|---|---|---|---|"]  # fmt: skip
        for name, s_ in c["clients"].items():
            cycles = ", ".join(str(r["active_cycles"]) for r in s_["runs"])
            ratios = [s_.get(f"{q}_ratio_to_kuka_median") for q in ("p50", "p99", "p999")]
            ratio = (
                "—" if all(r is None for r in ratios) else " / ".join("—" if r is None else f"{r:.2f}" for r in ratios)
            )
            lines.append(
                f"| {name} | {s_['sessions_kept']} of {s_['sessions']} | {cycles} | "
                f"{_ms(s_['p50_ms_median'])} / {_ms(s_['p99_ms_median'])} / {_ms(s_['p999_ms_median'])} | {ratio} |"
            )
    rt = results["realtime"]
    cpu = rt.get("cpu_us_per_message_steady")
    lines += ["", f"**`lbr execute --log --realtime`, two spinning processes beside it** — load average "
              f"{_loads(rt['load_average_1_5_15_start'])} → {_loads(rt['load_average_1_5_15_end'])}: session "
              f"{'kept' if rt['kept'] else 'not kept (' + str(rt['end_reason']) + ')'}, {rt['late_share'] * 100:.3f} % of the "
              f"COMMANDING_ACTIVE cycles without a timely reply ({rt['active_cycles']} cycles), reply p50 / p99 / p99.9 "
              f"{_ms(rt['p50_ms'])} / {_ms(rt['p99_ms'])} / {_ms(rt['p999_ms'])} ms, CPU "
              f"{'—' if cpu is None else f'{cpu:.0f}'} µs per message (the client and its log writer)."]  # fmt: skip
    return "\n".join(lines) + "\n"


def run(quick: bool = False, rounds: int | None = None, seconds: float | None = None, kuka_src: str | None = None,
        realtime_seconds: float | None = None, only: str | None = None) -> list[tuple[str, float, str]]:  # fmt: skip
    rounds = rounds or (2 if quick else 3)
    seconds = seconds or (3.0 if quick else 10.0)
    realtime_seconds = realtime_seconds or (10.0 if quick else 60.0)
    kuka, how = build_kuka(kuka_src)
    if kuka and not _port_free(KUKA_PORT):
        kuka, how = None, f"UDP port {KUKA_PORT} is taken (KUKA's client needs it)"
    print(f"KUKA's client: {kuka or 'skipped'} — {how}", flush=True)
    results: dict[str, Any] = {
        "date": datetime.datetime.now().isoformat(timespec="seconds"),
        "machine": {"cpus": os.cpu_count(), "kernel": platform.release(), "python": platform.python_version()},
        "period_ms": 1, "seconds_per_session": seconds, "rounds": rounds,
        "kuka_client": {"path": kuka, "how": how},
        "conditions": {},
    }  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        names = clients(kuka, Path(tmp), seconds)
        if only:  # a smaller run: the clients whose names contain one of these words (KUKA's kept as the reference)
            words = [w.strip() for w in only.split(",") if w.strip()]
            names = {n: a for n, a in names.items() if n == KUKA_NAME or any(w in n for w in words)}
        print("CPU per message (lenient quality rule: sessions that last)", flush=True)
        results["cpu"] = cpu_condition(names, seconds)
        print("condition quiet", flush=True)
        results["conditions"]["quiet"] = condition(names, rounds, seconds)
        print("condition busy (two spinning processes beside it)", flush=True)
        with Busy(2):
            results["conditions"]["busy"] = condition(names, rounds, seconds)
    if only:  # a partial run: no --realtime run, and the results are not replaced
        return _rows(results)
    print(f"lbr execute --realtime, {realtime_seconds:g} s, two spinning processes beside it", flush=True)
    results["realtime"] = realtime_run(realtime_seconds)
    _write(results)
    return _rows(results)


def _write(results: dict[str, Any]) -> None:
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    tmp_out = RESULTS.with_suffix(".json.tmp")
    tmp_out.write_text(json.dumps(results, indent=1) + "\n")
    tmp_out.replace(RESULTS)
    tmp_md = RESULTS.with_suffix(".md.tmp")
    tmp_md.write_text(markdown(results))
    tmp_md.replace(RESULTS.with_suffix(".md"))


def _rows(results: dict[str, Any]) -> list[tuple[str, float, str]]:
    rows: list[tuple[str, float, str]] = []
    for cond, c in results["conditions"].items():
        for name, s in c["clients"].items():
            rows.append((f"{cond}: {name}: sessions kept of {s['sessions']}", float(s["sessions_kept"]), "sessions"))
            rows.append(
                (f"{cond}: {name}: CPU per message, whole session (median)", s["cpu_us_per_message_median"], "µs")
            )
            rows.append(
                (
                    f"{cond}: {name}: CPU per message, steady commanding (median)",
                    s["cpu_us_per_message_steady_median"] or float("nan"),
                    "µs",
                )
            )
            rows.append((f"{cond}: {name}: reply p99 (median)", s["p99_ms_median"] or float("nan"), "ms"))
            if s.get("p99_ratio_to_kuka_median") is not None:
                rows.append((f"{cond}: {name}: p99 / KUKA's (median of rounds)", s["p99_ratio_to_kuka_median"], "×"))
    for name, r in results["cpu"]["clients"].items():
        rows.append(
            (f"CPU per message in steady commanding: {name}", r["cpu_us_per_message_steady"] or float("nan"), "µs")
        )
    rt = results.get("realtime")
    if rt is not None:
        rows += [
            ("--realtime: session kept", float(rt["kept"]), "bool"),
            ("--realtime: late or missed replies", rt["late_share"] * 100, "%"),
        ]
    return rows


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--rounds", type=int)
    ap.add_argument("--seconds", type=float)
    ap.add_argument("--realtime-seconds", type=float)
    ap.add_argument("--kuka-src")
    ap.add_argument("--clients", help="only the clients whose names contain one of these comma-separated words "
                    "(e.g. 'damp,serve'; KUKA's client always runs); the results files are then not written")  # fmt: skip
    a = ap.parse_args()
    for n, v, u in run(a.quick, a.rounds, a.seconds, a.kuka_src, a.realtime_seconds, a.clients):
        print(f"  {n:<75} {v:>10.4g} {u}")
