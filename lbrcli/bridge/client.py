"""The source side in Python: send joint targets to `lbr serve`, read the robot state it sends back."""

from __future__ import annotations

import socket

from .protocol import STATE_SIZE, State, decode_state, encode_target


class BridgeClient:
    """A UDP source for the bridge at ``host``:``port`` (the bridge answers to this socket's address)."""

    def __init__(self, host: str = "127.0.0.1", port: int = 30300, timeout_s: float = 1.0) -> None:
        self.address = (host, port)
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("0.0.0.0" if host not in ("127.0.0.1", "localhost") else "127.0.0.1", 0))
        self.sock.settimeout(timeout_s)
        self.seq = 0

    def send_joint(self, q, v=None, t: float = 0.0) -> None:
        """Target joint positions ``q`` [rad] (and feed-forward ``v`` [rad/s]); ``t`` [s] is echoed back."""
        self.sock.sendto(encode_target(q, v, self.seq, t), self.address)
        self.seq = (self.seq + 1) & 0xFFFFFFFF

    def end(self) -> None:
        """Tell the bridge the source is done: it brakes to rest and ends the session (exit 0)."""
        self.sock.sendto(b'{"end": true}', self.address)

    def receive_state(self) -> State | None:
        """The next state datagram (None on the time-out)."""
        try:
            data = self.sock.recv(STATE_SIZE + 64)
        except (socket.timeout, TimeoutError):
            return None
        return decode_state(data)

    def close(self) -> None:
        self.sock.close()
