"""FRI simulator timing at a 1 ms send period: the achieved send period (p50/p99/max), the reply latency it
measures and the work per cycle in each command mode (position, torque, wrench), with a trivial echo client in
another process (mirrors the ipo position, with a zero torque/wrench in the impedance modes, so the session goes
to COMMANDING_ACTIVE and the interpolator, the dynamics and the ball run every cycle). The quality thresholds are
lenient so that the session lasts the whole measurement on a loaded machine; the late and missed replies are
reported.

Issue #12's done criterion: KUKA's LBRJointSineOverlay semantics (command = ipo + 0.04·sin(2π·0.25 Hz·t) on A4
with its 0.99 filter, mirror in COMMANDING_WAIT) for 20 s at 1, 2 and 5 ms in both FRI versions, answered by the
KUKA-like raw client of lbrcli/fri/testing/kuka_client.py: max |measured − (ipo + sine)| over the commands the
controller demonstrably had in time, and whether a safety stop happened."""

from __future__ import annotations

import multiprocessing as mp
import time


def _mirror(mon, cmd, mode: str, seq: int) -> None:
    """Fill ``cmd`` as the answer to ``mon``: in the commanding states the ipo position (and a zero torque or
    wrench in those modes), else the header only."""
    cmd.commandData.Clear()
    if mon.connectionInfo.sessionState >= 3:
        cmd.commandData.jointPosition.value.extend(mon.ipoData.jointPosition.value)
        if mode == "torque":
            cmd.commandData.jointTorque.value.extend([0.0] * 7)
        elif mode == "wrench":
            cmd.commandData.cartesianWrenchFeedForward.element.extend([0.0] * 6)
    cmd.header.sequenceCounter = seq
    cmd.header.reflectedSequenceCounter = mon.header.sequenceCounter


def _echo_client(port_queue, version: str, stop_after: float, mode: str = "position") -> None:
    from lbrcli.fri.testing.kuka_client import KukaLikeClient

    client = KukaLikeClient(version)
    port_queue.put(client.port)
    try:
        client.run(None, mode=mode, timeout=stop_after, record=False)  # mirrors ipo (+ zero torque/wrench)
    finally:
        client.close()


def measure(
    duration_s: float,
    period_ms: int = 1,
    version: str = "1.15",
    ball: bool = True,
    realtime: bool = False,
    mode: str = "position",
):
    from lbrcli.fri.sim import SimConfig, SimulatorProcess
    from lbrcli.plants import default_plants

    ctx = mp.get_context("spawn")
    q = ctx.Queue()
    client = ctx.Process(target=_echo_client, args=(q, version, duration_s + 30.0, mode), daemon=True)
    client.start()
    port = q.get(timeout=30)
    cfg = SimConfig(
        client_port=port,
        period_ms=period_ms,
        version=version,
        max_runtime_s=duration_s,
        plants=default_plants(0.5 if ball else None),
        commanding_after_s=0.1,
        realtime=realtime,
        command_mode=mode,
        quality_window=500,
        quality_good=0.3,
        quality_fair=0.2,
    )  # keep commanding
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


def controller_cost(mode: str, version: str = "1.15", cycles: int = 3000, period_ms: int = 1) -> float:
    """Median compute time of one controller cycle [µs] (session, control law, dynamics, ball, encode and the
    decode of a mirroring reply), without sockets: the simulator's own share of a cycle."""
    import numpy as np

    from lbrcli.fri.constants import COMMAND_MESSAGE_ID
    from lbrcli.fri.sim import SimConfig
    from lbrcli.fri.sim.controller import Controller
    from lbrcli.plants import default_plants

    ctl = Controller(
        SimConfig(
            period_ms=period_ms,
            version=version,
            command_mode=mode,
            commanding_after_s=0.01,
            quality_window=5,
            plants=default_plants(0.5),
        )
    )
    codec = ctl.codec
    mon, cmd = codec.new_monitoring(), codec.new_command()
    cmd.header.messageIdentifier = COMMAND_MESSAGE_ID
    times = np.empty(cycles)
    for k in range(cycles):
        t0 = time.perf_counter()
        data = ctl.cycle(k * period_ms * 1e-3)
        codec.decode_monitoring(data, into=mon)
        _mirror(mon, cmd, mode, k)
        ctl.on_datagram(codec.encode(cmd), 0.0)
        times[k] = time.perf_counter() - t0
    ctl.close()
    return float(np.median(times[cycles // 2 :]) * 1e6)


def kuka_sine(duration_s: float, period_ms: int, version: str) -> tuple[float, float, bool, float, float]:
    """KUKA's joint sine overlay semantics for ``duration_s`` of COMMANDING_ACTIVE: (max |measured − command| [rad]
    over commands demonstrably in time, their share of the active messages, safety stop, max |measured − ipo|
    on A4 [rad] (the sine's reach), time in COMMANDING_ACTIVE [s])."""
    import numpy as np

    from lbrcli.fri.testing.kuka_client import CA, KukaLikeClient, joint_sine

    from lbrcli.fri.sim import SimConfig, SimulatorProcess

    client = KukaLikeClient(version)
    cfg = SimConfig(
        client_port=client.port,
        period_ms=period_ms,
        version=version,
        session_duration_s=duration_s,
        commanding_after_s=0.1,
        max_runtime_s=duration_s + 30.0,
        quality_window=max(25, 500 // period_ms),
        quality_good=0.3,
        quality_fair=0.2,
    )
    try:
        with SimulatorProcess(cfg) as sim:
            run = client.run(joint_sine(3, 0.04, 0.25, 0.99), timeout=duration_s + 40.0)
            stats = sim.wait(10.0) or sim.stop()
    finally:
        client.close()
    pairs = [(s, m) for s, m in run.executed_pairs(steady=3) if m.connectionInfo.sessionState == CA]
    err = max(
        (float(np.abs(np.array(m.monitorData.measuredJointPosition.value) - s.q).max()) for s, m in pairs),
        default=float("nan"),
    )
    active = run.active()
    reach = max(
        (abs(m.monitorData.measuredJointPosition.value[3] - m.ipoData.jointPosition.value[3]) for m in active),
        default=0.0,
    )
    return err, len(pairs) / max(1, len(active)), stats.safety_stop, reach, stats.active_cycles * period_ms * 1e-3


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    duration = 2.0 if quick else 10.0
    out = _figures(measure(duration), "")
    for version in ("1.15", "2.7"):
        for mode in ("position", "torque", "wrench"):
            out.append(
                (
                    f"FRI sim controller cycle, {mode} mode, FRI {version} (no sockets, with a ball)",
                    controller_cost(mode, version, 1000 if quick else 5000),
                    "us",
                )
            )
    for mode in ("torque", "wrench"):
        s = measure(duration / 2, mode=mode)
        out += [
            (f"FRI sim 1 ms {mode} mode: cycle work p50", s.work_us_p50, "us"),
            (f"FRI sim 1 ms {mode} mode: cycle work p99", s.work_us_p99, "us"),
            (f"FRI sim 1 ms {mode} mode: late + missed replies", float(s.late_replies + s.missed_replies), "replies"),
        ]
    rt = measure(duration, realtime=True)
    if rt.realtime:  # only where the OS grants SCHED_FIFO
        out += _figures(rt, " (realtime)")
    sine_s = 2.0 if quick else 20.0
    for version in ("1.15", "2.7"):
        for period in (1, 2, 5):
            err, share, safety, reach, active_s = kuka_sine(sine_s, period, version)
            tag = f"KUKA joint sine {sine_s:g} s, FRI {version}, {period} ms"
            out += [
                (f"{tag}: max |msr - (ipo + sine)|", err, "rad"),
                (f"{tag}: commands in time (checked)", share * 100.0, "%"),
                (f"{tag}: sine reach on A4", reach, "rad"),
                (f"{tag}: time in COMMANDING_ACTIVE", active_s, "s"),
                (f"{tag}: safety stop", float(safety), "yes=1"),
            ]
    return out


if __name__ == "__main__":
    import sys

    for name, value, unit in run(quick="--quick" in sys.argv):
        print(f"{name:<60} {value:12.4g} {unit}")
