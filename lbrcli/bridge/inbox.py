"""Targets from one or more transports (UDP, MQTT): decoding, authentication, the owner rule, counters.

Hand-over rule: the first source whose message is a valid target owns the session — on UDP a source is an address
and port, on MQTT a ``source`` id carried in the target (0 when unset). Messages from any other source are ignored
and counted (``foreign``); to hand over, end the session (the dead-man, an end message or Ctrl-C) and start another.
With a shared secret, a message without a valid HMAC tag is ignored and counted (``unauthenticated``). A message
from the owner that is not a target (or one that cannot be told apart from the owner's: an MQTT message without a
source id) sets ``error``; the follower then brakes. The state goes back to the owner in the form its targets came
in (binary or JSON).
"""

from __future__ import annotations

import json
import time
from typing import Hashable, Iterable, Protocol, Sequence

from .protocol import BadTarget, State, Target, decode_target, encode_state, encode_state_json, verify


class Transport(Protocol):
    """Where messages come from and states go back to."""

    name: str

    def receive(self) -> Iterable[tuple[bytes, Hashable | None]]:
        """The messages that arrived since the last call, each with its sender (None: the transport cannot tell)."""
        ...

    def admits(self, sender: Hashable | None) -> bool:
        """Whether ``sender`` may command at all (configured addresses)."""
        ...

    def send(self, data: bytes, sender: Hashable | None) -> None: ...

    def describe(self, sender: Hashable | None) -> str: ...

    def close(self) -> None: ...


def _end_source(data: bytes) -> int | None | bool:
    """For the end message ({"end": true}, optionally with "source"): its source id (0 if unset); False otherwise."""
    if not (data[:1] == b"{" and b'"end"' in data):
        return False
    try:
        obj = json.loads(data)
    except (UnicodeDecodeError, ValueError):
        return False
    if not (isinstance(obj, dict) and obj.get("end") is True):
        return False
    src = obj.get("source", 0)
    return src if isinstance(src, int) else 0


class TargetInbox:
    """The newest valid target from the owning source; ``error`` once the owner sent something that is not one."""

    def __init__(self, transports: Sequence[Transport], secret: bytes | None = None) -> None:
        self.transports = tuple(transports)
        self.secret = secret
        self.owner: tuple[Transport, Hashable] | None = None
        self.latest: Target | None = None
        self.latest_time = 0.0  # [s] time.monotonic() of its arrival
        self.fresh = False  # a target arrived since the follower last took one
        self.error: str | None = None
        self.ended = False  # the owner sent the end message
        self.received = self.accepted = self.bad = self.foreign = self.stale = self.unauthenticated = 0
        self._last_seq: int | None = None

    def poll(self) -> None:
        """Take in every message that arrived (non-blocking)."""
        for tr in self.transports:
            for data, sender in tr.receive():
                self.received += 1
                self._handle(tr, data, sender)

    def _identity(self, tr: Transport, sender: Hashable | None, source: int | None) -> tuple[Transport, Hashable] | None:
        if sender is not None:
            return (tr, sender)
        return None if source is None else (tr, source)

    def _is_owner(self, who: tuple[Transport, Hashable] | None) -> bool:
        return who is not None and self.owner is not None and who[0] is self.owner[0] and who[1] == self.owner[1]

    def _handle(self, tr: Transport, data: bytes, sender: Hashable | None) -> None:
        if not tr.admits(sender):
            self.foreign += 1
            return
        if self.secret is not None:
            try:
                data = verify(data, self.secret)
            except BadTarget:
                self.unauthenticated += 1
                return
        end = _end_source(data)
        if end is not False:
            if self.owner is not None and (self._is_owner(self._identity(tr, sender, end))):
                self.ended = True
            elif self.owner is not None:
                self.foreign += 1
            return
        try:
            target = decode_target(data)
        except BadTarget as exc:
            who = self._identity(tr, sender, None)
            if who is not None and self.owner is not None and not self._is_owner(who):
                self.foreign += 1
                return
            self.bad += 1
            if self.owner is not None and self.error is None:
                self.error = f"{exc} (from {tr.describe(sender)})"
            return
        who = self._identity(tr, sender, target.source)
        if self.owner is not None and not self._is_owner(who):
            self.foreign += 1
            return
        if target.seq is not None and self._last_seq is not None:
            d = (target.seq - self._last_seq) & 0xFFFFFFFF
            if d == 0 or d > 0x7FFFFFFF:
                self.stale += 1
                return
        if target.seq is not None:
            self._last_seq = target.seq
        self.owner = who
        self.latest = target
        self.latest_time = time.monotonic()
        self.fresh = True
        self.accepted += 1

    def send(self, state: State) -> None:
        """Send ``state`` to the owner, in the form of its targets (nothing before there is an owner)."""
        if self.owner is None:
            return
        tr, who = self.owner
        binary = self.latest.binary if self.latest is not None else True
        tr.send(encode_state(state) if binary else encode_state_json(state), who)

    def close(self) -> None:
        for tr in self.transports:
            tr.close()

    def figures(self) -> dict[str, int | str | None]:
        return {
            "targets_received": self.received,
            "targets_accepted": self.accepted,
            "targets_bad": self.bad,
            "targets_foreign": self.foreign,
            "targets_stale": self.stale,
            "targets_unauthenticated": self.unauthenticated,
            "source": self.owner[0].describe(self.owner[1]) if self.owner else None,
        }
