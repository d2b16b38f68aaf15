"""The client's UDP transport: the peer filter, the receive timeout, and the busy-wait window before each message."""

from __future__ import annotations

import pytest

import socket
import subprocess
import sys
import time

from lbrcli.fri.transport import UdpTransport


_SENDER = """
import socket, sys, time
port, n, period = int(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3])
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
time.sleep(0.2)
t = time.perf_counter()
for i in range(n):
    t += period
    while time.perf_counter() < t:
        time.sleep(min(2e-4, max(0.0, t - time.perf_counter())))
    s.sendto(i.to_bytes(4, "little"), ("127.0.0.1", port))
"""


def _sender(port: int, n: int, period_s: float) -> subprocess.Popen:
    """Another process (a thread would wait for the GIL while the receive busy-waits) sending n datagrams."""
    return subprocess.Popen([sys.executable, "-c", _SENDER, str(port), str(n), str(period_s)])


def _first(tr: UdpTransport) -> bytes:
    """The first datagram, however long the sender process takes to start (≤ 10 s)."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < 10:
        data = tr.receive()
        if data is not None:
            return data
    raise AssertionError("no datagram")


def _stream(tr: UdpTransport, n: int, period_s: float) -> list[int]:
    """The numbers of the ``n`` datagrams another process sends every ``period_s`` [s], as received: each one, or
    the newest waiting when the receiver fell behind (the older ones counted in ``overtaken``)."""
    th = _sender(tr.port, n, period_s)
    got = [int.from_bytes(_first(tr), "little")]
    while got[-1] < n - 1:
        d = tr.receive()
        assert d is not None
        got.append(int.from_bytes(d, "little"))
    th.wait(10)
    assert got == sorted(set(got)) and len(got) + tr.overtaken == n  # none lost, none twice, in order
    return got


def test_receive_times_out_with_none_and_takes_datagrams_in_order() -> None:
    tr = UdpTransport("127.0.0.1", 0, "127.0.0.1", timeout_s=0.05)
    try:
        t0 = time.perf_counter()
        assert tr.receive() is None
        assert 0.04 <= time.perf_counter() - t0 < 0.5
        got = _stream(tr, 20, 2e-3)
        assert got[-1] == 19
        assert tr.polled == 0  # no busy-wait without a period
    finally:
        tr.close()


@pytest.mark.heavy
def test_busy_wait_takes_the_messages_that_arrive_in_its_window() -> None:
    tr = UdpTransport("127.0.0.1", 0, "127.0.0.1", timeout_s=0.05, busy_wait_s=1.5e-3)
    tr.expect_period(2e-3)
    try:
        got = _stream(tr, 200, 2e-3)
        # the sender keeps its 2 ms grid: most messages land in the 1.5 ms before and after they are due (a sender
        # delayed on a loaded machine sends a few at once: the newest is taken)
        assert tr.polled >= len(got) // 2 and len(got) >= 50
        t0 = time.perf_counter()
        assert tr.receive() is None  # the sender stopped: the window passes, then the plain time-out
        assert time.perf_counter() - t0 < 0.5
    finally:
        tr.close()


def test_a_receiver_behind_takes_the_newest_waiting_datagram_and_counts_the_older_ones() -> None:
    tr = UdpTransport("127.0.0.1", 0, "127.0.0.1", timeout_s=0.05)
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        for i in range(4):  # the controller sent four messages while the client was stalled
            s.sendto(bytes([i]), ("127.0.0.1", tr.port))
        time.sleep(0.05)  # (loopback delivers at once; a margin for a loaded machine)
        assert tr.receive() == bytes([3]) and tr.overtaken == 3
        s.sendto(b"\x04", ("127.0.0.1", tr.port))
        assert tr.receive() == b"\x04" and tr.overtaken == 3  # none waiting: the one datagram
        assert tr.receive() is None
    finally:
        s.close()
        tr.close()


def test_datagrams_from_other_hosts_are_counted_and_ignored() -> None:
    tr = UdpTransport("127.0.0.2", 0, "127.0.0.1", timeout_s=0.05)
    try:
        s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        s.bind(("127.0.0.1", 0))
        s.sendto(b"x", ("127.0.0.1", tr.port))
        assert tr.receive() is None and tr.foreign == 1
        s.close()
    finally:
        tr.close()


@pytest.mark.heavy
def test_warm_is_called_while_busy_waiting_and_never_while_sleeping() -> None:
    from lbrcli.fri.transport import WARM_EVERY_S

    calls: list[float] = []
    busy = 1.5e-3  # [s]
    tr = UdpTransport("127.0.0.1", 0, "127.0.0.1", timeout_s=0.05, busy_wait_s=busy)
    tr.warm = lambda: calls.append(time.perf_counter())
    try:
        th = _sender(tr.port, 100, 2e-3)
        last = int.from_bytes(_first(tr), "little")
        assert calls == []  # no period known yet: a plain wait
        tr.expect_period(2e-3)
        waits = []
        while last < 99:  # (a sender delayed on a loaded machine sends a few at once: the newest is taken)
            n0 = len(calls)
            d = tr.receive()
            assert d is not None
            last = int.from_bytes(d, "little")
            waits.append(len(calls) - n0)
        th.wait(10)
        # nothing more comes: after a message, the next receive polls its whole window (from 1.5 ms before the
        # next message is due to 1.5 ms after), warming every WARM_EVERY_S, then sleeps in select until its
        # time-out without warming (retried: a loaded machine may run the two receives too far apart)
        out = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        for _ in range(5):
            out.sendto(b"x", ("127.0.0.1", tr.port))
            assert tr.receive() == b"x"
            n0 = len(calls)
            assert tr.receive() is None
            spin = calls[n0:]
            if len(spin) > 1:
                break
        out.close()
        assert tr.polled >= len(waits) // 2 and sum(1 for w in waits if w) >= 20  # messages waited for while warming
        gaps = [b - a for a, b in zip(spin, spin[1:])]
        # (bounds that hold however slowly a busy machine runs the loop: no more often than every WARM_EVERY_S, and
        # only within the window of the busy-wait)
        assert 2 <= len(spin) <= 2 * busy / WARM_EVERY_S + 2
        assert min(gaps) >= 0.9 * WARM_EVERY_S
        assert spin[-1] - spin[0] <= 2 * busy + 0.05  # (+ one descheduling on a loaded machine)
        tr.expect_period(None)
        n = len(calls)
        assert tr.receive() is None  # sleeping in select: no warming
        assert len(calls) == n
    finally:
        tr.close()


@pytest.mark.heavy
def test_the_default_wait_blocks_in_the_kernel_and_takes_a_1ms_stream_in_order() -> None:
    """No busy-wait by default (the CLI's and the library's): each receive blocks until its datagram, none is lost or
    reordered (a receiver behind takes the newest waiting), and nothing is ever taken by polling, also once the period
    is known."""
    tr = UdpTransport("127.0.0.1", 0, "127.0.0.1", timeout_s=0.05)
    tr.expect_period(1e-3)
    try:
        _stream(tr, 500, 1e-3)  # every one, or the newest of those waiting: none lost, none twice, in order
        assert tr.polled == 0
        t0 = time.perf_counter()
        assert tr.receive() is None  # then the kernel's receive time-out (SO_RCVTIMEO)
        assert time.perf_counter() - t0 >= 0.04
    finally:
        tr.close()


def test_received_ns_is_the_kernel_arrival_time_not_the_read_time() -> None:
    """A datagram read 50 ms after it arrived carries its arrival time (the supervision judges the controller's send
    rate by it), in both the blocking and the busy-waiting receive."""
    for busy in (0.0, 0.002):
        tr = UdpTransport("127.0.0.1", 0, bind_host="127.0.0.1", busy_wait_s=busy)
        if busy:
            tr.expect_period(0.001)
        out = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            before = time.time_ns()
            out.sendto(b"one", ("127.0.0.1", tr.port))
            time.sleep(0.05)
            read_at = time.time_ns()
            assert tr.receive() == b"one"
            stamp = tr.received_ns()
            if stamp is None and not sys.platform.startswith("linux"):
                pytest.skip("only Linux gives receive time stamps")
            assert stamp is not None, "Linux stamps every datagram (SO_TIMESTAMPNS)"
            assert before <= stamp < read_at  # arrived before the sleep ended, not when it was read
        finally:
            out.close()
            tr.close()
