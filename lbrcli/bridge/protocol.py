"""The bridge's wire format (version 1): targets from a source, the robot state back. Little-endian, fixed size.

Target (``TARGET_FORMAT``, 136 bytes)::

    offset  type        field
    0       char[4]     magic  b"LBRT"
    4       uint8       version  1
    5       uint8       kind  1 joint positions, 2 TCP pose (quaternion), 3 TCP pose (fixed angles)
    6       uint16      flags  bit 0: the feed-forward is set (else those bytes are ignored)
    8       uint32      sequence counter of the source (wraps; not newer than the last accepted: ignored)
    12      uint32      source id (tells MQTT sources apart: the first one owns the session; 0 if unused)
    16      float64     source time [s] (echoed in the state, for round-trip measurements)
    24      float64[7]  kind 1: q1..q7 [rad]
                        kind 2: x, y, z [m] of the TCP in the base frame, then the quaternion w, x, y, z
                        kind 3: x, y, z [m], then α, β, γ [rad] about the base's Z, Y, X (R = Rz·Ry·Rx), then 0
    80      float64[7]  feed-forward — kind 1: q̇1..q̇7 [rad/s]; kinds 2, 3: TCP velocity vx, vy, vz [m/s],
                        ωx, ωy, ωz [rad/s] in the base frame, then 0

The JSON form is one UTF-8 object per datagram or message, one of ``{"q": [7 × rad], "v": [7 × rad/s]}``,
``{"pose": [x, y, z, qw, qx, qy, qz], "twist": [6]}`` or ``{"pose_zyx": [x, y, z, α, β, γ], "twist": [6]}``, each
with optional ``"seq"`` (int), ``"t"`` [s] and ``"source"`` (int). ``{"end": true}`` ends the session.

With a shared secret every message (either form, the end message too) carries
``HMAC-SHA256(secret, nonce ‖ message)`` as its last 32 bytes, where ``nonce`` is the bridge's random 16-byte session
nonce: a source asks for it with a hello (``b"LBRH"`` + u8 version 1 + 3 zero bytes + u32 source id, 12 bytes, or
``{"hello": true, "source": id}``) and the bridge answers with the challenge (``b"LBRN"`` + u8 1 + 3 zero bytes + the
16-byte nonce, or ``{"nonce": "<32 hex digits>"}``; on MQTT published, retained, on ``<topic>/nonce``). A message
signed in another session fails (replays from earlier sessions); within a session the sequence counter inside the
signed message must grow (replays and reordering are stale); the end message carries the owner's ``seq`` and
``source`` and is judged the same way.

State (``STATE_FORMAT``, 256 bytes)::

    0   char[4]     magic  b"LBRS"          4   uint8  version 1        5  uint8  session state (0 IDLE … 4 ACTIVE)
    6   uint16      flags  bit 0 braking, bit 1 following a target, bit 2 the last pose target was not reached
                    (out of reach or beyond a position limit: the closest configuration is followed)
    8   uint32      the bridge's sequence counter   12  uint32  last accepted target's sequence counter
    16  float64     its source time [s]             24  float64 controller time [s]
    32  float64[7]  measured q [rad]    88  float64[7] commanded q [rad]    144 float64[7] external torque [Nm]
    200 float64[7]  the commanded TCP pose: x, y, z [m], quaternion w, x, y, z
"""

from __future__ import annotations

import hashlib
import hmac
import json
import math
import struct
from dataclasses import dataclass

VERSION = 1
TARGET_MAGIC = b"LBRT"
STATE_MAGIC = b"LBRS"
TARGET_FORMAT = "<4sBBHII d 7d 7d"
TARGET_SIZE = struct.calcsize(TARGET_FORMAT)  # 136 bytes
STATE_FORMAT = "<4sBBH I I d d 7d 7d 7d 7d"
STATE_SIZE = struct.calcsize(STATE_FORMAT)  # 256 bytes
KIND_JOINT = 1
"""Target kind: seven joint positions [rad]."""
KIND_POSE = 2  # position [m] + quaternion (w, x, y, z)
"""Target kind: a TCP pose, position [m] and unit quaternion (w, x, y, z)."""
KIND_POSE_ZYX = 3  # position [m] + fixed angles about Z, Y, X [rad]
"""Target kind: a TCP pose, position [m] and fixed angles about Z, Y, X [rad]."""
KINDS = {KIND_JOINT: "joint positions", KIND_POSE: "TCP pose (quaternion)", KIND_POSE_ZYX: "TCP pose (fixed angles)"}
FLAG_VELOCITY = 1
TAG_SIZE = 32  # HMAC-SHA256
_TARGET = struct.Struct(TARGET_FORMAT)
_STATE = struct.Struct(STATE_FORMAT)
_NAN7 = (math.nan,) * 7
_JSON_KINDS = (
    ("q", KIND_JOINT, 7, "v", 7),
    ("pose", KIND_POSE, 7, "twist", 6),
    ("pose_zyx", KIND_POSE_ZYX, 6, "twist", 6),
)


class BadTarget(ValueError):
    """A datagram that is not a valid target (the text says why)."""


@dataclass(frozen=True)
class Target:
    """A target of ``kind`` (see the layout): 7 ``values`` and an optional feed-forward ``v``; the source's counter,
    time [s] and id."""

    values: tuple[float, ...]
    v: tuple[float, ...] | None = None
    seq: int | None = None
    t: float = 0.0
    kind: int = KIND_JOINT
    source: int = 0
    binary: bool = True  # arrived in the binary form (the state goes back in the same form)


def encode_target(values, v=None, seq: int = 0, t: float = 0.0, kind: int = KIND_JOINT, source: int = 0) -> bytes:
    """The binary target datagram (version 1): joint positions [rad] or a pose (see the layout), feed-forward ``v``
    (7 joint velocities [rad/s], or the 6-value TCP twist [m/s, rad/s] for a pose)."""
    if kind not in KINDS:
        raise ValueError(f"target kind {kind} is not known")
    vals = tuple(float(x) for x in values)
    if kind == KIND_POSE_ZYX and len(vals) == 6:
        vals += (0.0,)
    if len(vals) != 7:
        raise ValueError(f"a target of kind {kind} has {6 if kind == KIND_POSE_ZYX else 7} values, got {len(vals)}")
    vs = _NAN7 if v is None else tuple(float(x) for x in v)
    if kind != KIND_JOINT and len(vs) == 6:
        vs += (0.0,)
    if len(vs) != 7:
        raise ValueError(f"the feed-forward has {7 if kind == KIND_JOINT else 6} values, got {len(vs)}")
    return _TARGET.pack(TARGET_MAGIC, VERSION, kind, FLAG_VELOCITY if v is not None else 0, seq & 0xFFFFFFFF,
                        source & 0xFFFFFFFF, float(t), *vals, *vs)  # fmt: skip


HELLO_MAGIC = b"LBRH"
NONCE_MAGIC = b"LBRN"
NONCE_SIZE = 16
_HELLO = struct.Struct("<4sB3xI")  # 12 bytes
_NONCE = struct.Struct("<4sB3x16s")  # 24 bytes


def sign(message: bytes, secret: bytes, nonce: bytes = b"") -> bytes:
    """``message`` followed by its HMAC-SHA256 tag under ``secret`` for the session ``nonce`` (see the layout)."""
    return message + hmac.digest(secret, nonce + message, hashlib.sha256)


def verify(data: bytes, secret: bytes, nonce: bytes = b"") -> bytes:
    """The message of a datagram signed for the session ``nonce``; :class:`BadTarget` when its tag does not match."""
    if len(data) <= TAG_SIZE:
        raise BadTarget("too short for a signed message")
    body, tag = data[:-TAG_SIZE], data[-TAG_SIZE:]
    if not hmac.compare_digest(hmac.digest(secret, nonce + body, hashlib.sha256), tag):
        raise BadTarget("its HMAC-SHA256 tag does not match the shared secret and this session's nonce")
    return body


def encode_hello(source: int = 0, binary: bool = True) -> bytes:
    """A source's request for the session nonce."""
    if binary:
        return _HELLO.pack(HELLO_MAGIC, VERSION, source & 0xFFFFFFFF)
    return json.dumps({"hello": True, "source": source}).encode()


def is_hello(data: bytes) -> bool | None:
    """True for a binary hello, False for a JSON one, None for anything else."""
    if len(data) == _HELLO.size and data[:4] == HELLO_MAGIC:
        return True
    if data[:1] == b"{" and b'"hello"' in data and len(data) < 256:
        try:
            obj = json.loads(data)
        except (UnicodeDecodeError, ValueError):
            return None
        if isinstance(obj, dict) and obj.get("hello") is True:
            return False
    return None


def encode_nonce(nonce: bytes, binary: bool = True) -> bytes:
    """The bridge's challenge: its session nonce (16 bytes)."""
    if binary:
        return _NONCE.pack(NONCE_MAGIC, VERSION, nonce)
    return json.dumps({"nonce": nonce.hex()}).encode()


def decode_nonce(data: bytes) -> bytes | None:
    """The session nonce of a challenge (binary or JSON), or None if ``data`` is not one."""
    if len(data) == _NONCE.size and data[:4] == NONCE_MAGIC:
        return _NONCE.unpack(data)[2]
    if data[:1] == b"{" and b'"nonce"' in data:
        try:
            obj = json.loads(data)
            nonce = bytes.fromhex(obj["nonce"])
        except (UnicodeDecodeError, ValueError, KeyError, TypeError):
            return None
        return nonce if len(nonce) == NONCE_SIZE else None
    return None


def encode_end(seq: int | None = None, source: int = 0) -> bytes:
    """The end message (``{"end": true}``, with the source's ``seq`` and id when it signs)."""
    obj: dict = {"end": True}
    if seq is not None:
        obj["seq"] = seq & 0xFFFFFFFF
    if source:
        obj["source"] = source
    return json.dumps(obj).encode()


def _finite(values, n: int, what: str, strict: bool = False) -> tuple[float, ...]:
    """``n`` finite floats; ``strict`` (JSON): only numbers — no strings, booleans or nested lists."""
    if strict and not (isinstance(values, list)
                       and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in values)):  # fmt: skip
        raise BadTarget(f"{what} must be a list of {n} numbers (not strings or booleans)")
    try:
        vals = tuple(float(x) for x in values)
    except (TypeError, ValueError, OverflowError):
        raise BadTarget(f"{what} must be {n} numbers") from None
    if len(vals) != n:
        raise BadTarget(f"{what} must be {n} numbers, got {len(vals)}")
    if not all(math.isfinite(x) for x in vals):
        raise BadTarget(f"{what} has a value that is not finite")
    return vals


def _check_pose(kind: int, vals: tuple[float, ...]) -> None:
    if kind == KIND_POSE and sum(x * x for x in vals[3:]) < 1e-12:
        raise BadTarget("the pose's quaternion has zero length")


def _uint32(obj: dict, key: str) -> int | None:
    x = obj.get(key)
    if x is not None and not (isinstance(x, int) and not isinstance(x, bool) and 0 <= x <= 0xFFFFFFFF):
        raise BadTarget(f'"{key}" must be an integer 0..2^32−1')
    return x


def decode_target(data: bytes) -> Target:
    """A target from a binary (magic b"LBRT") or JSON datagram; :class:`BadTarget` for anything else."""
    if data[:4] == TARGET_MAGIC:
        if len(data) != TARGET_SIZE:
            raise BadTarget(f"a version-1 target is {TARGET_SIZE} bytes, got {len(data)}")
        magic, version, kind, flags, seq, source, t, *rest = _TARGET.unpack(data)
        if version != VERSION:
            raise BadTarget(f"target version {version}, this bridge speaks {VERSION}")
        if kind not in KINDS:
            raise BadTarget(f"target kind {kind} is not known (1 joints, 2 pose with quaternion, 3 pose with angles)")
        what = "q" if kind == KIND_JOINT else "the pose"
        vals = _finite(rest[:7], 7, what)
        _check_pose(kind, vals)
        v = _finite(rest[7:], 7, "the feed-forward") if flags & FLAG_VELOCITY else None
        if not math.isfinite(t):
            raise BadTarget("the source time is not finite")
        return Target(vals, v, seq, t, kind, source)
    if data[:1] == b"{":
        try:
            obj = json.loads(data.decode("utf-8"))
        except (UnicodeDecodeError, ValueError):
            raise BadTarget("not valid JSON") from None
        if not isinstance(obj, dict):
            raise BadTarget("a JSON target is an object")
        for key, kind, n, vkey, vn in _JSON_KINDS:
            if key in obj:
                break
        else:
            raise BadTarget('a JSON target needs "q" (7 joint positions [rad]), "pose" or "pose_zyx"')
        vals = _finite(obj[key], n, f'"{key}"', strict=True) + ((0.0,) if n == 6 else ())
        _check_pose(kind, vals)
        v = None
        if obj.get(vkey) is not None:
            v = _finite(obj[vkey], vn, f'"{vkey}"', strict=True) + ((0.0,) if vn == 6 else ())
        seq = _uint32(obj, "seq")
        source = _uint32(obj, "source") or 0
        t = obj.get("t", 0.0)
        if not (isinstance(t, (int, float)) and not isinstance(t, bool) and math.isfinite(t)):
            raise BadTarget('"t" must be a finite number of seconds')
        t = float(t)
        return Target(vals, v, seq, t, kind, source, binary=False)
    raise BadTarget("neither a binary target (magic LBRT) nor a JSON object")


@dataclass(frozen=True)
class State:
    """The robot state the bridge sends back."""

    session_state: int
    braking: bool
    following: bool
    unreached: bool  # the last pose target was not reached (the closest configuration is followed)
    seq: int
    target_seq: int
    target_t: float  # [s] the last accepted target's source time
    t: float  # [s] controller time
    measured: tuple[float, ...]  # [rad]
    commanded: tuple[float, ...]  # [rad]
    external_torque: tuple[float, ...]  # [Nm]
    tcp: tuple[float, ...]  # commanded TCP: x, y, z [m], quaternion w, x, y, z


def encode_state(s: State) -> bytes:
    """The binary state datagram the bridge sends back to its source (little-endian; layout in the file-formats
    reference): session state, flags, counters, times [s], measured and commanded joints [rad], external torques
    [Nm], TCP [m, quaternion w x y z]."""
    flags = (1 if s.braking else 0) | (2 if s.following else 0) | (4 if s.unreached else 0)
    return _STATE.pack(STATE_MAGIC, VERSION, s.session_state, flags, s.seq & 0xFFFFFFFF, s.target_seq & 0xFFFFFFFF,
                       s.target_t, s.t, *s.measured, *s.commanded, *s.external_torque, *s.tcp)  # fmt: skip


STATE_NAMES = ("IDLE", "MONITORING_WAIT", "MONITORING_READY", "COMMANDING_WAIT", "COMMANDING_ACTIVE")


def encode_state_json(s: State) -> bytes:
    """The JSON state: the keys the MQTT telemetry (MQTT) and the execution log use for the same values
    (``state`` the session state's name, ``msr_q``, ``cmd_q`` [rad], ``ext_tau`` [Nm]), and the bridge's own
    (``state_id`` 0–4, ``braking``, ``following``, ``unreached``, ``seq``, ``target_seq``, ``target_t`` [s], ``t`` [s],
    ``tcp`` [m, quaternion w x y z])."""
    name = STATE_NAMES[s.session_state] if 0 <= s.session_state < len(STATE_NAMES) else str(s.session_state)
    return json.dumps({
        "state": name, "state_id": s.session_state, "braking": s.braking, "following": s.following,
        "unreached": s.unreached, "seq": s.seq, "target_seq": s.target_seq, "target_t": s.target_t, "t": s.t,
        "msr_q": list(s.measured), "cmd_q": list(s.commanded), "ext_tau": list(s.external_torque), "tcp": list(s.tcp),
    }).encode()  # fmt: skip


def decode_state(data: bytes) -> State:
    """A state from its binary (magic LBRS) or JSON form; ValueError for anything else."""
    if data[:1] == b"{":
        o = json.loads(data)
        return State(o["state_id"], o["braking"], o["following"], o["unreached"], o["seq"], o["target_seq"],
                     o["target_t"], o["t"], tuple(o["msr_q"]), tuple(o["cmd_q"]), tuple(o["ext_tau"]),
                     tuple(o["tcp"]))  # fmt: skip
    if data[:4] != STATE_MAGIC or len(data) != STATE_SIZE:
        raise ValueError("not a version-1 bridge state datagram")
    magic, version, st, flags, seq, tseq, tt, t, *rest = _STATE.unpack(data)
    return State(st, bool(flags & 1), bool(flags & 2), bool(flags & 4), seq, tseq, tt, t, tuple(rest[:7]),
                 tuple(rest[7:14]), tuple(rest[14:21]), tuple(rest[21:28]))  # fmt: skip


def claimed_source(data: bytes) -> int | None:
    """The source id a message that is not a valid target still carries (binary: its header; JSON: ``"source"``),
    or None: who sent it cannot be told."""
    if data[:4] == TARGET_MAGIC and len(data) >= 16:
        return struct.unpack_from("<I", data, 12)[0]
    if data[:1] == b"{":
        try:
            obj = json.loads(data)
        except (UnicodeDecodeError, ValueError, RecursionError):
            return None
        src = obj.get("source") if isinstance(obj, dict) else None
        return src if isinstance(src, int) and not isinstance(src, bool) else None
    return None
