"""The source side in Python: send targets to `lbr serve` over UDP or MQTT, read the robot state it sends back."""

from __future__ import annotations

import collections
import socket
import threading
import time

from .protocol import (
    KIND_JOINT,
    KIND_POSE,
    KIND_POSE_ZYX,
    STATE_SIZE,
    State,
    decode_nonce,
    decode_state,
    encode_end,
    encode_hello,
    encode_target,
    sign,
)


class _Source:
    """Target encoding shared by the UDP and MQTT sources (sequence counter, source id, optional HMAC secret and the
    session nonce it is bound to)."""

    def __init__(self, source_id: int = 0, secret: bytes | None = None) -> None:
        self.seq = 0
        self.source_id = source_id
        self.secret = secret
        self.nonce = b""  # the bridge's session nonce (``handshake``): signatures are bound to it

    def _send(self, data: bytes) -> None:
        raise NotImplementedError

    def _signed(self, data: bytes) -> bytes:
        return sign(data, self.secret, self.nonce) if self.secret is not None else data

    def _target(self, values, v, t: float, kind: int) -> None:
        data = encode_target(values, v, self.seq, t, kind, self.source_id)
        self.seq = (self.seq + 1) & 0xFFFFFFFF
        self._send(self._signed(data))

    def send_joint(self, q, v=None, t: float = 0.0) -> None:
        """Target joint positions ``q`` [rad] (and feed-forward ``v`` [rad/s]); ``t`` [s] is echoed back."""
        self._target(q, v, t, KIND_JOINT)

    def send_pose(self, position, quaternion, twist=None, t: float = 0.0) -> None:
        """Target TCP ``position`` [m] and ``quaternion`` (w, x, y, z) in the base frame; ``twist`` (vx, vy, vz
        [m/s], ωx, ωy, ωz [rad/s]) is the velocity feed-forward."""
        self._target((*position, *quaternion), twist, t, KIND_POSE)

    def send_pose_zyx(self, position, angles, twist=None, t: float = 0.0) -> None:
        """Target TCP ``position`` [m] and fixed ``angles`` α, β, γ [rad] about the base's Z, Y, X (SimulinkIIWA)."""
        self._target((*position, *angles), twist, t, KIND_POSE_ZYX)

    def end(self) -> None:
        """Tell the bridge the source is done: it brakes to rest and ends the session (exit 0)."""
        data = encode_end(self.seq if self.secret is not None else None, self.source_id)
        self.seq = (self.seq + 1) & 0xFFFFFFFF
        self._send(self._signed(data))


class BridgeClient(_Source):
    """A UDP source for the bridge at ``host``:``port`` (the bridge answers to this socket's address). With a
    ``secret`` it first asks the bridge for its session nonce (``handshake``; the bridge must be running)."""

    def __init__(self, host: str = "127.0.0.1", port: int = 30300, timeout_s: float = 1.0,
                 secret: bytes | None = None, handshake_s: float = 10.0) -> None:  # fmt: skip
        super().__init__(0, secret)
        self.address = (host, port)
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("0.0.0.0" if host not in ("127.0.0.1", "localhost") else "127.0.0.1", 0))
        self.sock.settimeout(timeout_s)
        self._early: collections.deque[bytes] = collections.deque(maxlen=64)  # states read while waiting
        if secret is not None:
            self.handshake(handshake_s)

    def handshake(self, timeout_s: float = 10.0) -> bytes:
        """Ask the bridge for its session nonce (a hello every 50 ms until the challenge comes); the nonce.
        ConnectionError when none came within ``timeout_s``."""
        deadline = time.monotonic() + timeout_s
        old = self.sock.gettimeout()
        self.sock.settimeout(0.05)
        try:
            while time.monotonic() < deadline:
                self.sock.sendto(encode_hello(self.source_id), self.address)
                try:
                    data = self.sock.recv(STATE_SIZE + 4096)
                except (socket.timeout, TimeoutError, ConnectionRefusedError):
                    continue
                nonce = decode_nonce(data)
                if nonce is not None:
                    self.nonce = nonce
                    return nonce
                self._early.append(data)
        finally:
            self.sock.settimeout(old)
        raise ConnectionError(f"the bridge at {self.address[0]}:{self.address[1]} did not answer the hello")

    def _send(self, data: bytes) -> None:
        self.sock.sendto(data, self.address)

    def receive_state(self) -> State | None:
        """The next state datagram (None on the time-out)."""
        while True:
            if self._early:
                data = self._early.popleft()
            else:
                try:
                    data = self.sock.recv(STATE_SIZE + 4096)
                except (socket.timeout, TimeoutError):
                    return None
            if decode_nonce(data) is None:  # a late answer to a hello
                return decode_state(data)

    def close(self) -> None:
        self.sock.close()


class MqttBridgeClient(_Source):
    """An MQTT source: targets published on ``url``'s topic, the states received from ``<topic>/state``.

    ``url`` is ``mqtt://[USER:PASSWORD@]HOST:PORT/TOPIC`` (mqtts:// for TLS); ``source_id`` tells sources apart.
    With a ``secret`` it takes the bridge's session nonce from the retained ``<topic>/nonce`` (saying hello if none
    is there yet) before it signs anything."""

    def __init__(self, url: str, source_id: int = 1, secret: bytes | None = None, timeout_s: float = 5.0,
                 handshake_s: float = 10.0) -> None:  # fmt: skip
        from lbrcli.lab.telemetry import paho_client, parse_mqtt_url

        super().__init__(source_id, secret)
        self.target = parse_mqtt_url(url, "url")
        self.states: collections.deque[State] = collections.deque(maxlen=10000)
        self._ready = threading.Event()
        self._nonce_seen = threading.Event()
        self._subscribed = 0
        topics = [f"{self.target.topic}/state"] + ([f"{self.target.topic}/nonce"] if secret is not None else [])
        self._client = paho_client(f"lbr-source-{id(self):x}", self.target)
        self._client.on_connect = lambda c, u, f, rc, p: [c.subscribe(t, qos=1) for t in topics]
        self._client.on_subscribe = self._on_subscribe(len(topics))
        self._client.on_message = self._on_message
        self._client.connect_async(self.target.host, self.target.port, keepalive=10)
        self._client.loop_start()
        if not self._ready.wait(timeout_s):
            self.close()
            raise ConnectionError(f"MQTT broker {self.target.host}:{self.target.port} did not answer")
        if secret is not None:
            self.handshake(handshake_s)

    def _on_subscribe(self, n: int):
        def done(client, userdata, mid, reason_codes, properties) -> None:
            self._subscribed += 1
            if self._subscribed >= n:
                self._ready.set()

        return done

    def _on_message(self, client, userdata, message) -> None:
        if message.topic.endswith("/nonce"):
            nonce = decode_nonce(message.payload)
            if nonce is not None:
                self.nonce = nonce
                self._nonce_seen.set()
            return
        try:
            self.states.append(decode_state(message.payload))
        except (ValueError, KeyError, TypeError):
            pass

    def handshake(self, timeout_s: float = 10.0) -> bytes:
        """Wait for the bridge's session nonce (the retained one, or the answer to a hello every 0.2 s); the nonce.
        ConnectionError when none came within ``timeout_s``."""
        deadline = time.monotonic() + timeout_s
        while not self._nonce_seen.wait(0.2):
            if time.monotonic() > deadline:
                raise ConnectionError(f"the bridge on {self.target.topic} did not publish its session nonce")
            self._client.publish(self.target.topic, encode_hello(self.source_id, binary=False), qos=0)
        return self.nonce

    def _send(self, data: bytes) -> None:
        self._client.publish(self.target.topic, data, qos=0)

    def close(self) -> None:
        self._client.loop_stop()
        self._client.disconnect()
