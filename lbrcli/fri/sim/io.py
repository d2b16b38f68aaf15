"""The robot application's FRI IO configuration as the controller reports it and the client writes it.

Every configured channel is in every monitoring message's readIORequest with its type and direction (inputs:
INPUT, outputs: OUTPUT, as KUKA's controller sends them). A client's writeIORequest sets outputs; a write to an
input, to an unknown channel or with the wrong type is refused (counted, ignored) — KUKA's client SDK itself
refuses to write anything but an OUTPUT.
"""

from __future__ import annotations

from typing import Any, Iterable

from trajectories.errors import SettingError

from .config import IoChannel

_TYPES = {"boolean": "BOOLEAN", "digital": "DIGITAL", "analog": "ANALOG"}


class IoBank:
    """The channels inside one monitoring message (``readIORequest`` entries created once, values updated)."""

    def __init__(self, monitor_data: Any, enums: dict[str, dict[str, int]], channels: Iterable[IoChannel]) -> None:
        self._md = monitor_data
        self._type = {k: enums["FriIOType"][v] for k, v in _TYPES.items()}
        self._dir = {"in": enums["FriIODirection"]["INPUT"], "out": enums["FriIODirection"]["OUTPUT"]}
        self._by_name: dict[str, tuple[IoChannel, Any]] = {}
        self.writes = 0  # accepted writes
        self.refused = 0  # refused writes
        for ch in channels:
            self.add(ch)

    def add(self, ch: IoChannel) -> Any:
        """Configure a channel; returns its message entry (set ``analogValue``/``digitalValue`` on it)."""
        if ch.name in self._by_name:
            raise SettingError("SimConfig", "io", f"channel {ch.name} configured twice")
        io = self._md.readIORequest.add()
        io.name, io.type, io.direction = ch.name, self._type[ch.type], self._dir[ch.direction]
        if ch.is_analog:
            io.analogValue = float(ch.value)
        else:
            io.digitalValue = int(ch.value)
        self._by_name[ch.name] = (ch, io)
        return io

    def entry(self, name: str) -> Any | None:
        got = self._by_name.get(name)
        return got[1] if got is not None else None

    def channel(self, name: str) -> IoChannel | None:
        got = self._by_name.get(name)
        return got[0] if got is not None else None

    def value(self, name: str) -> float:
        """Current value of a channel (analog: float, boolean/digital: the integer)."""
        ch, io = self._by_name[name]
        return io.analogValue if ch.is_analog else float(io.digitalValue)

    def apply(self, requests: Any) -> None:
        """Apply a command message's writeIORequest (repeated FriIOValue)."""
        for w in requests:
            got = self._by_name.get(w.name)
            if got is None or not got[0].is_output or w.type != self._type[got[0].type]:
                self.refused += 1
                continue
            ch, io = got
            if ch.is_analog:
                if not w.HasField("analogValue"):
                    self.refused += 1
                    continue
                io.analogValue = w.analogValue
            else:
                if not w.HasField("digitalValue"):
                    self.refused += 1
                    continue
                io.digitalValue = (1 if w.digitalValue else 0) if ch.type == "boolean" else w.digitalValue
            self.writes += 1
