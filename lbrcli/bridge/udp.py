"""UDP transport: a non-blocking socket drained once per FRI cycle (no thread); a sender is its address and port."""

from __future__ import annotations

import socket
from typing import Hashable, Iterator, Sequence

from .inbox import TargetInbox


class UdpTransport:
    """Datagrams on ``host``:``port``; with ``allowed`` only those hosts may command."""

    name = "udp"

    def __init__(self, port: int = 30300, host: str = "127.0.0.1", allowed: set[str] | None = None) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self.sock.bind((host, port))
        except OSError:
            self.sock.close()
            raise
        self.sock.setblocking(False)
        self.host = host
        self.port = self.sock.getsockname()[1]
        self.allowed = allowed

    def receive(self) -> Iterator[tuple[bytes, Hashable | None]]:
        recv = self.sock.recvfrom
        while True:
            try:
                data, addr = recv(65536)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:  # e.g. ICMP port unreachable from sending state to a source that left
                continue
            yield data, addr

    def admits(self, sender: Hashable | None) -> bool:
        return self.allowed is None or (isinstance(sender, tuple) and sender[0] in self.allowed)

    def send(self, data: bytes, sender: Hashable | None) -> None:
        try:
            self.sock.sendto(data, sender)  # type: ignore[arg-type]
        except OSError:
            pass

    def describe(self, sender: Hashable | None) -> str:
        return f"{sender[0]}:{sender[1]}" if isinstance(sender, tuple) else "udp"

    def close(self) -> None:
        self.sock.close()


class UdpTargets(TargetInbox):
    """A :class:`TargetInbox` on one UDP socket (``port`` 0: any free port, in ``.port``)."""

    def __init__(self, port: int = 30300, host: str = "127.0.0.1", allowed: set[str] | None = None,
                 secret: bytes | None = None, more: Sequence = (), limits=None) -> None:  # fmt: skip
        self.udp = UdpTransport(port, host, allowed)
        self.port = self.udp.port
        super().__init__((self.udp, *more), secret, limits)
