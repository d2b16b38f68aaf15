"""Live camera results on the wire: one UDP datagram per tracked frame (binary or JSON), and MQTT.

Binary datagram (little-endian, 64 bytes, ``struct`` format ``<4sHHIddffffffffI``):

| offset | type | field |
|---|---|---|
| 0 | 4 bytes | magic ``LBRC`` |
| 4 | u16 | version (1) |
| 6 | u16 | flags: bit 0 found, bit 1 θ valid, bit 2 tilt valid, bit 3 tilt ambiguous |
| 8 | u32 | seq: frame index from the source |
| 12 | f64 | t_capture [s] (sender's monotonic clock) |
| 20 | f64 | t_source [s] (the source's timestamp; NaN if none) |
| 28 | f32 | latency [s] from capture to result |
| 32 | f32 | u [px] |
| 36 | f32 | v [px] |
| 40 | f32 | radius [px] |
| 44 | f32 | confidence (0–1) |
| 48 | f32 | θ [rad] |
| 52 | f32 | θx [rad] |
| 56 | f32 | θy [rad] |
| 60 | u32 | frames dropped so far |

Missing values are NaN. The JSON datagram is one object with the same names (``found``, ``seq``, ``t_capture``, …;
NaN as null).
"""

from __future__ import annotations

import json
import math
import socket
import struct
from typing import Any

from tracking.live import LiveResult

MAGIC = b"LBRC"
VERSION = 1
FORMAT = "<4sHHIddffffffffI"
SIZE = struct.calcsize(FORMAT)  # 64 bytes
FOUND, THETA_VALID, TILT_VALID, TILT_AMBIGUOUS = 1, 2, 4, 8


def result_dict(r: LiveResult) -> dict[str, Any]:
    """The result as a JSON-ready dict (NaN → None)."""

    def f(x: float):
        return float(x) if math.isfinite(x) else None

    return {
        "seq": r.seq,
        "t_capture": r.t_capture,
        "t_source": f(r.t_source),
        "latency_s": f(r.latency_s),
        "found": r.found,
        "confidence": r.confidence,
        "u": f(r.u),
        "v": f(r.v),
        "radius_px": f(r.radius_px),
        "theta": f(r.theta),
        "theta_x": f(r.theta_x),
        "theta_y": f(r.theta_y),
        "tilt_ambiguous": r.tilt_ambiguous,
        "dropped": r.dropped,
    }


def encode(r: LiveResult, fmt: str = "binary") -> bytes:
    """One datagram for a result: 'binary' (the layout above) or 'json'."""
    if fmt == "json":
        return json.dumps(result_dict(r), separators=(",", ":")).encode()
    flags = (FOUND if r.found else 0) | (THETA_VALID if math.isfinite(r.theta) else 0)
    flags |= (TILT_VALID if math.isfinite(r.theta_x) else 0) | (TILT_AMBIGUOUS if r.tilt_ambiguous else 0)
    return struct.pack(
        FORMAT,
        MAGIC,
        VERSION,
        flags,
        r.seq & 0xFFFFFFFF,
        r.t_capture,
        r.t_source,
        r.latency_s,
        r.u,
        r.v,
        r.radius_px,
        r.confidence,
        r.theta,
        r.theta_x,
        r.theta_y,
        r.dropped & 0xFFFFFFFF,
    )


def decode(data: bytes) -> dict[str, Any]:
    """A binary datagram back to a dict (ValueError if it is not one)."""
    if len(data) != SIZE or data[:4] != MAGIC:
        raise ValueError(f"not an LBRC datagram ({len(data)} bytes)")
    (_, version, flags, seq, t_cap, t_src, lat, u, v, radius, conf, theta, tx, ty, dropped) = struct.unpack(
        FORMAT, data
    )
    return {
        "version": version,
        "seq": seq,
        "t_capture": t_cap,
        "t_source": t_src,
        "latency_s": lat,
        "found": bool(flags & FOUND),
        "confidence": conf,
        "u": u,
        "v": v,
        "radius_px": radius,
        "theta": theta,
        "theta_x": tx,
        "theta_y": ty,
        "tilt_ambiguous": bool(flags & TILT_AMBIGUOUS),
        "dropped": dropped,
    }


class UdpPublisher:
    """Sends each result as one datagram to host:port (fire and forget; a full socket buffer drops, counted)."""

    def __init__(self, host: str, port: int, fmt: str = "binary") -> None:
        if fmt not in ("binary", "json"):
            raise ValueError(f"format must be binary or json, got {fmt!r}")
        self.target = (host, int(port))
        self.fmt = fmt
        self.sent = 0
        self.failed = 0
        family = socket.AF_INET6 if ":" in host else socket.AF_INET
        self._sock = socket.socket(family, socket.SOCK_DGRAM)
        self._sock.setblocking(False)

    def publish(self, r: LiveResult) -> None:
        try:
            self._sock.sendto(encode(r, self.fmt), self.target)
            self.sent += 1
        except OSError:
            self.failed += 1

    def close(self) -> None:
        self._sock.close()
