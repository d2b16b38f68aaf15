"""A UDP relay between the simulator and a client in another process, recording both directions.

KUKA's example clients answer whoever sent the last datagram (started without a controller address), so the relay
binds one loopback port, gives it to the simulator as the client's address, forwards each monitoring message to the
client's port and each reply back to the simulator, and keeps every datagram (arrival order, direction). Decoding is
left to the caller (``lbrcli.fri.codec``). Used by tests/lbrcli/fri/sim/test_simulator_kuka27.py and benchmarks/bench_fri_cartesian.py.
"""

from __future__ import annotations

import socket
import threading


class Relay:
    """``port``: where the simulator sends; ``client_port``: where the client listens. ``to_client`` and
    ``to_sim`` hold the datagrams forwarded each way."""

    def __init__(self, client_port: int) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.port = self.sock.getsockname()[1]
        self.client = ("127.0.0.1", client_port)
        self.sim: tuple[str, int] | None = None
        self.to_client: list[bytes] = []
        self.to_sim: list[bytes] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> "Relay":
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(2.0)
        self.sock.close()

    def _run(self) -> None:
        self.sock.settimeout(0.1)
        while not self._stop.is_set():
            try:
                data, addr = self.sock.recvfrom(2048)
            except (socket.timeout, ConnectionRefusedError):  # (the client's port not bound yet: ICMP unreachable)
                continue
            except OSError:
                return
            if addr == self.client:
                self.to_sim.append(data)
                if self.sim is not None:
                    self._send(data, self.sim)
            else:
                self.sim = addr
                self.to_client.append(data)
                self._send(data, self.client)

    def _send(self, data: bytes, to: tuple[str, int]) -> None:
        try:
            self.sock.sendto(data, to)
        except OSError:  # the other side is gone (or not there yet): the datagram is lost, as on a network
            pass


def free_udp_port() -> int:
    """A UDP port free on loopback now (the client binds it on all interfaces)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("", 0))
        return s.getsockname()[1]
