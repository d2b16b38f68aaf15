"""Targets from one or more transports (UDP, MQTT): decoding, authentication, the owner rule, counters.

Hand-over rule: the first source whose message is a valid target owns the session — on UDP a source is an address
and port, on MQTT a ``source`` id carried in the target (0 when unset). Messages from any other source are ignored
and counted (``foreign``); to hand over, end the session (the dead-man, an end message or Ctrl-C) and start another.

Every message is judged when it arrives, also when several come in one FRI cycle: a target is 7 finite numbers (JSON:
numbers only) and a joint target lies inside the position limits. An invalid message from the owner sets ``error``
(the follower brakes, exit 1); one that cannot be told to come from the owner (from another address, another source
id, or MQTT garbage that names no source) is ignored and counted (``bad``) — it never stops the session.

With a shared secret (``secret``) a message counts only with a valid HMAC tag for this session's random nonce
(:mod:`~lbrcli.bridge.protocol`: a source asks for it with a hello); messages signed in an earlier session, unsigned
or forged ones are ignored and counted (``unauthenticated``). Within the session the sequence counter inside the
signed message must grow: replays and reordering are ``stale``. The end message is bound to the owner the same way.
The state goes back to the owner in the form its targets came in (binary or JSON).
"""

from __future__ import annotations

import json
import os
import time
from typing import Hashable, Iterable, Protocol, Sequence

from .protocol import (
    KIND_JOINT,
    BadTarget,
    State,
    Target,
    claimed_source,
    decode_target,
    encode_nonce,
    encode_state,
    encode_state_json,
    is_hello,
    verify,
)


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

    # optional: ``announce(data)`` publishes the session's challenge where any source finds it (MQTT); a transport
    # without it answers each hello to its sender

    def describe(self, sender: Hashable | None) -> str: ...

    def close(self) -> None: ...


def _end_message(data: bytes) -> tuple[int, int | None] | None:
    """For the end message (``{"end": true}``, optionally with ``"source"`` and ``"seq"``): (source id, seq);
    None for anything else."""
    if not (data[:1] == b"{" and b'"end"' in data):
        return None
    try:
        obj = json.loads(data)
    except (UnicodeDecodeError, ValueError, RecursionError):
        return None
    if not (isinstance(obj, dict) and obj.get("end") is True):
        return None
    src, seq = obj.get("source", 0), obj.get("seq")
    src = src if isinstance(src, int) and not isinstance(src, bool) else 0
    seq = seq if isinstance(seq, int) and not isinstance(seq, bool) and 0 <= seq <= 0xFFFFFFFF else None
    return src, seq


class TargetInbox:
    """The newest valid target from the owning source; ``error`` once the owner sent something that is not one.
    ``limits`` (a JointLimits): joint targets beyond its position limits are invalid."""

    def __init__(self, transports: Sequence[Transport], secret: bytes | None = None, limits=None) -> None:
        self.transports = tuple(transports)
        self.secret = secret
        self.nonce = os.urandom(16) if secret is not None else b""  # this session's: signatures are bound to it
        self._upper = tuple(float(x) for x in limits.position) if limits is not None else None
        self.owner: tuple[Transport, Hashable] | None = None
        self.latest: Target | None = None
        self.latest_time = 0.0  # [s] time.monotonic() of its arrival
        self.fresh = False  # a target arrived since the follower last took one
        self.error: str | None = None
        self.ended = False  # the owner sent the end message
        self.received = self.accepted = self.bad = self.foreign = self.stale = self.unauthenticated = 0
        self.hellos = 0
        self.last_bad: str | None = None  # why the last invalid message was refused
        self._last_seq: int | None = None
        for tr in self.transports:
            announce = getattr(tr, "announce", None)
            if announce is not None and secret is not None:
                announce(encode_nonce(self.nonce, binary=False))  # MQTT: retained, for sources that start later

    def poll(self) -> None:
        """Take in and judge every message that arrived (non-blocking)."""
        for tr in self.transports:
            for data, sender in tr.receive():
                self.received += 1
                self._handle(tr, data, sender)

    def _identity(
        self, tr: Transport, sender: Hashable | None, source: int | None
    ) -> tuple[Transport, Hashable] | None:
        if sender is not None:
            return (tr, sender)
        return None if source is None else (tr, source)

    def _is_owner(self, who: tuple[Transport, Hashable] | None) -> bool:
        return who is not None and self.owner is not None and who[0] is self.owner[0] and who[1] == self.owner[1]

    def _fresh_seq(self, seq: int | None) -> bool:
        """The owner's counter grew (a message without one passes unless the session is signed)."""
        if seq is None:
            return self.secret is None
        last = self._last_seq
        if last is None:
            return True
        d = (seq - last) & 0xFFFFFFFF
        return 0 < d <= 0x7FFFFFFF

    def _handle(self, tr: Transport, data: bytes, sender: Hashable | None) -> None:
        if not tr.admits(sender):
            self.foreign += 1
            return
        hello = is_hello(data)
        if hello is not None:  # a source asks for the session nonce: the challenge goes back to it
            self.hellos += 1
            challenge = encode_nonce(self.nonce, binary=hello)
            announce = getattr(tr, "announce", None)  # MQTT: the retained nonce topic (no sender to answer)
            announce(challenge) if announce is not None else tr.send(challenge, sender)
            return
        if self.secret is not None:
            try:
                data = verify(data, self.secret, self.nonce)
            except BadTarget:
                self.unauthenticated += 1
                return
        end = _end_message(data)
        if end is not None:
            who = self._identity(tr, sender, end[0])
            if self.owner is not None and self._is_owner(who) and self._fresh_seq(end[1]):
                self.ended = True
            elif self.owner is not None and self._is_owner(who):
                self.stale += 1
            else:
                self.foreign += 1
            return
        try:
            target = decode_target(data)
            self._check_limits(target)
        except BadTarget as exc:
            self.bad += 1
            self.last_bad = f"{exc} (from {tr.describe(sender)})"
            who = self._identity(tr, sender, claimed_source(data))
            if self.owner is not None and self._is_owner(who) and self.error is None:
                self.error = f"{exc} (from {tr.describe(sender)})"
            return
        who = self._identity(tr, sender, target.source)
        if self.owner is not None and not self._is_owner(who):
            self.foreign += 1
            return
        if target.seq is not None or self.secret is not None:
            if not self._fresh_seq(target.seq):
                self.stale += 1
                return
            self._last_seq = target.seq
        self.owner = who
        self.latest = target
        self.latest_time = time.monotonic()
        self.fresh = True
        self.accepted += 1

    def _check_limits(self, target: Target) -> None:
        upper = self._upper
        if upper is None or target.kind != KIND_JOINT:
            return
        for j, (x, u) in enumerate(zip(target.values, upper)):
            if not -u <= x <= u:
                raise BadTarget(f"the target for A{j + 1} ({x:.4f} rad) is outside its position limits [{-u:g}, {u:g}]")

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
            "hellos": self.hellos,
            "source": self.owner[0].describe(self.owner[1]) if self.owner else None,
        }
