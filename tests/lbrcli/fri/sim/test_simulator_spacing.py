"""The simulator sends like a real controller even when its own process runs late: after a cycle that started late
the next one starts at least MIN_SPACING periods later (a send delayed inside a cycle: MIN_SEND_SPACING), so a client
is not judged late (and its session dropped) for the simulator's delay — and otherwise it keeps its period."""

from __future__ import annotations

import socket
import threading
import time

import numpy as np
import pytest

from lbrcli.fri.sim import SimConfig, Simulator
from lbrcli.fri.sim.simulator import MIN_SEND_SPACING, MIN_SPACING

_SO_TIMESTAMPNS = getattr(socket, "SO_TIMESTAMPNS", 35)


def _sink() -> socket.socket:
    sink = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sink.bind(("127.0.0.1", 0))
    sink.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 22)
    sink.setsockopt(socket.SOL_SOCKET, _SO_TIMESTAMPNS, 1)
    return sink


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


def _spin(s: float) -> None:
    end = time.perf_counter() + s
    while time.perf_counter() < end:
        pass


def _sends(
    period_ms: int, runtime_s: float, late_start: float = 0.0, late_send: float = 0.0, work: float = 0.0
) -> list[float]:
    """Send instants [s] of a simulator whose every 5th cycle starts ``late_start`` periods late (it wakes late) or
    sends ``late_send`` periods late (its own work), and that works ``work`` periods before every send."""
    sink = _sink()
    sim = Simulator(SimConfig(client_port=sink.getsockname()[1], period_ms=period_ms, max_runtime_s=runtime_s))
    period = period_ms * 1e-3
    wait_until, cycle, n = sim.link.wait_until, sim.controller.cycle, [0, 0]

    def late_wake(deadline, on_datagram, spin_s):
        wait_until(deadline, on_datagram, spin_s)
        n[0] += 1
        if n[0] % 5 == 0:
            _spin(late_start * period)

    def late_cycle(t):
        n[1] += 1
        _spin((late_send if n[1] % 5 == 0 else 0.0) * period + work * period)
        return cycle(t)

    if late_start:
        sim.link.wait_until = late_wake  # type: ignore[method-assign]
    if late_send or work:
        sim.controller.cycle = late_cycle  # type: ignore[method-assign]
    runner = threading.Thread(target=sim.run)
    runner.start()
    try:
        return _arrivals(sink)
    finally:
        runner.join(10.0)
        sink.close()


@pytest.mark.parametrize("late_start, late_send, floor", [(0.6, 0.0, MIN_SPACING), (0.0, 0.6, MIN_SEND_SPACING)])
def test_a_late_cycle_does_not_shorten_the_next_period(late_start, late_send, floor):
    period_ms = 4
    times = _sends(period_ms, 0.6, late_start, late_send)
    gaps = np.diff(times)  # [s]
    assert len(times) > 50
    late = np.flatnonzero(gaps > 1.4 * period_ms * 1e-3)
    assert len(late) >= 10  # the injected delays happened
    # the send after each delayed one keeps the floor (without it: ≈ 0.4 period), less the variation of the
    # simulator's own work between a cycle's start and its send (≤ 0.1 period here). Judged on most of them: a busy
    # machine can preempt this process between a cycle's start and its send, which no floor counted from the start
    # can see (CI saw one such gap of 0.65 period among 20)
    p = period_ms * 1e-3
    after = gaps[late[late + 1 < len(gaps)] + 1]
    kept = after >= (floor - 0.1) * p
    assert kept.mean() >= 0.75 and np.median(after) >= (floor - 0.1) * p, after / p
    assert np.mean(gaps >= (MIN_SEND_SPACING - 0.1) * p) >= 0.97, np.sort(gaps)[:5] / p


def test_on_time_cycles_keep_the_period():
    period_ms = 1
    gaps = np.diff(_sends(period_ms, 1.0, work=0.2)) * 1e3  # [ms] (0.2 ms of work before each send)
    assert len(gaps) > 500
    # the floor never holds the simulator back when it is on time: the median period is the period (a floor
    # counted from each send, without the grid, made it 0.9 period + the work)
    assert abs(np.median(gaps) - period_ms) < 0.01 * period_ms, np.median(gaps)
