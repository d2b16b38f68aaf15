"""The bridge's wire format (version 1): targets from a source, the robot state back. Little-endian, fixed size.

Target (``TARGET_FORMAT``, 136 bytes)::

    offset  type        field
    0       char[4]     magic  b"LBRT"
    4       uint8       version  1
    5       uint8       kind  1 = joint positions
    6       uint16      flags  bit 0: the velocity feed-forward is set (else those bytes are ignored)
    8       uint32      sequence counter of the source (wraps; not newer than the last accepted: ignored)
    12      uint32      reserved (0)
    16      float64     source time [s] (echoed in the state, for round-trip measurements)
    24      float64[7]  target q1..q7 [rad]
    80      float64[7]  velocity feed-forward q̇1..q̇7 [rad/s]

The JSON form is one UTF-8 object per datagram: ``{"q": [7 × rad], "v": [7 × rad/s], "seq": int, "t": s}`` ("v",
"seq" and "t" optional).

State (``STATE_FORMAT``, 200 bytes)::

    0   char[4]     magic  b"LBRS"          4   uint8  version 1        5  uint8  session state (0 IDLE … 4 ACTIVE)
    6   uint16      flags  bit 0 braking, bit 1 following a target      8  uint32 the bridge's sequence counter
    12  uint32      last accepted target's sequence counter            16 float64 its source time [s]
    24  float64     controller time [s]
    32  float64[7]  measured q [rad]    88  float64[7] commanded q [rad]    144 float64[7] external torque [Nm]
"""

from __future__ import annotations

import json
import math
import struct
from dataclasses import dataclass

VERSION = 1
TARGET_MAGIC = b"LBRT"
STATE_MAGIC = b"LBRS"
TARGET_FORMAT = "<4sBBHII d 7d 7d"
TARGET_SIZE = struct.calcsize(TARGET_FORMAT)  # 136 bytes
STATE_FORMAT = "<4sBBH I I d d 7d 7d 7d"
STATE_SIZE = struct.calcsize(STATE_FORMAT)
KIND_JOINT = 1
FLAG_VELOCITY = 1
_TARGET = struct.Struct(TARGET_FORMAT)
_STATE = struct.Struct(STATE_FORMAT)
_NAN7 = (math.nan,) * 7


class BadTarget(ValueError):
    """A datagram that is not a valid target (the text says why)."""


@dataclass(frozen=True)
class Target:
    """A joint target [rad] with an optional velocity feed-forward [rad/s]; the source's counter and time [s]."""

    q: tuple[float, ...]
    v: tuple[float, ...] | None = None
    seq: int | None = None
    t: float = 0.0


def encode_target(q, v=None, seq: int = 0, t: float = 0.0) -> bytes:
    """The binary target datagram (version 1) for joint positions ``q`` [rad] and feed-forward ``v`` [rad/s]."""
    qs = tuple(float(x) for x in q)
    if len(qs) != 7:
        raise ValueError(f"a target has 7 joint positions, got {len(qs)}")
    vs = _NAN7 if v is None else tuple(float(x) for x in v)
    if len(vs) != 7:
        raise ValueError(f"the velocity feed-forward has 7 values, got {len(vs)}")
    return _TARGET.pack(TARGET_MAGIC, VERSION, KIND_JOINT, FLAG_VELOCITY if v is not None else 0, seq & 0xFFFFFFFF, 0,
                        float(t), *qs, *vs)  # fmt: skip


def _finite7(values, what: str) -> tuple[float, ...]:
    try:
        vals = tuple(float(x) for x in values)
    except (TypeError, ValueError):
        raise BadTarget(f"{what} must be 7 numbers") from None
    if len(vals) != 7:
        raise BadTarget(f"{what} must be 7 numbers, got {len(vals)}")
    if not all(math.isfinite(x) for x in vals):
        raise BadTarget(f"{what} has a value that is not finite")
    return vals


def decode_target(data: bytes) -> Target:
    """A target from a binary (magic b"LBRT") or JSON datagram; :class:`BadTarget` for anything else."""
    if data[:4] == TARGET_MAGIC:
        if len(data) != TARGET_SIZE:
            raise BadTarget(f"a version-1 target is {TARGET_SIZE} bytes, got {len(data)}")
        magic, version, kind, flags, seq, _, t, *rest = _TARGET.unpack(data)
        if version != VERSION:
            raise BadTarget(f"target version {version}, this bridge speaks {VERSION}")
        if kind != KIND_JOINT:
            raise BadTarget(f"target kind {kind} is not known (1: joint positions)")
        q = _finite7(rest[:7], "q")
        v = _finite7(rest[7:], "v") if flags & FLAG_VELOCITY else None
        return Target(q, v, seq, t if math.isfinite(t) else 0.0)
    if data[:1] == b"{":
        try:
            obj = json.loads(data.decode("utf-8"))
        except (UnicodeDecodeError, ValueError):
            raise BadTarget("not valid JSON") from None
        if not isinstance(obj, dict) or "q" not in obj:
            raise BadTarget('a JSON target needs "q": [7 joint positions in rad]')
        q = _finite7(obj["q"], "q")
        v = _finite7(obj["v"], "v") if obj.get("v") is not None else None
        seq = obj.get("seq")
        if seq is not None and not (isinstance(seq, int) and 0 <= seq <= 0xFFFFFFFF):
            raise BadTarget('"seq" must be an integer 0..2^32−1')
        t = obj.get("t", 0.0)
        return Target(q, v, seq, float(t) if isinstance(t, (int, float)) and math.isfinite(t) else 0.0)
    raise BadTarget("neither a binary target (magic LBRT) nor a JSON object")


@dataclass(frozen=True)
class State:
    """The robot state the bridge sends back."""

    session_state: int
    braking: bool
    following: bool
    seq: int
    target_seq: int
    target_t: float  # [s] the last accepted target's source time
    t: float  # [s] controller time
    measured: tuple[float, ...]  # [rad]
    commanded: tuple[float, ...]  # [rad]
    external_torque: tuple[float, ...]  # [Nm]


def encode_state(session_state: int, braking: bool, following: bool, seq: int, target_seq: int, target_t: float,
                 t: float, measured, commanded, external_torque) -> bytes:  # fmt: skip
    flags = (1 if braking else 0) | (2 if following else 0)
    return _STATE.pack(STATE_MAGIC, VERSION, session_state, flags, seq & 0xFFFFFFFF, target_seq & 0xFFFFFFFF,
                       target_t, t, *measured, *commanded, *external_torque)  # fmt: skip


def decode_state(data: bytes) -> State:
    if data[:4] != STATE_MAGIC or len(data) != STATE_SIZE:
        raise ValueError("not a version-1 bridge state datagram")
    magic, version, st, flags, seq, tseq, tt, t, *rest = _STATE.unpack(data)
    return State(st, bool(flags & 1), bool(flags & 2), seq, tseq, tt, t, tuple(rest[:7]), tuple(rest[7:14]),
                 tuple(rest[14:21]))  # fmt: skip
