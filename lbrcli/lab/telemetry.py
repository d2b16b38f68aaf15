"""Live telemetry over MQTT (paho-mqtt): the session state as JSON at a decimated rate, off the FRI loop.

The FRI loop calls ``offer(t, state)`` every cycle; it only compares a time stamp and, at the publish rate,
stores a reference to a small snapshot. A background thread serialises and publishes it; paho's own network
thread handles reconnects. Nothing here can block the FRI loop.
"""

from __future__ import annotations

import json
import threading
import time
from dataclasses import dataclass
from typing import Any, Callable
from urllib.parse import unquote, urlsplit

from trajectories.errors import OptionError


@dataclass(frozen=True)
class MqttTarget:
    """A broker, a topic and how to log in: user name and password (the broker authenticates), TLS (mqtts)."""

    host: str
    port: int
    topic: str
    username: str | None = None
    password: str | None = None
    tls: bool = False


def parse_mqtt_url(url: str, option: str = "LabOptions.mqtt") -> MqttTarget:
    """'mqtt://[USER:PASSWORD@]HOST:PORT/TOPIC' (port 1883 by default; 'mqtts://' for TLS, port 8883 by default;
    the topic may contain '/'); OptionError naming ``option`` (the setting, or the caller's flag)."""
    parts = urlsplit(url)
    if parts.scheme not in ("mqtt", "mqtts") or not parts.hostname:
        raise OptionError(f"{option}: expected mqtt://[USER:PASSWORD@]HOST:PORT/TOPIC, got {url!r}")
    topic = parts.path.lstrip("/")
    if not topic or "#" in url or "+" in topic:
        raise OptionError(f"{option}: a topic without wildcards is needed, e.g. mqtt://localhost:1883/lbr/state")
    try:
        port = parts.port or (8883 if parts.scheme == "mqtts" else 1883)
    except ValueError:
        raise OptionError(f"{option}: bad port in {url!r}") from None
    user = unquote(parts.username) if parts.username else None
    password = unquote(parts.password) if parts.password is not None else None
    return MqttTarget(parts.hostname, port, topic, user, password, parts.scheme == "mqtts")


def paho_client(client_id: str, target: MqttTarget | None = None):
    """A paho client (callback API 2) that reconnects by itself, logging in as ``target`` says (user, TLS)."""
    import paho.mqtt.client as mqtt

    client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id=client_id)
    client.reconnect_delay_set(min_delay=1, max_delay=5)
    if target is not None and target.username is not None:
        client.username_pw_set(target.username, target.password)
    if target is not None and target.tls:
        client.tls_set()  # the system's certificate authorities
    return client


class TelemetryPublisher:
    """Publishes the newest offered state at most ``rate_hz`` times per second to an MQTT topic."""

    def __init__(self, target: MqttTarget, rate_hz: float = 50.0) -> None:
        self.target = target
        self.period = 1.0 / rate_hz
        self.published = 0
        self.dropped = 0  # snapshots replaced before the thread sent them
        self._next_t = -1e300
        self._pending: tuple[float, Any] | None = None
        self._wake = threading.Event()
        self._stop = threading.Event()
        self._client = paho_client(f"lbr-{id(self):x}", target)
        self._thread: threading.Thread | None = None

    def start(self) -> "TelemetryPublisher":
        self._client.connect_async(self.target.host, self.target.port, keepalive=10)
        self._client.loop_start()  # paho's network thread: connects and reconnects in the background
        self._thread = threading.Thread(target=self._run, name="mqtt-telemetry", daemon=True)
        self._thread.start()
        return self

    def due(self, t: float) -> bool:
        """True when a snapshot at time t [s] would be published (lets the caller skip building one)."""
        return t >= self._next_t

    def offer(self, t: float, state: dict[str, Any] | Callable[[], dict[str, Any]]) -> None:
        """Hand over the state at time t [s] (a dict or a callable building it); cheap when not due."""
        if t < self._next_t:
            return
        self._next_t = t + self.period
        if self._pending is not None:
            self.dropped += 1
        self._pending = (t, state)
        self._wake.set()

    def _run(self) -> None:
        while not self._stop.is_set():
            self._wake.wait(0.5)
            self._wake.clear()
            item, self._pending = self._pending, None
            if item is None:
                continue
            t, state = item
            payload = state() if callable(state) else state
            payload = {"t": t, **payload}
            if self._client.is_connected():
                self._client.publish(self.target.topic, json.dumps(payload), qos=0)
                self.published += 1
            else:
                self.dropped += 1

    def stop(self, flush_timeout: float = 1.0) -> None:
        if self._thread is not None:
            deadline = time.monotonic() + flush_timeout
            while self._pending is not None and time.monotonic() < deadline:
                self._wake.set()
                time.sleep(0.01)
            self._stop.set()
            self._wake.set()
            self._thread.join(timeout=1.0)
        self._client.loop_stop()
        self._client.disconnect()


class TelemetryListener:
    """Subscribes to a topic and hands every JSON message to ``on_message(dict)`` (a remote operator's view)."""

    def __init__(self, target: MqttTarget, on_message: Callable[[dict], None]) -> None:
        self.target = target
        self.on_message = on_message
        self.received = 0
        self.malformed = 0
        self.connected = threading.Event()
        self._client = paho_client(f"lbr-listen-{id(self):x}", target)
        self._client.on_connect = self._on_connect
        self._client.on_message = self._on_message

    def _on_connect(self, client, userdata, flags, reason_code, properties) -> None:
        client.subscribe(self.target.topic, qos=0)
        self.connected.set()

    def _on_message(self, client, userdata, message) -> None:
        try:
            data = json.loads(message.payload)
        except (ValueError, UnicodeDecodeError):
            self.malformed += 1
            return
        self.received += 1
        self.on_message(data)

    def start(self) -> "TelemetryListener":
        self._client.connect_async(self.target.host, self.target.port, keepalive=10)
        self._client.loop_start()
        return self

    def stop(self) -> None:
        self._client.loop_stop()
        self._client.disconnect()
