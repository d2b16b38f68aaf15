"""The simulator sends like a real controller even when its own process runs late: after a cycle that started late
the next one starts at least MIN_SPACING periods later (a send delayed inside a cycle: MIN_SEND_SPACING), so a client
is not judged late (and its session dropped) for the simulator's delay — and otherwise it keeps its period."""

from __future__ import annotations

import socket

import numpy as np
import pytest

from lbrcli.fri.sim import SimConfig, Simulator
from lbrcli.fri.sim import simulator as simulator_module
from lbrcli.fri.sim.simulator import MIN_SEND_SPACING, MIN_SPACING


class _VirtualClock:
    """The simulator's perf_counter, advanced only by what the test says takes time (waits, late wake-ups, work):
    the send instants are exactly what the loop's scheduling makes of them, whatever else this machine runs."""

    def __init__(self) -> None:
        self.t = 1000.0  # [s]

    def perf_counter(self) -> float:
        return self.t

    def process_time(self) -> float:
        return 0.0


def _sends(
    monkeypatch, period_ms: int, runtime_s: float, late_start: float = 0.0, late_send: float = 0.0, work: float = 0.0
) -> np.ndarray:
    """Send instants [s] of a simulator whose every 5th cycle starts ``late_start`` periods late (it wakes late) or
    sends ``late_send`` periods late (its own work), and that works ``work`` periods before every send."""
    clock = _VirtualClock()
    monkeypatch.setattr(simulator_module, "time", clock)
    sink = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sink.bind(("127.0.0.1", 0))
    sim = Simulator(SimConfig(client_port=sink.getsockname()[1], period_ms=period_ms, max_runtime_s=runtime_s))
    period = period_ms * 1e-3
    cycle, send, n, sent = sim.controller.cycle, sim.link.send, [0, 0], []

    def wait_until(deadline, on_datagram, spin_s):  # the wait ends at its deadline, every 5th one late_start late
        clock.t = max(clock.t, deadline)
        n[0] += 1
        if n[0] % 5 == 0:
            clock.t += late_start * period

    def late_cycle(t):
        n[1] += 1
        clock.t += ((late_send if n[1] % 5 == 0 else 0.0) + work) * period
        return cycle(t)

    def timed_send(data, seq):
        sent.append(clock.t)
        send(data, seq)

    sim.link.wait_until = wait_until  # type: ignore[method-assign]
    sim.link.wait_for = lambda done, deadline, on_datagram: False  # type: ignore[method-assign]
    sim.controller.cycle = late_cycle  # type: ignore[method-assign]
    sim.link.send = timed_send  # type: ignore[method-assign]
    try:
        sim.run()
    finally:
        sim.link.close()
        sink.close()
    return np.array(sent)


@pytest.mark.heavy
@pytest.mark.parametrize("late_start, late_send, floor", [(0.6, 0.0, MIN_SPACING), (0.0, 0.6, MIN_SEND_SPACING)])
def test_a_late_cycle_does_not_shorten_the_next_period(monkeypatch, late_start, late_send, floor):
    period_ms = 4
    times = _sends(monkeypatch, period_ms, 0.6, late_start, late_send)
    gaps = np.diff(times)  # [s]
    assert len(times) > 50
    late = np.flatnonzero(gaps > 1.4 * period_ms * 1e-3)
    assert len(late) >= 10  # the injected delays happened
    # the send after each delayed one keeps the floor (without it: ≈ 0.4 period)
    p = period_ms * 1e-3
    after = gaps[late[late + 1 < len(gaps)] + 1]
    assert after.min() >= floor * p - 1e-9, after / p
    assert gaps.min() >= MIN_SEND_SPACING * p - 1e-9, np.sort(gaps)[:5] / p


@pytest.mark.heavy
def test_on_time_cycles_keep_the_period(monkeypatch):
    period_ms = 1
    gaps = np.diff(_sends(monkeypatch, period_ms, 1.0, work=0.2)) * 1e3  # [ms] (0.2 ms of work before each send)
    assert len(gaps) > 900
    # the floor never holds the simulator back when it is on time: every period is the period (a floor counted from
    # each send, without the grid, made it 0.9 period + the work)
    assert np.abs(gaps - period_ms).max() < 1e-6 * period_ms, np.unique(np.round(gaps, 6))
