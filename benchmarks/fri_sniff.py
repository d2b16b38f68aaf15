"""Reply latency seen on the wire: `lbr sim` as the controller, a client in its own process, and a loopback packet
sniffer (an AF_PACKET socket on ``lo``, kernel timestamps; needs root or CAP_NET_RAW) — the way issue #12's
figures were taken. For each monitoring message in COMMANDING_ACTIVE the latency is the time from its datagram on
``lo`` to the first command datagram reflecting it. KUKA's example client and `lbr execute` are measured in
interleaved rounds (same simulator settings, same trajectory length) so that the VM's slow drifts of noise fall on
both alike. Used by ``bench_fri.run`` when KUKA clients are given."""

from __future__ import annotations

import contextlib
import os
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Sequence

import numpy as np
from bench_fri import _SO_TIMESTAMPNS, _trajectory, kernel_time_ns, kuka_version

FRI_PORT = 30200
_ETH_P_ALL = 0x0003
_PACKET_OUTGOING = 4  # lo shows each packet twice (outgoing and incoming): one copy is enough


def available() -> bool:
    """Whether this process may open a packet socket on ``lo``."""
    try:
        socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.ntohs(_ETH_P_ALL)).close()
        return True
    except (OSError, AttributeError):
        return False


class LoopbackSniffer:
    """Records (kernel time [ns], source port, destination port, UDP payload) of the datagrams to or from ``port``
    on ``lo``; drains its socket every 20 ms, so it wakes rarely on the measured machine."""

    def __init__(self, port: int = FRI_PORT) -> None:
        self.port = port
        self.records: list[tuple[int, int, int, bytes]] = []
        self._sock = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.ntohs(_ETH_P_ALL))
        self._sock.bind(("lo", 0))
        self._sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 24)
        self._sock.setsockopt(socket.SOL_SOCKET, _SO_TIMESTAMPNS, 1)
        self._sock.setblocking(False)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> "LoopbackSniffer":
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join(5.0)
        self._drain()
        self._sock.close()

    def _run(self) -> None:
        if hasattr(os, "SCHED_IDLE"):  # the sniffer's own Python work must not delay the measured processes
            with contextlib.suppress(OSError):
                os.sched_setscheduler(0, os.SCHED_IDLE, os.sched_param(0))
        while not self._stop.is_set():
            self._drain()
            time.sleep(0.02)

    def _drain(self) -> None:
        sock, port, out = self._sock, self.port, self.records
        while True:
            try:
                frame, anc, _, addr = sock.recvmsg(4096, 64)
            except (BlockingIOError, OSError):
                return
            if addr[2] != _PACKET_OUTGOING:
                continue
            ip = frame[14:]  # after the (zero) Ethernet header of lo
            if len(ip) < 28 or ip[0] >> 4 != 4 or ip[9] != 17:
                continue
            ihl = (ip[0] & 15) * 4
            sport, dport = struct.unpack_from("!HH", ip, ihl)
            if port not in (sport, dport):
                continue
            out.append((kernel_time_ns(anc) or 0, sport, dport, bytes(ip[ihl + 8 :])))


def latencies(
    records: Sequence[tuple[int, int, int, bytes]], version: str, port: int = FRI_PORT
) -> tuple[np.ndarray, int]:
    """Reply latencies [ms] of the COMMANDING_ACTIVE messages answered, and how many such messages were sent."""
    from lbrcli.fri.codec import FriCodec

    codec = FriCodec(version)
    mon, cmd = codec.new_monitoring(), codec.new_command()
    sent: dict[int, int] = {}
    lat: list[float] = []
    active = 0
    for t, _, dport, payload in records:
        try:
            if dport == port:
                m = codec.decode_monitoring(payload, mon)
                if m.connectionInfo.sessionState == 4:
                    sent[m.header.sequenceCounter] = t
                    active += 1
            else:
                refl = codec.decode_command(payload, cmd).header.reflectedSequenceCounter
                if refl in sent:
                    lat.append((t - sent.pop(refl)) * 1e-6)
        except Exception:  # noqa: BLE001 - not an FRI datagram of this version
            continue
    return np.array(lat), active


def _round(client: list[str] | None, version: str, seconds: float, workdir: Path) -> tuple[float, float, bool]:
    """One sniffed run: (p50, p99 [ms], whether COMMANDING_ACTIVE lasted the whole run). ``client``: a KUKA
    example binary's command, or None for ``lbr execute`` on a trajectory of ``seconds``."""
    lbr = [sys.executable, "-m", "lbrcli"]
    sim_cmd = lbr + ["sim", "--period", "1", "--fri-version", version, "--timeout", str(seconds + 8)]
    if client is not None:
        sim_cmd += ["--duration", str(seconds)]
    with LoopbackSniffer() as sniffer:
        sim = subprocess.Popen(sim_cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            if client is None:
                cmd = lbr + ["execute", str(workdir / "traj.csv"), "--robot", "127.0.0.1", "--port", str(FRI_PORT),
                             "--json", "--wait", "20"]  # fmt: skip
            else:
                time.sleep(0.3)
                cmd = client
            subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=seconds + 30, cwd=workdir)
            if client is None:
                sim.terminate()  # lbr execute has finished: the simulator closes the session (IDLE)
            sim.wait(seconds + 15)
        finally:
            if sim.poll() is None:
                sim.kill()
                sim.wait()
    lat, active = latencies(sniffer.records, version)
    if len(lat) == 0:
        return float("nan"), float("nan"), False
    return (
        float(np.percentile(lat, 50)),
        float(np.percentile(lat, 99)),
        active >= 0.9 * seconds * 1000,
    )  # (the simulator drops a slot now and then)


def interleaved(kuka: Sequence[str], rounds: int = 3, seconds: float = 10.0) -> list[tuple[str, float, str]]:
    """For each KUKA client (its FRI version from its path), ``rounds`` × (that client, then ``lbr execute``
    with its defaults) against ``lbr sim`` at 1 ms: medians of the per-round p50/p99 and of the p99 ratios."""
    rows: list[tuple[str, float, str]] = []
    with tempfile.TemporaryDirectory() as tmp:
        workdir = Path(tmp)
        _trajectory(workdir / "traj.csv", 1e-3, seconds)
        for path in kuka:
            version = kuka_version(path)
            per: dict[str, list[tuple[float, float, bool]]] = {"KUKA": [], "lbr": []}
            for _ in range(rounds):
                per["KUKA"].append(_round([path], version, seconds, workdir))
                per["lbr"].append(_round(None, version, seconds, workdir))
            name = f"{Path(path).name} ({version})"
            tag = f"on the wire (lbr sim + loopback sniffer), {rounds}×{seconds:g} s, 1 ms"
            for who, label in (("KUKA", f"KUKA {name}"), ("lbr", f"lbr execute ({version})")):
                f = np.array([r[:2] for r in per[who]])
                rows += [
                    (f"{tag}, {label}: reply p50 (median of rounds)", float(np.nanmedian(f[:, 0])), "ms"),
                    (f"{tag}, {label}: reply p99 (median of rounds)", float(np.nanmedian(f[:, 1])), "ms"),
                    (f"{tag}, {label}: sessions that lasted the run", float(sum(r[2] for r in per[who])), f"of {rounds}"),
                ]  # fmt: skip
            ratio = np.array([b[1] / a[1] for a, b in zip(per["KUKA"], per["lbr"])])
            rows.append((f"{tag}: p99 of lbr execute / p99 of KUKA {name}, median of rounds (range "
                         f"{np.nanmin(ratio):.2f}–{np.nanmax(ratio):.2f})", float(np.nanmedian(ratio)), "×"))  # fmt: skip
    return rows


if __name__ == "__main__":
    if not available():
        sys.exit("needs root or CAP_NET_RAW (a packet socket on lo)")
    for n, v, u in interleaved(
        [a for a in sys.argv[1:] if not a.startswith("-")], rounds=2 if "--quick" in sys.argv else 3
    ):
        print(f"  {n:<100} {v:>10.4g} {u}")
