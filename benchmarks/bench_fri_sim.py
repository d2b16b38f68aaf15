"""FRI simulator timing at a 1 ms send period: the achieved send period (p50/p99/max) and the reply latency
it measures, with a trivial echo client in another process (mirrors the ipo position, so the session goes
to COMMANDING_ACTIVE and the interpolator, the inverse dynamics and the ball run every cycle). The quality
thresholds are lenient so that the session lasts the whole measurement on a loaded machine; the late and
missed replies are reported."""

from __future__ import annotations

import multiprocessing as mp
import time


def _echo_client(port_queue, version: str, stop_after: float) -> None:
    import socket

    from lbrcli.fri.codec import FriCodec
    from lbrcli.fri.constants import COMMAND_MESSAGE_ID
    from trajectories.errors import FriDecodeError

    codec = FriCodec(version)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    port_queue.put(sock.getsockname()[1])
    sock.settimeout(1.0)
    mon, cmd = codec.new_monitoring(), codec.new_command()
    cmd.header.messageIdentifier = COMMAND_MESSAGE_ID
    jp = cmd.commandData.jointPosition.value
    seq = 0
    end = time.monotonic() + stop_after
    while time.monotonic() < end:
        try:
            data, addr = sock.recvfrom(2048)
        except socket.timeout:
            break
        try:
            codec.decode_monitoring(data, into=mon)
        except FriDecodeError:
            continue
        state = mon.connectionInfo.sessionState
        if state == 0:
            break
        if state >= 3:
            jp[:] = mon.ipoData.jointPosition.value
        else:
            cmd.ClearField("commandData")
            jp = cmd.commandData.jointPosition.value
        cmd.header.sequenceCounter = seq
        cmd.header.reflectedSequenceCounter = mon.header.sequenceCounter
        seq += 1
        sock.sendto(codec.encode(cmd), addr)
    sock.close()


def measure(duration_s: float, period_ms: int = 1, version: str = "1.15", ball: bool = True, realtime: bool = False):
    from lbrcli.fri.simulator import SimConfig, SimulatorProcess

    ctx = mp.get_context("spawn")
    q = ctx.Queue()
    client = ctx.Process(target=_echo_client, args=(q, version, duration_s + 30.0), daemon=True)
    client.start()
    port = q.get(timeout=30)
    cfg = SimConfig(client_port=port, period_ms=period_ms, version=version, max_runtime_s=duration_s,
                    ball_length=0.5 if ball else None, commanding_after_s=0.1, realtime=realtime,
                    quality_window=500, quality_good=0.3, quality_fair=0.2)  # keep commanding through hiccups
    with SimulatorProcess(cfg) as sim:
        stats = sim.wait(duration_s + 30.0) or sim.stop()
    client.join(5)
    if client.is_alive():
        client.terminate()
    return stats


def _figures(s, tag: str) -> list[tuple[str, float, str]]:
    return [
        (f"FRI sim 1 ms{tag}: cycles / in COMMANDING_ACTIVE", float(s.cycles), f"cycles ({s.active_cycles} active)"),
        (f"FRI sim 1 ms{tag}: send period p50", s.period_ms_p50, "ms"),
        (f"FRI sim 1 ms{tag}: send period p99", s.period_ms_p99, "ms"),
        (f"FRI sim 1 ms{tag}: send period max", s.period_ms_max, "ms"),
        (f"FRI sim 1 ms{tag}: overruns (> 1 period late)", float(s.overruns), "cycles"),
        (f"FRI sim 1 ms{tag}: cycle work p50", s.work_us_p50, "us"),
        (f"FRI sim 1 ms{tag}: cycle work p99", s.work_us_p99, "us"),
        (f"FRI sim 1 ms{tag}: echo reply latency p50", s.reply_latency_ms_p50, "ms"),
        (f"FRI sim 1 ms{tag}: echo reply latency p99", s.reply_latency_ms_p99, "ms"),
        (f"FRI sim 1 ms{tag}: late + missed replies", float(s.late_replies + s.missed_replies), "replies"),
        (f"FRI sim 1 ms{tag}: simulator CPU use", s.cpu_fraction * 100.0, "% of a core"),
    ]


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    duration = 2.0 if quick else 10.0
    out = _figures(measure(duration), "")
    rt = measure(duration, realtime=True)
    if rt.realtime:  # only where the OS grants SCHED_FIFO
        out += _figures(rt, " (realtime)")
    return out


if __name__ == "__main__":
    import sys

    for name, value, unit in run(quick="--quick" in sys.argv):
        print(f"{name:<48} {value:10.4f} {unit}")
