"""Encoding and decoding of FRI datagrams for both wire formats.

FRI 1.x: the datagram is the bare protobuf encoding. FRI 2.7: [uint32 LE length][protobuf][uint32 LE CRC-32].
Decoders check the framing, the CRC, the header, the message identifier and the required fields, and raise
FriDecodeError on anything else (its subclass FriForeignMessage for a valid message with another identifier);
standard protobuf parsing accepts both packed and unpacked repeated doubles.
"""

from __future__ import annotations

import struct
import zlib
from typing import Any

from google.protobuf.message import DecodeError

from trajectories.errors import FriDecodeError, FriForeignMessage

from .constants import COMMAND_MESSAGE_ID, MAX_DATAGRAM, MONITORING_MESSAGE_ID
from .messages import FriMessages, FriVersion, messages

_U32 = struct.Struct("<I")


class FriCodec:
    """Encoder/decoder of one FRI version. Decoding can reuse a message object (no allocation per cycle)."""

    def __init__(self, version: FriVersion | str = FriVersion.V1_15) -> None:
        self.version = FriVersion(version)
        self.msgs: FriMessages = messages(self.version)
        self.framed = self.version is FriVersion.V2_7

    # -- framing ---------------------------------------------------------------------------------------------
    def frame(self, payload: bytes) -> bytes:
        """Wrap a protobuf payload for the wire (2.7: length + payload + CRC-32)."""
        if not self.framed:
            return payload
        return _U32.pack(len(payload)) + payload + _U32.pack(zlib.crc32(payload) & 0xFFFFFFFF)

    def unframe(self, data: bytes) -> bytes:
        """The protobuf payload of a datagram; FriDecodeError on bad length or CRC."""
        if len(data) > MAX_DATAGRAM:
            raise FriDecodeError(f"datagram of {len(data)} bytes exceeds {MAX_DATAGRAM}")
        if not self.framed:
            return data
        if len(data) < 8:
            raise FriDecodeError(f"FRI 2.7 datagram too short ({len(data)} bytes)")
        (length,) = _U32.unpack_from(data, 0)
        if length != len(data) - 8:
            raise FriDecodeError(f"FRI 2.7 length field {length} does not match datagram ({len(data) - 8} bytes)")
        payload = data[4 : 4 + length]
        (crc,) = _U32.unpack_from(data, 4 + length)
        if crc != (zlib.crc32(payload) & 0xFFFFFFFF):
            raise FriDecodeError("FRI 2.7 CRC-32 mismatch")
        return payload

    # -- messages --------------------------------------------------------------------------------------------
    def new_monitoring(self) -> Any:
        return self.msgs.Monitoring()

    def new_command(self) -> Any:
        return self.msgs.Command()

    def encode(self, message: Any) -> bytes:
        """Serialise a monitoring or command message (required fields must be set) and frame it."""
        return self.frame(message.SerializeToString())

    def _decode(self, data: bytes, into: Any, expected_id: int, kind: str) -> Any:
        payload = self.unframe(data)
        try:
            into.ParseFromString(payload)  # (clears the message first)
        except DecodeError as exc:
            raise FriDecodeError(f"not an FRI {self.version.value} {kind} message ({exc})") from None
        complete = into.IsInitialized()  # every required field, the header's included (the common case: one call)
        if not complete and not into.HasField("header"):
            raise FriDecodeError(f"FRI {self.version.value} {kind} message without a header")
        ident = into.header.messageIdentifier
        if ident != expected_id:
            raise FriForeignMessage(f"{kind} message identifier 0x{ident:x}, expected 0x{expected_id:x}")
        if not complete:
            missing = ", ".join(into.FindInitializationErrors())
            raise FriDecodeError(f"FRI {self.version.value} {kind} message lacks required fields: {missing}")
        return into

    def decode_monitoring(self, data: bytes, into: Any | None = None) -> Any:
        """Parse a monitoring message (controller → client) into ``into`` (or a new message)."""
        return self._decode(
            data, into if into is not None else self.msgs.Monitoring(), MONITORING_MESSAGE_ID, "monitoring"
        )

    def decode_command(self, data: bytes, into: Any | None = None) -> Any:
        """Parse a command message (client → controller) into ``into`` (or a new message)."""
        return self._decode(data, into if into is not None else self.msgs.Command(), COMMAND_MESSAGE_ID, "command")


def detect_version(data: bytes) -> FriVersion | None:
    """The wire format of a monitoring datagram: 2.7 when it carries a matching length and CRC-32, 1.15 when it
    decodes as a bare 1.15 monitoring message, None otherwise."""
    if len(data) >= 8:
        (length,) = _U32.unpack_from(data, 0)
        if length == len(data) - 8:
            (crc,) = _U32.unpack_from(data, 4 + length)
            if crc == (zlib.crc32(data[4 : 4 + length]) & 0xFFFFFFFF):
                try:
                    FriCodec(FriVersion.V2_7).decode_monitoring(data)
                    return FriVersion.V2_7
                except FriDecodeError:
                    return None
    try:
        FriCodec(FriVersion.V1_15).decode_monitoring(data)
        return FriVersion.V1_15
    except FriDecodeError:
        return None
