"""MQTT transport: targets on a command topic, the state published on ``<topic>/state`` at a chosen rate.

paho's network thread receives (its callback only appends the payload to a bounded deque); the FRI loop drains the
deque once per cycle, so the broker never blocks a cycle. MQTT does not tell who published: the broker
authenticates the clients (user name and password in the URL, TLS with mqtts://, its ACL decides who may publish on
the command topic), and a shared secret (HMAC-SHA256 on every message, bound to the session's nonce that is published
retained on ``<topic>/nonce``) lets the bridge itself refuse anyone else, and replays.
"""

from __future__ import annotations

import collections
import threading
import time
from typing import Hashable, Iterator

from lbrcli.lab.telemetry import MqttTarget, paho_client


class MqttUnavailable(RuntimeError):
    """The broker could not be reached or refused the log-in (the text says which)."""


class MqttTransport:
    """Commands on ``target.topic``; states to ``state_topic`` (default ``<topic>/state``) at most ``state_rate_hz``."""

    name = "mqtt"

    def __init__(self, target: MqttTarget, state_topic: str | None = None, state_rate_hz: float = 50.0,
                 queue: int = 4096) -> None:  # fmt: skip
        self.target = target
        self.state_topic = state_topic or f"{target.topic}/state"
        self.state_period = 1.0 / state_rate_hz if state_rate_hz > 0 else None  # [s]; None: no state
        self.published = 0
        self.overflow = 0  # messages dropped because the FRI loop did not drain them (queue full)
        self._queue: collections.deque[bytes] = collections.deque(maxlen=queue)
        self._next_state = 0.0
        self._ready = threading.Event()
        self._refused: str | None = None
        self._announced = False
        self._client = paho_client(f"lbr-serve-{id(self):x}", target)
        self._client.on_connect = self._on_connect
        self._client.on_subscribe = self._on_subscribe
        self._client.on_message = self._on_message

    def start(self, timeout_s: float = 5.0) -> "MqttTransport":
        """Connect and subscribe; :class:`MqttUnavailable` when that does not happen within ``timeout_s``."""
        try:
            self._client.connect_async(self.target.host, self.target.port, keepalive=10)
        except (OSError, ValueError) as exc:
            raise MqttUnavailable(f"cannot connect to {self.target.host}:{self.target.port}: {exc}") from None
        self._client.loop_start()
        if not self._ready.wait(timeout_s):
            self.close()
            why = self._refused or f"no answer within {timeout_s:g} s"
            raise MqttUnavailable(f"MQTT broker {self.target.host}:{self.target.port}: {why}")
        return self

    def _on_connect(self, client, userdata, flags, reason_code, properties) -> None:
        if reason_code.is_failure:
            self._refused = f"refused the connection ({reason_code})"
            return
        client.subscribe(self.target.topic, qos=0)

    def _on_subscribe(self, client, userdata, mid, reason_codes, properties) -> None:
        if any(rc.is_failure for rc in reason_codes):
            self._refused = f"refused the subscription to {self.target.topic}"
            return
        self._ready.set()

    def _on_message(self, client, userdata, message) -> None:
        if len(self._queue) == self._queue.maxlen:
            self.overflow += 1
        self._queue.append(message.payload)

    def receive(self) -> Iterator[tuple[bytes, Hashable | None]]:
        queue = self._queue
        while queue:
            yield queue.popleft(), None

    def admits(self, sender: Hashable | None) -> bool:
        return True

    def send(self, data: bytes, sender: Hashable | None) -> None:
        """Publish ``data`` on the state topic unless the last one went out less than a state period ago."""
        if self.state_period is None:
            return
        now = time.monotonic()
        if now < self._next_state:
            return
        self._next_state = now + self.state_period
        self._client.publish(self.state_topic, data, qos=0)
        self.published += 1

    @property
    def nonce_topic(self) -> str:
        return f"{self.target.topic}/nonce"

    def announce(self, data: bytes) -> None:
        """Publish the session's challenge (its nonce), retained on ``<topic>/nonce``: a source that starts later,
        or says hello, finds it there."""
        self._client.publish(self.nonce_topic, data, qos=1, retain=True)
        self._announced = True

    def describe(self, sender: Hashable | None) -> str:
        where = f"mqtt://{self.target.host}:{self.target.port}/{self.target.topic}"
        return f"{where} source {sender}" if sender is not None else where

    def close(self) -> None:
        if self._announced:  # the session's nonce goes with it: no source signs for a session that is over
            self._client.publish(self.nonce_topic, b"", qos=1, retain=True).wait_for_publish(1.0)
        self._client.loop_stop()
        self._client.disconnect()
