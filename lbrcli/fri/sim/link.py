"""The simulator's UDP link: socket, peer filter, kernel receive timestamps, fault injection and the delay line.

Outgoing monitoring messages can be dropped (loss), corrupted (malformed), or delayed by a fixed delay plus
uniform jitter (kept in a delay line and sent when due while the loop waits). Incoming datagrams from hosts other
than the client are counted and dropped; the others are handed on with their arrival time, the kernel's receive
timestamp where the OS provides it (so the measured latency excludes the simulator's own scheduling delays).
"""

from __future__ import annotations

import heapq
import math
import random
import select
import socket
import struct
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from trajectories.errors import FriError, SettingError

from ..constants import MAX_DATAGRAM

RING = 1 << 19  # per-message records kept (8.7 min at 1 kHz)
_SO_TIMESTAMPNS = getattr(socket, "SO_TIMESTAMPNS", None)
_TIMESPEC = struct.Struct("@qq")  # struct timespec (64-bit Linux)
_ANC_SIZE = socket.CMSG_SPACE(_TIMESPEC.size) if _SO_TIMESTAMPNS is not None else 0

OnDatagram = Callable[[bytes, float], None]  # (datagram, arrival time.time() [s])


@dataclass(frozen=True)
class Faults:
    """Fault injection on outgoing datagrams (probabilities 0..1, times [ms])."""

    loss: float = 0.0
    delay_ms: float = 0.0
    jitter_ms: float = 0.0
    malformed: float = 0.0
    seed: int = 0


def corrupt(data: bytes, rng: random.Random, framed: bool) -> bytes:
    """A damaged copy of a datagram that no FRI decoder accepts: truncated, a flipped byte, or garbage.

    1.x (no CRC): truncation inside the header field, or a byte sequence starting with the invalid tag 0.
    2.7: truncation (length mismatch) or one flipped payload byte (CRC-32 mismatch).
    """
    kind = rng.randrange(3)
    if kind == 0:  # truncated
        cut = rng.randrange(2, data[1] + 2) if not framed else rng.randrange(1, len(data) - 1)
        return data[:cut]
    if kind == 1 and framed:  # one payload byte flipped
        b = bytearray(data)
        b[rng.randrange(4, len(b) - 4)] ^= 1 << rng.randrange(8)
        return bytes(b)
    return b"\x00" + bytes(rng.getrandbits(8) for _ in range(rng.randrange(0, 64)))


class Link:
    """Non-blocking UDP socket bound to (host, port), talking to one client address."""

    def __init__(self, host: str, port: int, client_host: str, client_port: int, faults: Faults, framed: bool) -> None:
        try:
            self.client_ip = socket.gethostbyname(client_host)
        except OSError as exc:
            raise SettingError("SimConfig", "client_host", f"cannot resolve {client_host!r} ({exc})") from None
        self.client_addr = (self.client_ip, client_port)
        self.faults = faults
        self.framed = framed
        self._rng = random.Random(faults.seed)
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self.sock.bind((host, port))
        except OSError as exc:
            self.sock.close()
            raise FriError(f"simulator cannot bind {host}:{port} ({exc})") from None
        self.sock.setblocking(False)
        if _SO_TIMESTAMPNS is not None:
            self.sock.setsockopt(socket.SOL_SOCKET, _SO_TIMESTAMPNS, 1)
        self._delay_line: list[tuple[float, int, bytes]] = []
        self._send_time = np.full(RING, np.nan)  # send time (time.time) of monitoring message seq % RING [s]
        self.lost = 0  # dropped by the loss injection
        self.malformed_sent = 0
        self.foreign = 0  # datagrams from other hosts

    @property
    def address(self) -> tuple[str, int]:
        return self.sock.getsockname()[:2]

    def sent_at(self, seq: int) -> float:
        """When monitoring message ``seq`` went out (time.time [s]); NaN if it did not (yet)."""
        return float(self._send_time[seq % RING])

    # -- sending ---------------------------------------------------------------------------------------------
    def send(self, data: bytes, seq: int) -> None:
        """Send monitoring message ``seq`` through the fault injection."""
        f, rng = self.faults, self._rng
        if f.loss > 0.0 and rng.random() < f.loss:
            self.lost += 1
            return
        if f.malformed > 0.0 and rng.random() < f.malformed:
            self.malformed_sent += 1
            data = corrupt(data, rng, self.framed)
            seq = -1
        delay = f.delay_ms + (rng.random() * f.jitter_ms if f.jitter_ms > 0.0 else 0.0)
        if delay > 0.0:
            heapq.heappush(self._delay_line, (time.perf_counter() + delay * 1e-3, seq, data))
        else:
            self._sendto(data, seq)

    def _sendto(self, data: bytes, seq: int) -> None:
        """Send a datagram; ``seq`` >= 0 records its send time for the reply latency (on loopback the kernel
        delivers inside sendto, so the time is taken before)."""
        t = time.time()
        try:
            self.sock.sendto(data, self.client_addr)
        except OSError:
            return
        if seq >= 0:
            self._send_time[seq % RING] = t

    def _flush_delay_line(self, now: float) -> float:
        """Send delayed datagrams that are due; returns the next due time (inf if none)."""
        line = self._delay_line
        while line and line[0][0] <= now:
            _, seq, data = heapq.heappop(line)
            self._sendto(data, seq)
        return line[0][0] if line else math.inf

    # -- receiving -------------------------------------------------------------------------------------------
    def drain(self, on_datagram: OnDatagram) -> None:
        """Hand on every datagram waiting in the socket (non-blocking); foreign hosts are counted and dropped."""
        sock = self.sock
        while True:
            try:
                data, anc, _, addr = sock.recvmsg(MAX_DATAGRAM + 64, _ANC_SIZE)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:  # e.g. ICMP port unreachable reported on loopback: the client is not there (yet)
                continue
            if addr[0] != self.client_ip:
                self.foreign += 1
                continue
            arrival = None
            for level, kind, cdata in anc:  # the kernel's receive time: the latency without our own delays
                if level == socket.SOL_SOCKET and kind == _SO_TIMESTAMPNS and len(cdata) >= _TIMESPEC.size:
                    sec, nsec = _TIMESPEC.unpack_from(cdata)
                    arrival = sec + nsec * 1e-9
            on_datagram(data, time.time() if arrival is None else arrival)

    def wait_until(self, deadline: float, on_datagram: OnDatagram, spin_s: float) -> None:
        """Receive (and send delayed datagrams) until ``deadline`` (perf_counter [s]); sleeps in select, then
        busy-waits the last ``spin_s`` [s] for a punctual send."""
        fd = [self.sock]
        while True:
            now = time.perf_counter()
            due = self._flush_delay_line(now) if self._delay_line else math.inf
            remaining = deadline - now
            if remaining <= 0.0:
                return
            timeout = min(remaining - spin_s, due - now)
            r, _, _ = select.select(fd, (), (), timeout if timeout > 0.0 else 0.0)
            if r:
                self.drain(on_datagram)

    def wait_for(self, done: Callable[[], bool], deadline: float, on_datagram: OnDatagram) -> bool:
        """Receive (and send delayed datagrams) until ``done()`` or ``deadline`` (perf_counter [s]); whether
        ``done()`` became true."""
        fd = [self.sock]
        while not done():
            now = time.perf_counter()
            due = self._flush_delay_line(now) if self._delay_line else math.inf
            if now >= deadline:
                return False
            r, _, _ = select.select(fd, (), (), max(0.0, min(deadline, due) - now))
            if r:
                self.drain(on_datagram)
        return True

    def flush(self, on_datagram: OnDatagram, max_wait_s: float = 0.2) -> None:
        """Let datagrams still in the delay line go out (at most ``max_wait_s`` [s] from now)."""
        if self._delay_line:
            last = max(d[0] for d in self._delay_line)
            self.wait_until(min(last, time.perf_counter() + max_wait_s) + 1e-4, on_datagram, 0.0)

    def close(self) -> None:
        self.sock.close()
