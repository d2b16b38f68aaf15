"""The simulator sends like a real controller even when its own process runs late: two messages are never closer
than MIN_SPACING periods, so a client is not judged late (and its session dropped) for the simulator's delay."""

from __future__ import annotations

import socket
import threading
import time

from lbrcli.fri.sim import SimConfig, Simulator
from lbrcli.fri.sim.simulator import MIN_SPACING

_SO_TIMESTAMPNS = getattr(socket, "SO_TIMESTAMPNS", 35)


def _arrivals(sock: socket.socket, quiet_s: float = 0.5) -> list[float]:
    """Kernel receive times [s] of every datagram until ``quiet_s`` without one (taken inside the sender's sendto
    on loopback: the simulator's send instants)."""
    out = []
    sock.settimeout(10.0)
    try:
        while True:
            _, anc, _, _ = sock.recvmsg(2048, 64)
            ts = next((int.from_bytes(d[:8], "little") + int.from_bytes(d[8:16], "little") * 1e-9
                       for lvl, typ, d in anc if lvl == socket.SOL_SOCKET and typ == _SO_TIMESTAMPNS), time.time())  # fmt: skip
            out.append(ts)
            sock.settimeout(quiet_s)
    except socket.timeout:
        return out


def test_a_late_send_does_not_shorten_the_next_period():
    period_ms = 4
    sink = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sink.bind(("127.0.0.1", 0))
    sink.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 22)
    sink.setsockopt(socket.SOL_SOCKET, _SO_TIMESTAMPNS, 1)
    sim = Simulator(SimConfig(client_port=sink.getsockname()[1], period_ms=period_ms, max_runtime_s=0.6))
    cycle = sim.controller.cycle
    n = [0]

    def late_cycle(t: float) -> bytes:
        """Every 5th cycle the simulator's own work makes it send 0.6 periods late."""
        n[0] += 1
        if n[0] % 5 == 0:
            end = time.perf_counter() + 0.6 * period_ms * 1e-3
            while time.perf_counter() < end:
                pass
        return cycle(t)

    sim.controller.cycle = late_cycle  # type: ignore[method-assign]
    runner = threading.Thread(target=sim.run)
    runner.start()
    try:
        times = _arrivals(sink)
    finally:
        runner.join(10.0)
        sink.close()
    gaps = [b - a for a, b in zip(times, times[1:])]  # [s]
    assert len(times) > 50
    late = [i for i, g in enumerate(gaps) if g > 1.4 * period_ms * 1e-3]
    assert len(late) >= 10  # the injected late sends happened
    # after each late send the next one keeps (almost) a whole period, not the ≈ 0.4 period a catch-up would leave;
    # and no two sends are closer, however this process is scheduled (the floor counts from after each send)
    after = [gaps[i + 1] for i in late if i + 1 < len(gaps)]
    assert min(after) >= MIN_SPACING * period_ms * 1e-3 - 5e-5, min(after)
    assert min(gaps) >= MIN_SPACING * period_ms * 1e-3 - 5e-5, min(gaps)
    # and the schedule catches up after each delay (a loaded machine's overruns re-synchronise and cost slots)
    nominal = 0.6 / (period_ms * 1e-3) + 3
    assert 0.5 * nominal <= len(times) <= nominal + 2
