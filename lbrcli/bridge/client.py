"""The source side in Python: send targets to `lbr serve` over UDP or MQTT, read the robot state it sends back."""

from __future__ import annotations

import collections
import json
import socket
import threading

from .protocol import KIND_JOINT, KIND_POSE, KIND_POSE_ZYX, STATE_SIZE, State, decode_state, encode_target, sign


class _Source:
    """Target encoding shared by the UDP and MQTT sources (sequence counter, source id, optional HMAC secret)."""

    def __init__(self, source_id: int = 0, secret: bytes | None = None) -> None:
        self.seq = 0
        self.source_id = source_id
        self.secret = secret

    def _send(self, data: bytes) -> None:
        raise NotImplementedError

    def _target(self, values, v, t: float, kind: int) -> None:
        data = encode_target(values, v, self.seq, t, kind, self.source_id)
        self.seq = (self.seq + 1) & 0xFFFFFFFF
        self._send(sign(data, self.secret) if self.secret is not None else data)

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
        data = json.dumps({"end": True, "source": self.source_id}).encode()
        self._send(sign(data, self.secret) if self.secret is not None else data)


class BridgeClient(_Source):
    """A UDP source for the bridge at ``host``:``port`` (the bridge answers to this socket's address)."""

    def __init__(self, host: str = "127.0.0.1", port: int = 30300, timeout_s: float = 1.0,
                 secret: bytes | None = None) -> None:  # fmt: skip
        super().__init__(0, secret)
        self.address = (host, port)
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("0.0.0.0" if host not in ("127.0.0.1", "localhost") else "127.0.0.1", 0))
        self.sock.settimeout(timeout_s)

    def _send(self, data: bytes) -> None:
        self.sock.sendto(data, self.address)

    def receive_state(self) -> State | None:
        """The next state datagram (None on the time-out)."""
        try:
            data = self.sock.recv(STATE_SIZE + 4096)
        except (socket.timeout, TimeoutError):
            return None
        return decode_state(data)

    def close(self) -> None:
        self.sock.close()


class MqttBridgeClient(_Source):
    """An MQTT source: targets published on ``url``'s topic, the states received from ``<topic>/state``.

    ``url`` is ``mqtt://[USER:PASSWORD@]HOST:PORT/TOPIC`` (mqtts:// for TLS); ``source_id`` tells sources apart."""

    def __init__(self, url: str, source_id: int = 1, secret: bytes | None = None, timeout_s: float = 5.0) -> None:
        from lbrcli.lab.telemetry import paho_client, parse_mqtt_url

        super().__init__(source_id, secret)
        self.target = parse_mqtt_url(url, "url")
        self.states: collections.deque[State] = collections.deque(maxlen=10000)
        self._ready = threading.Event()
        self._client = paho_client(f"lbr-source-{id(self):x}", self.target)
        self._client.on_connect = lambda c, u, f, rc, p: c.subscribe(f"{self.target.topic}/state", qos=0)
        self._client.on_subscribe = lambda c, u, mid, rcs, p: self._ready.set()
        self._client.on_message = lambda c, u, m: self.states.append(decode_state(m.payload))
        self._client.connect_async(self.target.host, self.target.port, keepalive=10)
        self._client.loop_start()
        if not self._ready.wait(timeout_s):
            self.close()
            raise ConnectionError(f"MQTT broker {self.target.host}:{self.target.port} did not answer")

    def _send(self, data: bytes) -> None:
        self._client.publish(self.target.topic, data, qos=0)

    def close(self) -> None:
        self._client.loop_stop()
        self._client.disconnect()
