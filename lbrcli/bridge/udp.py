"""Targets arriving over UDP: a non-blocking socket drained once per FRI cycle (no thread), the owner rule, counters.

Hand-over rule: the first source (address and port) whose datagram is a valid target owns the session; datagrams
from any other source are ignored and counted (``foreign``) — to hand over, end the session (the dead-man, an end
message or Ctrl-C) and start another. With ``allowed`` only those hosts may become the owner at all.
"""

from __future__ import annotations

import json
import socket
import time

from .protocol import BadTarget, Target, decode_target



def _is_end(data: bytes) -> bool:
    """The end message: a JSON object with "end": true."""
    if not (data[:1] == b"{" and b'"end"' in data):
        return False
    try:
        obj = json.loads(data)
    except (UnicodeDecodeError, ValueError):
        return False
    return isinstance(obj, dict) and obj.get("end") is True


class UdpTargets:
    """The newest valid target from the owning source; ``error`` once the owner sent something that is not one."""

    def __init__(self, port: int = 30300, host: str = "127.0.0.1", allowed: set[str] | None = None) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind((host, port))
        self.sock.setblocking(False)
        self.port = self.sock.getsockname()[1]
        self.allowed = allowed
        self.owner: tuple[str, int] | None = None
        self.latest: Target | None = None
        self.latest_time = 0.0  # [s] time.monotonic() of its arrival
        self.fresh = False  # a target arrived since the last ``take``
        self.error: str | None = None  # the owner's datagram that was not a target
        self.ended = False  # the owner sent the end message
        self.received = self.accepted = self.bad = self.foreign = self.stale = 0
        self._last_seq: int | None = None

    def poll(self) -> None:
        """Drain the socket (non-blocking)."""
        recv = self.sock.recvfrom
        while True:
            try:
                data, addr = recv(65536)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:  # e.g. ICMP port unreachable from sending state to a source that left
                continue
            self.received += 1
            self._handle(data, addr)

    def _handle(self, data: bytes, addr: tuple[str, int]) -> None:
        if (self.owner is not None and addr != self.owner) or (self.allowed is not None and addr[0] not in self.allowed):
            self.foreign += 1
            return
        if _is_end(data):
            if self.owner is not None:
                self.ended = True
            return
        try:
            target = decode_target(data)
        except BadTarget as exc:
            self.bad += 1
            if self.owner is not None and self.error is None:
                self.error = f"{exc} (from {addr[0]}:{addr[1]})"
            return
        if target.seq is not None and self._last_seq is not None:
            d = (target.seq - self._last_seq) & 0xFFFFFFFF
            if d == 0 or d > 0x7FFFFFFF:
                self.stale += 1
                return
        if target.seq is not None:
            self._last_seq = target.seq
        self.owner = addr
        self.latest = target
        self.latest_time = time.monotonic()
        self.fresh = True
        self.accepted += 1

    def send(self, data: bytes) -> None:
        """Send ``data`` to the owner (nothing before there is one)."""
        if self.owner is not None:
            try:
                self.sock.sendto(data, self.owner)
            except OSError:
                pass

    def close(self) -> None:
        self.sock.close()

    def figures(self) -> dict[str, int | str | None]:
        return {
            "targets_received": self.received,
            "targets_accepted": self.accepted,
            "targets_bad": self.bad,
            "targets_foreign": self.foreign,
            "targets_stale": self.stale,
            "source": f"{self.owner[0]}:{self.owner[1]}" if self.owner else None,
        }
