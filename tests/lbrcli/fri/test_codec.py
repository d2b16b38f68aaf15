"""FRI wire format: round trips of every field, KUKA's unpacked and the packed repeated doubles, 2.7 framing,
and rejection of everything that is not a valid datagram of the expected version and type."""

from __future__ import annotations

import struct
import zlib

import pytest
from google.protobuf import descriptor_pb2
from google.protobuf.descriptor import FieldDescriptor

from lbrcli.fri.codec import FriCodec
from lbrcli.fri.constants import COMMAND_MESSAGE_ID, MAX_DATAGRAM, MONITORING_MESSAGE_ID
from lbrcli.fri.messages import FriVersion
from trajectories.errors import FriDecodeError, FriForeignMessage

VERSIONS = ("1.15", "2.7")
Q = [0.1, -0.25, 0.5, -1.3523, 0.75, 0.1301, -2.9]  # [rad]


def _varint(n: int) -> bytes:
    out = bytearray()
    while True:
        b = n & 0x7F
        n >>= 7
        out.append(b | (0x80 if n else 0))
        if not n:
            return bytes(out)


def _tag(field: int, wire: int) -> bytes:
    return _varint(field << 3 | wire)


def _len_field(field: int, payload: bytes) -> bytes:
    return _tag(field, 2) + _varint(len(payload)) + payload


def _fill(msg, seed: int = 1) -> None:
    """Set every field of ``msg`` (recursively) to a distinct non-default value; repeated fields get 7 / 2 items."""
    counter = [seed]

    def nxt() -> int:
        counter[0] += 1
        return counter[0]

    for f in msg.DESCRIPTOR.fields:
        repeated = f.is_repeated
        if f.type == FieldDescriptor.TYPE_MESSAGE:
            if repeated:
                for _ in range(2):
                    _fill(getattr(msg, f.name).add(), nxt())
            else:
                _fill(getattr(msg, f.name), nxt())
            continue
        if f.type == FieldDescriptor.TYPE_ENUM:
            values = [v.number for v in f.enum_type.values]
            make = lambda: values[nxt() % len(values)]  # noqa: E731
        elif f.type == FieldDescriptor.TYPE_DOUBLE:
            make = lambda: nxt() * 0.125 - 3.0  # noqa: E731
        elif f.type == FieldDescriptor.TYPE_STRING:
            make = lambda: f"name{nxt()}"  # noqa: E731
        else:  # integer types
            make = nxt
        if repeated:
            getattr(msg, f.name).extend([make() for _ in range(7)])
        else:
            setattr(msg, f.name, make())


def _all_fields_set(msg) -> bool:
    """True if every field of the message tree is present."""
    for f in msg.DESCRIPTOR.fields:
        if f.is_repeated:
            items = getattr(msg, f.name)
            if len(items) == 0:
                return False
            if f.type == FieldDescriptor.TYPE_MESSAGE and not all(_all_fields_set(m) for m in items):
                return False
        elif not msg.HasField(f.name):
            return False
        elif f.type == FieldDescriptor.TYPE_MESSAGE and not _all_fields_set(getattr(msg, f.name)):
            return False
    return True


def _full(codec: FriCodec, kind: str):
    msg = codec.new_monitoring() if kind == "monitoring" else codec.new_command()
    _fill(msg)
    msg.header.messageIdentifier = MONITORING_MESSAGE_ID if kind == "monitoring" else COMMAND_MESSAGE_ID
    return msg


def _monitoring(codec: FriCodec, seq: int = 41, state: int = 4):
    m = codec.new_monitoring()
    m.header.messageIdentifier = MONITORING_MESSAGE_ID
    m.header.sequenceCounter = seq
    m.header.reflectedSequenceCounter = 17
    m.connectionInfo.sessionState = state
    m.connectionInfo.quality = 3
    m.connectionInfo.sendPeriod = 2
    m.connectionInfo.receiveMultiplier = 1
    m.robotInfo.numberOfJoints = 7
    m.robotInfo.driveState.extend([2] * 7)
    m.monitorData.measuredJointPosition.value.extend(Q)
    m.monitorData.measuredTorque.value.extend([1.5, -20.0, 0.25, 12.0, 0.0, -0.5, 0.01])
    m.monitorData.timestamp.sec = 1_700_000_000
    m.monitorData.timestamp.nanosec = 123_456_789
    io = m.monitorData.readIORequest.add()
    io.name, io.type, io.direction, io.analogValue = "ball_theta", 2, 0, 0.0625
    m.ipoData.jointPosition.value.extend(Q)
    m.ipoData.trackingPerformance = 0.75
    return m


def _command(codec: FriCodec, seq: int = 5, reflected: int = 41):
    c = codec.new_command()
    c.header.messageIdentifier = COMMAND_MESSAGE_ID
    c.header.sequenceCounter = seq
    c.header.reflectedSequenceCounter = reflected
    c.commandData.jointPosition.value.extend(Q)
    return c


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("kind", ["monitoring", "command"])
def test_round_trip_with_every_field(version, kind):
    codec = FriCodec(version)
    msg = _full(codec, kind)
    assert _all_fields_set(msg)
    data = codec.encode(msg)
    assert len(data) <= MAX_DATAGRAM
    decode = codec.decode_monitoring if kind == "monitoring" else codec.decode_command
    back = decode(data)
    assert back == msg
    assert _all_fields_set(back)
    # a second decode into the same object gives the same message (no leftovers, no allocation needed)
    again = decode(data, into=back)
    assert again is back and again == msg


@pytest.mark.parametrize("version", VERSIONS)
def test_decoded_monitoring_fields(version):
    codec = FriCodec(version)
    m = codec.decode_monitoring(codec.encode(_monitoring(codec)))
    assert m.header.messageIdentifier == 0x245142
    assert (m.header.sequenceCounter, m.header.reflectedSequenceCounter) == (41, 17)
    assert (m.connectionInfo.sessionState, m.connectionInfo.quality) == (4, 3)
    assert (m.connectionInfo.sendPeriod, m.connectionInfo.receiveMultiplier) == (2, 1)
    assert list(m.robotInfo.driveState) == [2] * 7
    assert list(m.monitorData.measuredJointPosition.value) == Q
    assert m.monitorData.measuredTorque.value[1] == -20.0
    assert (m.monitorData.timestamp.sec, m.monitorData.timestamp.nanosec) == (1_700_000_000, 123_456_789)
    io = m.monitorData.readIORequest[0]
    assert (io.name, io.type, io.analogValue) == ("ball_theta", 2, 0.0625)
    assert list(m.ipoData.jointPosition.value) == Q
    assert m.ipoData.trackingPerformance == 0.75


@pytest.mark.parametrize("version", VERSIONS)
def test_decode_into_reused_message_clears_old_fields(version):
    codec = FriCodec(version)
    into = codec.decode_command(codec.encode(_command(codec)))
    bare = codec.new_command()
    bare.header.messageIdentifier, bare.header.sequenceCounter, bare.header.reflectedSequenceCounter = (
        COMMAND_MESSAGE_ID,
        6,
        42,
    )
    out = codec.decode_command(codec.encode(bare), into=into)
    assert out is into
    assert not out.HasField("commandData")
    assert out.header.sequenceCounter == 6


@pytest.mark.parametrize("version", VERSIONS)
def test_repeated_doubles_are_written_unpacked_like_kuka(version):
    codec = FriCodec(version)
    payload = codec.unframe(codec.encode(_command(codec)))
    unpacked = b"".join(b"\x09" + struct.pack("<d", v) for v in Q)  # tag (field 1, fixed64) before every double
    packed = b"\x0a" + _varint(56) + struct.pack("<7d", *Q)
    assert unpacked in payload
    assert packed not in payload
    # the command's jointPosition is exactly commandData{ jointPosition{ value × 7 unpacked } }
    assert _len_field(2, _len_field(1, unpacked)) in payload


@pytest.mark.parametrize("version", VERSIONS)
def test_packed_and_unpacked_encodings_decode_to_the_same_values(version):
    codec = FriCodec(version)
    header = _len_field(
        1, _tag(1, 0) + _varint(COMMAND_MESSAGE_ID) + _tag(2, 0) + _varint(9) + _tag(3, 0) + _varint(300)
    )
    unpacked = b"".join(b"\x09" + struct.pack("<d", v) for v in Q)
    packed = _len_field(1, struct.pack("<7d", *Q))  # field 1, wire type 2, 56 bytes of doubles
    datagrams = [codec.frame(header + _len_field(2, _len_field(1, body))) for body in (unpacked, packed)]
    a, b = (codec.decode_command(d) for d in datagrams)
    assert list(a.commandData.jointPosition.value) == Q
    assert list(b.commandData.jointPosition.value) == Q
    assert (b.header.sequenceCounter, b.header.reflectedSequenceCounter) == (9, 300)
    # a monitoring message with packed positions, torques and drive states
    m = codec.decode_monitoring(codec.frame(_packed_monitoring_payload()))
    assert list(m.monitorData.measuredJointPosition.value) == Q
    assert list(m.monitorData.externalTorque.value) == Q
    assert list(m.robotInfo.driveState) == [2] * 7
    assert (m.connectionInfo.sessionState, m.connectionInfo.quality) == (2, 3)


def _packed_monitoring_payload() -> bytes:
    """A monitoring payload written by hand with packed repeated doubles and packed drive states."""
    header = _len_field(
        1, _tag(1, 0) + _varint(MONITORING_MESSAGE_ID) + _tag(2, 0) + _varint(41) + _tag(3, 0) + _varint(17)
    )
    robot = _len_field(2, _tag(1, 0) + _varint(7) + _len_field(5, b"\x02" * 7))
    joints = _len_field(1, struct.pack("<7d", *Q))  # JointValues{value packed}
    monitor = _len_field(3, _len_field(1, joints) + _len_field(5, joints))
    conn = _len_field(4, _tag(1, 0) + _varint(2) + _tag(2, 0) + _varint(3))
    return header + robot + monitor + conn


def test_framing_27_is_length_payload_crc():
    codec = FriCodec("2.7")
    msg = _monitoring(codec)
    data = codec.encode(msg)
    payload = msg.SerializeToString()
    (length,) = struct.unpack_from("<I", data, 0)
    (crc,) = struct.unpack_from("<I", data, len(data) - 4)
    assert length == len(payload) == len(data) - 8
    assert data[4:-4] == payload
    assert crc == zlib.crc32(payload)
    assert FriCodec("1.15").encode(_monitoring(FriCodec("1.15"))) == _monitoring(FriCodec("1.15")).SerializeToString()


def _bad_27_datagrams() -> dict[str, bytes]:
    codec = FriCodec("2.7")
    good = codec.encode(_command(codec))
    wrong_crc = good[:-4] + struct.pack("<I", (zlib.crc32(good[4:-4]) + 1) & 0xFFFFFFFF)
    flipped = bytearray(good)
    flipped[10] ^= 0x10
    return {
        "wrong CRC": wrong_crc,
        "flipped payload byte": bytes(flipped),
        "length too large": struct.pack("<I", len(good) - 7) + good[4:],
        "length too small": struct.pack("<I", len(good) - 9) + good[4:],
        "truncated": good[:-1],
        "truncated to 5 bytes": good[:5],
        "empty": b"",
        "garbage": bytes(range(200, 256)) * 3,
        "oversized": good + b"\x00" * MAX_DATAGRAM,
    }


@pytest.mark.parametrize("name", list(_bad_27_datagrams()))
def test_bad_27_framing_raises(name):
    with pytest.raises(FriDecodeError):
        FriCodec("2.7").decode_command(_bad_27_datagrams()[name])


@pytest.mark.parametrize("kind", ["monitoring", "command"])
def test_version_mismatch_raises_both_ways(kind):
    c115, c27 = FriCodec("1.15"), FriCodec("2.7")
    for seq in (0, 1, 200, 70000):
        m115 = _monitoring(c115, seq) if kind == "monitoring" else _command(c115, seq)
        m27 = _monitoring(c27, seq) if kind == "monitoring" else _command(c27, seq)
        dec115 = c115.decode_monitoring if kind == "monitoring" else c115.decode_command
        dec27 = c27.decode_monitoring if kind == "monitoring" else c27.decode_command
        with pytest.raises(FriDecodeError):
            dec27(c115.encode(m115))
        with pytest.raises(FriDecodeError):
            dec115(c27.encode(m27))


@pytest.mark.parametrize("version", VERSIONS)
def test_foreign_identifier_raises(version):
    codec = FriCodec(version)
    mon = codec.encode(_monitoring(codec))
    cmd = codec.encode(_command(codec))
    with pytest.raises(FriForeignMessage, match="0x245142"):
        codec.decode_command(mon)  # a monitoring message where a command is expected
    with pytest.raises(FriForeignMessage):
        codec.decode_monitoring(cmd)
    other = _command(codec)
    other.header.messageIdentifier = 0x1234
    with pytest.raises(FriDecodeError, match="0x1234"):
        codec.decode_command(codec.encode(other))
    assert issubclass(FriForeignMessage, FriDecodeError)


@pytest.mark.parametrize("version", VERSIONS)
def test_garbage_and_incomplete_messages_raise(version):
    codec = FriCodec(version)
    partial = codec.new_command()
    partial.header.messageIdentifier = COMMAND_MESSAGE_ID  # sequence counters (required) missing
    no_header = codec.new_command()
    no_header.commandData.jointPosition.value.extend(Q)
    cases = [
        codec.frame(b"\xff\xff\xff\xff"),
        codec.frame(b"\x00" + bytes(20)),
        codec.frame(partial.SerializePartialToString()),
        codec.frame(no_header.SerializePartialToString()),
        codec.frame(codec.unframe(codec.encode(_command(codec)))[:7]),
    ]
    for data in cases:
        with pytest.raises(FriDecodeError):
            codec.decode_command(data)


def test_messages_of_both_versions_differ_as_documented():
    m115 = FriCodec("1.15").new_monitoring().monitorData.DESCRIPTOR.fields_by_name
    m27 = FriCodec("2.7").new_monitoring().monitorData.DESCRIPTOR.fields_by_name
    assert "commandedJointPosition" in m115 and "commandedJointPosition" not in m27
    assert "externalForce" in m27 and "measuredCartesianPose" in m27
    assert "endOfMessageData" in FriCodec("1.15").new_command().DESCRIPTOR.fields_by_name
    assert "endOfMessageData" not in FriCodec("2.7").new_command().DESCRIPTOR.fields_by_name


@pytest.mark.parametrize("version", list(FriVersion))
def test_descriptor_sets_match_the_proto_sources(version):
    pytest.importorskip("grpc_tools")
    from importlib import resources

    from lbrcli.fri.generate import compile_descriptor

    shipped = descriptor_pb2.FileDescriptorSet.FromString(
        resources.files("lbrcli.fri").joinpath(version.stem + ".desc").read_bytes()
    )
    compiled = descriptor_pb2.FileDescriptorSet.FromString(compile_descriptor(version.stem))
    assert compiled == shipped, f"{version.stem}.desc is stale: run python -m lbrcli.fri.generate"
