"""FRI client timing: reply latency measured from a separate process acting as the controller.

The client is the real command, `lbr execute TRAJ.csv --robot 127.0.0.1 --log LOG.csv --json`, in its own process.
This process plays the controller: every send period (1 ms, then 5 ms) it sends a monitoring message
(MONITORING_READY → COMMANDING_WAIT → COMMANDING_ACTIVE, ideal position tracking) and waits for the reply
reflecting it. A reply that has not arrived when the next message is due counts as missed. Figures: send → reply
latency p50/p99/max [ms], answered fraction, missed replies, and the client's own CPU time per cycle [µs] and
internal receive → send latency (from its --json), and the share of replies it prepared a cycle ahead (the rows are
known: the reply goes out once the message is decoded and checked). 1 ms is measured with the defaults (no busy-wait
since #40: the client blocks in the kernel until each message arrives), with `--busy-wait 0.2`, `--busy-wait 0` and
`--realtime` (SCHED_FIFO, one CPU, mlockall; needs root or CAP_SYS_NICE + CAP_IPC_LOCK, else exit 2). The comparison
with KUKA's client on `lbr sim` under load is `bench_fri_timing.py`.
Full: 60 s of streaming per run; quick: 5 s.

Floors on this machine, measured the same way: a C UDP echo (compiled here with cc) and a Python one. With
`--kuka=PATH` (repeatable) a KUKA example client built from KUKA's FRI client SDK (e.g. lbr-stack/fri's
LBRJointSineOverlayApp; it binds port 30200, so that port must be free) is measured the same way at 1 ms, in rounds
interleaved with `lbr execute` (6 × 10 s each; the VM's noise comes and goes over minutes, so the comparison is made
round by round and reported as medians). With root, the same clients are also compared on the wire against
`lbr sim` with a loopback packet sniffer, as issue #12's figures were taken (``fri_sniff.py``).

Run: `python benchmarks/run_all.py fri [--quick] [--kuka PATH ...]` or `python benchmarks/bench_fri.py [--quick] [--kuka=PATH ...]`.
"""

from __future__ import annotations

import json
import os
import select
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
from trajectories.start_poses import THESIS_START

Q0 = np.array(THESIS_START)  # [rad]
SETTLE_S = 0.05
_SO_TIMESTAMPNS = getattr(socket, "SO_TIMESTAMPNS", 35)  # Linux; the kernel's receive time of each datagram


def kernel_time_ns(anc: list[tuple[int, int, bytes]]) -> int | None:
    """The kernel's receive time [ns, time.time_ns clock] in a ``recvmsg`` ancillary list (SO_TIMESTAMPNS), if any."""
    return next((int.from_bytes(d[:8], "little") * 10**9 + int.from_bytes(d[8:16], "little")
                 for lvl, typ, d in anc if lvl == socket.SOL_SOCKET and typ == _SO_TIMESTAMPNS), None)  # fmt: skip


def kuka_version(path: str) -> str:
    """The FRI version of a KUKA example client, from its path (built from the SDK of that version)."""
    return "2.7" if "2.7" in path else "1.15"


def _free_port() -> int:
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def _trajectory(path: Path, period_s: float, duration_s: float) -> int:
    from trajectories.csvio import write_joint_csv
    from trajectories.trajectory import JointTrajectory

    t = np.arange(0.0, duration_s + 1e-12, period_s)
    s = (1 - np.cos(2 * np.pi * t / min(duration_s, 10.0))) / 2
    q = Q0 + s[:, None] * np.array([0.2, 0.1, -0.1, 0.15, 0.1, -0.2, 0.3])
    write_joint_csv(path, JointTrajectory(t=t, q=q))
    return len(t)


class _Controller:
    """A paced FRI controller on loopback running PositionHold (ipo constant) with an ideal robot (measured = last
    command)."""

    def __init__(self, client_port: int, period_ms: int, version: str = "1.15") -> None:
        from lbrcli.fri.codec import FriCodec

        self.codec = FriCodec(version)
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.setblocking(False)
        self.sock.setsockopt(socket.SOL_SOCKET, _SO_TIMESTAMPNS, 1)
        self.dest = ("127.0.0.1", client_port)
        self.period = period_ms * 1e-3
        self.msg = self.codec.new_monitoring()
        m = self.msg
        m.header.messageIdentifier, m.header.sequenceCounter, m.header.reflectedSequenceCounter = 0x245142, 0, 0
        m.connectionInfo.sessionState, m.connectionInfo.quality = 2, 3
        m.connectionInfo.sendPeriod, m.connectionInfo.receiveMultiplier = period_ms, 1
        m.robotInfo.numberOfJoints, m.robotInfo.safetyState = 7, 0
        m.robotInfo.driveState.extend([2] * 7)
        md = m.monitorData
        self.has_commanded = "commandedJointPosition" in md.DESCRIPTOR.fields_by_name  # 1.15 only
        for f in (
            "measuredJointPosition",
            "measuredTorque",
            "externalTorque",
            "commandedTorque",
            "commandedJointPosition",
        ):
            if f in md.DESCRIPTOR.fields_by_name:
                getattr(md, f).value.extend(Q0.tolist() if "Position" in f else [0.0] * 7)
        for name in ("ball_theta", "ball_phi", "ball_theta_x", "ball_theta_y"):
            io = md.readIORequest.add()
            io.name, io.type, io.direction, io.analogValue = name, 2, 0, 0.0
        m.ipoData.jointPosition.value.extend(Q0.tolist())
        m.ipoData.clientCommandMode, m.ipoData.overlayType = 1, 1
        self.q = Q0.tolist()
        self.cmd = self.codec.new_command()
        self.seq = 0

    def _fill(self, state: int) -> bytes:
        m = self.msg
        m.header.sequenceCounter = self.seq
        m.connectionInfo.sessionState = state
        m.ipoData.trackingPerformance = 1.0 if state == 4 else 0.0
        m.monitorData.measuredJointPosition.value[:] = self.q
        if self.has_commanded:
            m.monitorData.commandedJointPosition.value[:] = self.q
        m.monitorData.timestamp.sec = int(time.time())
        m.monitorData.timestamp.nanosec = 0
        return self.codec.encode(m)

    def exchange(self, data: bytes, deadline: float, accept: Callable[[bytes], bool]) -> tuple[int, int] | None:
        """Send ``data`` at ``deadline`` [perf_counter s]; (send, arrival) [ns, time.time_ns clock] of the first
        reply ``accept`` takes before the next send is due, or None. Arrival times are the kernel's receive
        timestamps (SO_TIMESTAMPNS), so a stall of this controller process after the arrival does not count against
        the client."""
        now = time.perf_counter()
        if deadline - now > 3e-4:
            time.sleep(deadline - now - 3e-4)
        while time.perf_counter() < deadline:
            pass
        t_send = time.time_ns()
        self.sock.sendto(data, self.dest)
        while True:
            left = deadline + self.period - time.perf_counter() - 1e-4
            if left > 0:
                select.select([self.sock], [], [], left)
            try:
                reply, anc, _, _ = self.sock.recvmsg(2048, 64)
            except BlockingIOError:
                if left > 0:
                    continue
                return None
            if accept(reply):
                t_rx = kernel_time_ns(anc) or time.time_ns()
                return t_send, t_rx

    def _reflects(self, reply: bytes, seq: int) -> bool:
        """``reply`` is a command message answering monitoring message ``seq`` (decoded into ``self.cmd``)."""
        try:
            c = self.codec.decode_command(reply, self.cmd)
        except Exception:  # noqa: BLE001
            return False
        return c.header.reflectedSequenceCounter == seq  # else a late reply to an earlier message

    def cycle(self, state: int, deadline: float) -> float | None:
        """Send one message at ``deadline`` [perf_counter s] and return the latency [s] of the reply reflecting it,
        or None if no reply arrived within the period."""
        data = self._fill(state)
        seq = self.seq
        self.seq += 1
        got = self.exchange(data, deadline, lambda reply: self._reflects(reply, seq))
        if got is None:
            return None
        t_send, t_rx = got
        c = self.cmd
        self.msg.header.reflectedSequenceCounter = c.header.sequenceCounter
        pos = c.commandData.jointPosition.value
        if state >= 3 and len(pos) == 7:
            self.q = list(pos)
        return (t_rx - t_send) * 1e-9 if t_rx <= t_send + int(self.period * 1e9) else None


def _measure(
    period_ms: int,
    duration_s: float,
    workdir: Path,
    realtime: bool = False,
    extra_args: tuple[str, ...] = (),
    tag: str | None = None,
    kuka: str | None = None,
) -> list[tuple[str, float, str]]:
    """One run against ``lbr execute`` — or, with ``kuka``, against that KUKA example client binary (FRI version
    from its path: 2.7 if it contains "2.7"), which binds the default port 30200."""
    traj = workdir / f"traj_{period_ms}ms.csv"
    log = workdir / f"log_{period_ms}ms.csv"
    n_rows = _trajectory(traj, period_ms * 1e-3, duration_s)
    if kuka is not None:
        port, version = 30200, kuka_version(kuka)
        client = subprocess.Popen([kuka], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, text=True, cwd=workdir)
    else:
        port, version = _free_port(), "1.15"
        client = subprocess.Popen(
            [sys.executable, "-m", "lbrcli", "execute", str(traj), "--robot", "127.0.0.1", "--port", str(port),
             "--log", str(log), "--settle", str(SETTLE_S), "--json", "--wait", "60"] + (["--realtime"] if realtime else [])
            + list(extra_args),
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )  # fmt: skip
    ctl = _Controller(port, period_ms, version)
    period = period_ms * 1e-3
    deadline = time.perf_counter() + period
    t_wait = time.monotonic()
    # until the client is up: MONITORING_READY until its first reply
    while ctl.cycle(2, deadline) is None:
        deadline = max(deadline + period, time.perf_counter())
        if time.monotonic() - t_wait > 60 or client.poll() is not None:
            client.kill()
            raise RuntimeError(f"client did not answer: {client.communicate()[1]}")
    lat: list[float] = []
    missed = 0
    phases = [(2, 200), (3, 10), (4, n_rows + int(round(SETTLE_S / period)))]
    for state, count in phases:
        for _ in range(count):
            deadline = max(deadline + period, time.perf_counter())
            r = ctl.cycle(state, deadline)
            if r is None:
                missed += 1
            else:
                lat.append(r)
    # the client stops answering after the settle rows; let it finish
    for _ in range(5):
        deadline = max(deadline + period, time.perf_counter())
        ctl.cycle(4 if kuka is None else 0, deadline)  # KUKA's clients leave at IDLE
    if kuka is not None:
        try:
            client.wait(2.0)
        except subprocess.TimeoutExpired:
            client.kill()
    out, err = client.communicate(timeout=60)
    ctl.sock.close()
    figures = json.loads(out) if out and out.strip() else {}
    arr = np.sort(np.array(lat)) * 1e3
    total = len(lat) + missed
    tag = tag or f"{period_ms} ms" + (" --realtime" if realtime else "")
    rows = [
        (f"{tag}: reply latency p50 (controller side)", float(np.percentile(arr, 50)), "ms"),
        (f"{tag}: reply latency p99 (controller side)", float(np.percentile(arr, 99)), "ms"),
        (f"{tag}: reply latency max (controller side)", float(arr[-1]), "ms"),
        (f"{tag}: answered within the period", len(lat) / total, "fraction"),
        (f"{tag}: missed replies of {total}", float(missed), "cycles"),
    ]
    if kuka is None:
        rows.append(
            (f"{tag}: trajectory rows commanded of {n_rows}", float(figures.get("trajectory_rows", -1)), "rows")
        )
        if figures.get("answered"):
            rows.append((f"{tag}: replies prepared a cycle ahead (TrajectoryPlayer.prepare_command)",
                         figures.get("prepared_replies", 0) / figures["answered"], "fraction"))  # fmt: skip
    if figures.get("cpu_us_per_cycle") is not None:
        rows += [
            (f"{tag}: client CPU per cycle (decode, guard, reply, log row)", figures["cpu_us_per_cycle"], "µs"),
            (f"{tag}: messages left unanswered at session start", figures.get("unanswered_at_start", -1), "messages"),
            (f"{tag}: client-internal receive→send p50", figures["latency_p50_ms"], "ms"),
            (f"{tag}: client-internal receive→send p99", figures["latency_p99_ms"], "ms"),
            (f"{tag}: client-internal receive→send max", figures["latency_max_ms"], "ms"),
        ]
    return rows


class _MemoryTransport:
    """In-memory stand-in for the UDP transport: hands out prepared datagrams, swallows the replies."""

    def __init__(self, datagrams: list[bytes]) -> None:
        self.datagrams, self.i, self.sent, self.port, self.robot_ip, self.foreign = datagrams, 0, 0, 0, "127.0.0.1", 0

    def receive(self) -> bytes | None:
        if self.i >= len(self.datagrams):
            return None
        self.i += 1
        return self.datagrams[self.i - 1]

    def send(self, data: bytes) -> None:
        self.sent += 1

    def drain(self) -> int:
        return 0

    def close(self) -> None:
        pass


def _processing_cost(n: int = 20000) -> list[tuple[str, float, str]]:
    """[µs] per cycle of the real loop (``ClientApplication.step`` with a ``TrajectoryPlayer``, the guard and the
    execution log to /dev/null) with the socket calls replaced by memory: the Python work of one FRI cycle."""
    from lbrcli.fri import ClientApplication, ExecutionLog, LogObserver, SessionFigures, TrajectoryPlayer
    from trajectories.limits import default_limits

    ctl = _Controller(9, 1)
    ctl.sock.close()
    preamble = [ctl._fill(2) for _ in range(5)] + [ctl._fill(3) for _ in range(3)]
    for d in preamble:
        ctl.seq += 1
    active = []
    for _ in range(n):
        active.append(ctl._fill(4))
        ctl.seq += 1
    t = np.arange(n) * 1e-3
    traj = Q0 + 1e-6 * np.outer(np.sin(t), np.ones(7))  # [rad] rows at 1 ms
    out, before = {}, {}
    for with_log, prepare in ((False, True), (True, True), (False, False)):
        best = best_before = float("inf")
        for _ in range(3):
            player = TrajectoryPlayer(traj, default_limits(), period_s=1e-3, start_tolerance=1e-3)
            app = ClientApplication(player, "127.0.0.1", 0, version="1.15", observers=[SessionFigures()],
                                    prepare=prepare)  # fmt: skip
            app.transport = _MemoryTransport(preamble + active)
            log = ExecutionLog(os.devnull) if with_log else None
            if log is not None:
                app.observers.insert(0, LogObserver(log))
            app.start()
            for _ in range(len(preamble) + 50):  # past the start checks and the plan at activation
                app.step()
            k0, j0 = app.transport.i, len(app.latencies)
            t0 = time.perf_counter()
            while app.transport.i < len(app.transport.datagrams) - 10 and app.step():
                pass
            k = app.transport.i - k0
            best = min(best, (time.perf_counter() - t0) / max(k, 1) * 1e6)
            # receive → reply handed to the (memory) socket: the Python work that delays each reply [ns]
            best_before = min(best_before, float(np.median(app.latencies[j0:])) * 1e-3)
            if log is not None:
                log.close()
        out[with_log, prepare] = best
        before[with_log, prepare] = best_before
    return [
        ("client Python work per cycle, real loop without socket I/O (decode, checks, player, guard, encode)",
         out[False, True], "µs"),
        ("... plus the execution log row", out[True, True], "µs"),
        ("... of which before the reply, replies prepared a cycle ahead (decode, checks; p50)", before[False, True], "µs"),
        ("... of which before the reply, cycle by cycle (prepare=False: + player, guard, encode; p50)",
         before[False, False], "µs"),
    ]  # fmt: skip


_C_ECHO = r"""
#include <stdlib.h>
#include <arpa/inet.h>
#include <sys/select.h>
#include <sys/socket.h>
int main(int argc, char **argv) {
  int s = socket(AF_INET, SOCK_DGRAM, 0);
  struct sockaddr_in a = {0}, from;
  a.sin_family = AF_INET; a.sin_port = htons(atoi(argv[1])); a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (bind(s, (struct sockaddr *)&a, sizeof a) != 0) return 1;
  char buf[2048];
  for (;;) {  /* as KUKA's client: select, receive, answer */
    fd_set f; FD_ZERO(&f); FD_SET(s, &f);
    struct timeval tv = {3, 0};
    if (select(s + 1, &f, 0, 0, &tv) <= 0) return 0;
    socklen_t fl = sizeof from;
    int n = recvfrom(s, buf, sizeof buf, 0, (struct sockaddr *)&from, &fl);
    if (n > 0) sendto(s, buf, n, 0, (struct sockaddr *)&from, fl);
  }
}
"""

_PY_ECHO = """
import socket, sys
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
s.bind(("127.0.0.1", int(sys.argv[1])))
s.settimeout(3.0)
try:
    while True:
        d, a = s.recvfrom(2048)
        s.sendto(d, a)
except OSError:
    pass
"""


def _echo_floor(kind: str, workdir: Path, n: int) -> list[tuple[str, float, str]]:
    """Reply latency of an echo process (``kind`` "C": compiled here with cc, skipped without one; "Python"), with
    the controller's pacing and kernel receive timestamps of the FRI runs: the floor of any client on this machine
    (a C echo does less than KUKA's C++ client, which also decodes and encodes)."""
    import shutil

    port = _free_port()
    if kind == "C":
        cc = shutil.which("cc") or shutil.which("gcc")
        if cc is None:
            return []
        src, exe = workdir / "echo.c", workdir / "echo"
        src.write_text(_C_ECHO)
        if subprocess.run([cc, "-O2", "-o", str(exe), str(src)], capture_output=True).returncode != 0:
            return []
        cmd = [str(exe), str(port)]
    else:
        cmd = [sys.executable, "-c", _PY_ECHO, str(port)]
    proc = subprocess.Popen(cmd)
    ctl = _Controller(port, 1)
    lat: list[float] = []
    missed = 0
    try:
        time.sleep(1.0)
        deadline = time.perf_counter()
        for i in range(n + 200):
            deadline = max(deadline + 1e-3, time.perf_counter())
            ctl.seq = i
            data = ctl._fill(4)
            got = ctl.exchange(data, deadline, lambda reply: reply == data)  # (a late echo of an earlier message)
            if i < 200:  # the start
                continue
            if got is None:
                missed += 1
            else:
                lat.append((got[1] - got[0]) * 1e-6)
    finally:
        proc.kill()
        proc.wait()
        ctl.sock.close()
    arr = np.array(lat)
    return [
        (f"floor: {kind} UDP echo, reply latency p50", float(np.percentile(arr, 50)), "ms"),
        (f"floor: {kind} UDP echo, reply latency p99", float(np.percentile(arr, 99)), "ms"),
        (f"floor: {kind} UDP echo, missed of {n}", float(missed), "cycles"),
    ]


def run(quick: bool = False, kuka: Sequence[str] = ()) -> list[tuple[str, float, str]]:
    """The figures; ``kuka``: paths of KUKA example clients (built from KUKA's FRI client SDK, e.g. lbr-stack/fri)
    to measure the same way, for the comparison with a C++ client on this machine."""
    duration = 5.0 if quick else 60.0
    rows: list[tuple[str, float, str]] = _processing_cost()
    with tempfile.TemporaryDirectory() as tmp:
        for kind in ("C", "Python"):
            rows += _echo_floor(kind, Path(tmp), int(duration * 1000))
        for period_ms, realtime, extra in (
            (1, False, ()),
            (1, False, ("--busy-wait", "0.2")),
            (1, False, ("--busy-wait", "0")),
            (1, True, ()),
            (5, False, ()),
        ):
            tag = f"{period_ms} ms" + (" --realtime" if realtime else "") + (" " + " ".join(extra) if extra else "")
            rows += _measure(period_ms, duration, Path(tmp), realtime, extra, tag)
        if kuka:
            rows += _interleaved(kuka, Path(tmp), rounds=2 if quick else 6, round_s=3.0 if quick else 10.0)
    if kuka:
        import fri_sniff

        if fri_sniff.available():
            rows += fri_sniff.interleaved(kuka, rounds=2 if quick else 3, seconds=3.0 if quick else 10.0)
        else:
            print("  (skipped the on-the-wire comparison: a packet socket on lo needs root or CAP_NET_RAW)")
    return rows


def _interleaved(kuka: Sequence[str], workdir: Path, rounds: int, round_s: float) -> list[tuple[str, float, str]]:
    """``lbr execute`` (defaults) and each KUKA client in turn, ``rounds`` times for ``round_s`` [s] each at 1 ms:
    on a shared VM the noise comes and goes over minutes, so each comparison is made within a round and the
    figures are medians over the rounds."""

    def figures(rows: list[tuple[str, float, str]]) -> tuple[float, float, float]:
        get = {name.rsplit(": ", 1)[1]: value for name, value, _ in rows}
        missed = next(v for k, v in get.items() if k.startswith("missed replies"))
        return get["reply latency p50 (controller side)"], get["reply latency p99 (controller side)"], missed

    names = ["lbr execute"] + [f"KUKA {Path(p).name} ({kuka_version(p)})" for p in kuka]
    per: dict[str, list[tuple[float, float, float]]] = {n: [] for n in names}
    for _ in range(rounds):
        per[names[0]].append(figures(_measure(1, round_s, workdir, tag="x")))
        for name, path in zip(names[1:], kuka):
            per[name].append(figures(_measure(1, round_s, workdir, tag="x", kuka=path)))
    out: list[tuple[str, float, str]] = []
    for name in names:
        f = np.array(per[name])
        out += [
            (f"interleaved 1 ms, {rounds}×{round_s:g} s, {name}: reply p50 (median of rounds)", float(np.median(f[:, 0])), "ms"),
            (f"interleaved 1 ms, {rounds}×{round_s:g} s, {name}: reply p99 (median of rounds)", float(np.median(f[:, 1])), "ms"),
            (f"interleaved 1 ms, {rounds}×{round_s:g} s, {name}: missed replies (sum)", float(f[:, 2].sum()), "cycles"),
        ]  # fmt: skip
        if name != names[0]:
            ratio = np.array(per[names[0]])[:, 1] / f[:, 1]
            out.append((f"interleaved 1 ms: p99 of lbr execute / p99 of {name}, median of rounds (range "
                        f"{ratio.min():.2f}–{ratio.max():.2f})", float(np.median(ratio)), "×"))  # fmt: skip
    return out


if __name__ == "__main__":
    kuka_clients = [a.split("=", 1)[1] for a in sys.argv[1:] if a.startswith("--kuka=")]
    for name, value, unit in run(quick="--quick" in sys.argv, kuka=kuka_clients):
        print(f"  {name:<62} {value:>12.4g} {unit}")
    sys.stdout.flush()
    os._exit(0)
