"""The monitoring side of a session, a collaborator of :class:`~lbrcli.fri.application.ClientApplication`: each
datagram decoded into the session's one monitoring message and checked before anything may answer it — the wire
format (detected from the first datagram unless given), the sequence (stale and repeated messages are dropped) and
self-consistency (:func:`~lbrcli.fri.supervision.consistent`: a message no real controller sends is never answered).
"""

from __future__ import annotations

from typing import Any, Sequence

from .codec import FriCodec, detect_version
from .command import LBRCommand
from .errors import FriDecodeError
from .messages import FriVersion
from .state import LBRState
from .supervision import commanding_end, consistent, joint_bound

from .constants import STATE_COMMANDING_ACTIVE as CMD_ACTIVE


class Inbound:
    """Decodes the controller's datagrams into one reused message, viewed by ``state`` (an :class:`LBRState`) and
    commanded through ``command`` (an :class:`LBRCommand`), both made when the wire format is known.
    ``position_limit`` [rad]: the joints' position limits (a reported position well beyond them is not a robot's)."""

    def __init__(self, version: FriVersion | None, position_limit: Sequence[float]) -> None:
        self.version = version  # None: the first datagram tells
        self._bound = joint_bound(position_limit)  # [rad] |joint value| a real robot reports at most
        self.codec: FriCodec | None = None
        self.mon: Any = None  # the monitoring message every datagram is decoded into
        self.state: LBRState | None = None
        self.command: LBRCommand | None = None
        self.last_seq = -1  # sequence counter of the last accepted message (−1: none yet)
        self.last_data: bytes | None = None  # the last accepted datagram (decoded again while busy-waiting)
        self.malformed = 0  # undecodable or not self-consistent
        self.stale = 0  # repeated or older than the last accepted

    def open(self, data: bytes) -> bool:
        """The codec for the session's wire format (``version``, else detected from ``data``); False if unknown
        (the datagram counts as malformed)."""
        version = self.version or detect_version(data)
        if version is None:
            self.malformed += 1
            return False
        self.version = version
        self.codec = FriCodec(version)
        self.mon = self.codec.new_monitoring()
        self.state = LBRState(self.mon, version)
        self.command = LBRCommand(self.state)
        return True

    def decode(self, data: bytes) -> int:
        """Decode ``data`` into the message and check it (the codec is open): the sequence step from the last
        accepted message (0 for the first), or −1 for a datagram never answered (malformed, stale, inconsistent)."""
        mon = self.mon
        try:
            self.codec.decode_monitoring(data, mon)  # type: ignore[union-attr]
        except FriDecodeError:
            self.malformed += 1
            return -1
        d = 0
        seq = mon.header.sequenceCounter
        if self.last_seq >= 0:
            d = (seq - self.last_seq) & 0xFFFFFFFF
            if d == 0 or d > 0x7FFFFFFF:
                self.stale += 1
                return -1
        if not consistent(mon, self._bound):
            self.malformed += 1
            return -1
        self.last_data = data
        self.last_seq = seq
        return d

    def warm(self, period_key: tuple[int, int] | None) -> None:
        """Between messages (the transport's busy-wait): decode the last good datagram again into the message it
        is already in (the same values) and run the checks a prepared reply waits for, so that their code and data
        are in the CPU's caches when the next message arrives."""
        data = self.last_data
        if data is not None:
            mon = self.codec.decode_monitoring(data, self.mon)  # type: ignore[union-attr]
            consistent(mon, self._bound)
            commanding_end(mon, CMD_ACTIVE, True, period_key)
