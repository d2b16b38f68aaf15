"""UDP transport of the FRI client: the bound socket, the peer filter and the reply address.

The client binds the port of the robot's FRI configuration (30200 by default), accepts datagrams only from the
controller's IP address (any source port: a simulator on the same machine cannot own the port too) and replies
to the port each datagram came from.
"""

from __future__ import annotations

import socket

from .constants import MAX_DATAGRAM
from .errors import FriError, InputError

RECV_TIMEOUT_S = 0.05  # [s] how often a blocked receive returns to look at clocks and interrupt flags


def resolve_ip(host: str) -> str:
    """The IPv4 address of ``host`` (an address or a name)."""
    try:
        return socket.getaddrinfo(host, None, socket.AF_INET, socket.SOCK_DGRAM)[0][4][0]
    except (socket.gaierror, IndexError, UnicodeError):
        raise InputError(f"--robot: cannot resolve {host!r} to an IPv4 address") from None


class UdpTransport:
    """A bound UDP socket that receives from one controller address and answers the last sender."""

    def __init__(self, robot_ip: str, port: int, bind_host: str = "", timeout_s: float = RECV_TIMEOUT_S) -> None:
        self.robot_ip = resolve_ip(robot_ip)
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            sock.bind((bind_host, port))
        except OSError as exc:
            sock.close()
            raise FriError(f"cannot bind the FRI port {bind_host or '*'}:{port}: {exc.strerror}") from None
        sock.settimeout(timeout_s)
        self.sock = sock
        self.port: int = sock.getsockname()[1]
        self.timeout_s = timeout_s
        self.peer: tuple[str, int] | None = None  # where replies go (the last accepted datagram's source)
        self.foreign = 0  # datagrams from other addresses (ignored)

    def receive(self) -> bytes | None:
        """The next datagram from the controller, or None after the receive timeout."""
        recvfrom = self.sock.recvfrom
        robot = self.robot_ip
        while True:
            try:
                data, addr = recvfrom(MAX_DATAGRAM + 64)
            except (TimeoutError, BlockingIOError, InterruptedError):
                return None
            except ConnectionRefusedError:  # an ICMP error from an earlier reply: nothing to read
                continue
            if addr[0] != robot:
                self.foreign += 1
                continue
            self.peer = addr
            return data

    def send(self, data: bytes) -> None:
        """Send a datagram to the last sender (OSError propagates: the caller decides)."""
        self.sock.sendto(data, self.peer)  # type: ignore[arg-type]

    def drain(self) -> int:
        """Discard the datagrams waiting in the socket; their number."""
        n = 0
        self.sock.setblocking(False)
        try:
            while True:
                self.sock.recvfrom(MAX_DATAGRAM + 64)
                n += 1
        except (BlockingIOError, InterruptedError, ConnectionRefusedError):
            pass
        finally:
            self.sock.settimeout(self.timeout_s)
        return n

    def close(self) -> None:
        self.sock.close()


def no_message_text(transport: UdpTransport, waited: float, undecodable: int, version: str) -> str:
    """Why no monitoring message arrived within ``waited`` [s], with hints from what did arrive."""
    text = f"no FRI monitoring message from {transport.robot_ip} on UDP port {transport.port} within {waited:.1f} s"
    hints = []
    if undecodable:
        hints.append(f"{undecodable} datagrams from it did not decode as {version} (--fri-version?)")
    if transport.foreign:
        hints.append(f"{transport.foreign} datagrams came from other addresses (--robot?)")
    if not hints:
        hints.append("is the robot application running with this PC's address and port, and the firewall open?")
    return text + "; " + "; ".join(hints)
