"""The bridge's pose targets on the wire, the shared secret, and the inbox's owner rule over a scripted transport
(MQTT-like: no sender address, the source id in the target)."""

from __future__ import annotations

import json
import struct

import numpy as np
import pytest

from lbrcli.bridge import (
    KIND_POSE,
    KIND_POSE_ZYX,
    BadTarget,
    State,
    TargetInbox,
    decode_state,
    decode_target,
    encode_target,
    sign,
    verify,
)
from tests.helpers.cli import Q_START

KEY = b"0123456789abcdef-secret"


def test_pose_targets_round_trip_in_both_forms():
    pose = (0.5, -0.1, 0.6, 0.0, 1.0, 0.0, 0.0)
    data = encode_target(pose, (0.1, 0, 0, 0, 0, 0.2), seq=4, t=1.5, kind=KIND_POSE, source=77)
    assert len(data) == 136 and data[5] == KIND_POSE and struct.unpack_from("<I", data, 12) == (77,)
    t = decode_target(data)
    assert (t.kind, t.values, t.v, t.seq, t.source) == (KIND_POSE, pose, (0.1, 0, 0, 0, 0, 0.2, 0.0), 4, 77)
    zyx = decode_target(encode_target((0.5, 0, 0.6, 0.1, 0.2, 0.3), kind=KIND_POSE_ZYX))
    assert zyx.kind == KIND_POSE_ZYX and zyx.values == (0.5, 0, 0.6, 0.1, 0.2, 0.3, 0.0) and zyx.v is None
    j = decode_target(json.dumps({"pose_zyx": [0.5, 0, 0.6, 0.1, 0.2, 0.3], "twist": [0] * 6, "source": 3}).encode())
    assert j.kind == KIND_POSE_ZYX and j.source == 3 and j.v == (0.0,) * 7 and not j.binary
    j = decode_target(json.dumps({"pose": list(pose)}).encode())
    assert j.kind == KIND_POSE and j.values == pose


@pytest.mark.parametrize(
    "data, words",
    [
        (encode_target((0.5, 0, 0.6, 0, 0, 0, 0), kind=KIND_POSE), "zero length"),
        (b'{"pose": [0.5, 0, 0.6, 1, 0, 0]}', "7 numbers"),
        (b'{"pose_zyx": [0.5, 0, 0.6, 1, 0, 0], "twist": [0, 0, 0]}', "6 numbers"),
        (b'{"q": [0, 0, 0, 0, 0, 0, 0], "seq": -1}', "seq"),
        (b'{"q": [0, 0, 0, 0, 0, 0, 0], "source": "me"}', "source"),
        (encode_target([0] * 7)[:5] + bytes([9]) + encode_target([0] * 7)[6:], "kind 9"),
    ],
)
def test_bad_pose_targets_are_refused_with_a_reason(data, words):
    with pytest.raises(BadTarget, match=words):
        decode_target(data)


def test_signed_messages_verify_only_with_the_secret():
    msg = encode_target([0.1] * 7)
    assert verify(sign(msg, KEY), KEY) == msg
    for bad in (
        sign(msg, b"another-secret-of-16"),
        msg,
        sign(msg, KEY)[:-1] + bytes([sign(msg, KEY)[-1] ^ 1]),
        b"short",
    ):
        with pytest.raises(BadTarget):
            verify(bad, KEY)


class Scripted:
    """A transport that delivers what the test queues; like MQTT it cannot name the sender."""

    name = "scripted"

    def __init__(self, sender=None):
        self.queue, self.sent, self.sender = [], [], sender

    def receive(self):
        while self.queue:
            yield self.queue.pop(0), self.sender

    def admits(self, sender):
        return True

    def send(self, data, sender):
        self.sent.append(data)

    def describe(self, sender):
        return f"scripted {sender}"

    def close(self):
        pass


def _state():
    return State(4, False, True, False, 1, 0, 0.0, 0.0, (0,) * 7, (0,) * 7, (0,) * 7, (0,) * 7)


def test_the_first_source_id_owns_the_session_and_others_are_ignored():
    tr = Scripted()
    box = TargetInbox([tr])
    tr.queue += [encode_target([0.1] * 7, source=5, seq=1), encode_target([0.2] * 7, source=6, seq=2),
                 json.dumps({"end": True, "source": 6}).encode()]  # fmt: skip
    box.poll()
    assert box.latest.values == (0.1,) * 7 and box.accepted == 1 and box.foreign == 2 and not box.ended
    tr.queue += [json.dumps({"q": [0.3] * 7, "source": 5, "seq": 3}).encode()]
    box.poll()
    assert box.latest.values == (0.3,) * 7
    box.send(_state())  # a JSON source gets JSON back
    assert tr.sent[-1][:1] == b"{" and decode_state(tr.sent[-1]).following
    tr.queue += [json.dumps({"end": True, "source": 5}).encode()]
    box.poll()
    assert box.ended and box.error is None


def test_garbage_from_the_owner_stops_but_a_stranger_or_anonymous_garbage_does_not():
    tr = Scripted()  # MQTT-like: the sender is known only by the source id inside a message
    box = TargetInbox([tr])
    tr.queue += [encode_target([0.1] * 7, source=5), encode_target([np.nan] * 7, source=9), b"hello",
                 b'{"q": "nonsense"}']  # fmt: skip
    box.poll()
    assert box.error is None and box.bad == 3  # a stranger's NaN, garbage that names no source: ignored, counted
    tr.queue += [encode_target([0.2] * 7, source=5), encode_target([np.nan] * 7, source=5)]
    box.poll()
    assert box.error is not None and "not finite" in box.error  # the owner's invalid target
    udp = Scripted(sender=("10.0.0.2", 4000))
    other = Scripted(sender=("10.0.0.3", 4000))
    box = TargetInbox([udp, other])
    udp.queue.append(encode_target([0.1] * 7))
    other.queue.append(b"garbage")
    box.poll()
    assert box.error is None and box.bad == 1  # an address that is not the owner's: ignored
    udp.queue.append(b"garbage")
    box.poll()
    assert "garbage" not in box.error and "scripted ('10.0.0.2', 4000)" in box.error


def test_every_target_is_judged_on_arrival_even_when_a_valid_one_follows_in_the_same_cycle():
    from trajectories.limits import default_limits

    lim = default_limits()
    tr = Scripted(sender=("10.0.0.2", 4000))
    box = TargetInbox([tr], limits=lim)
    q = Q_START.tolist()
    beyond = list(q)
    beyond[3] = -lim.position[3] - 0.01
    tr.queue += [encode_target(q, seq=1), encode_target(beyond, seq=2), encode_target(q, seq=3)]
    box.poll()
    assert box.error is not None and "A4" in box.error and "position limits" in box.error


@pytest.mark.parametrize("q", [["0"] * 7, [True] * 7, [[0]] * 7, [0] * 6 + ["1e300"]])
def test_json_targets_take_numbers_only(q):
    with pytest.raises(BadTarget):
        decode_target(json.dumps({"q": q}).encode())


def test_with_a_secret_only_this_sessions_signatures_count_and_replays_are_stale():
    tr = Scripted()
    box = TargetInbox([tr], secret=KEY)
    other_session = b"\x01" * 16
    n = box.nonce
    assert len(n) == 16 and n != other_session
    tr.queue += [encode_target([0.9] * 7, seq=1), sign(encode_target([0.8] * 7, seq=2), b"wrong-secret-0000", n),
                 b"garbage", sign(encode_target([0.7] * 7, seq=9), KEY, other_session),  # recorded earlier
                 sign(encode_target([0.1] * 7, seq=3), KEY, n)]  # fmt: skip
    box.poll()
    assert box.unauthenticated == 4 and box.accepted == 1 and box.latest.values == (0.1,) * 7
    assert box.error is None  # an unauthenticated party cannot even stop the session
    tr.queue += [sign(encode_target([0.2] * 7, seq=3), KEY, n)]  # a replay of this session's counter
    box.poll()
    assert box.stale == 1 and box.latest.values == (0.1,) * 7
    # the end message is bound to the session and the counter too: an old one, or a replayed one, ends nothing
    tr.queue += [sign(json.dumps({"end": True, "seq": 10}).encode(), KEY, other_session),
                 sign(json.dumps({"end": True, "seq": 2}).encode(), KEY, n)]  # fmt: skip
    box.poll()
    assert not box.ended and box.unauthenticated == 5 and box.stale == 2
    tr.queue += [sign(json.dumps({"end": True, "seq": 4}).encode(), KEY, n)]
    box.poll()
    assert box.ended


def test_a_hello_gets_the_session_nonce_back_in_its_form():
    from lbrcli.bridge.protocol import decode_nonce, encode_hello

    tr = Scripted(sender=("10.0.0.2", 4000))
    box = TargetInbox([tr], secret=KEY)
    tr.queue += [encode_hello(3), encode_hello(3, binary=False)]
    box.poll()
    assert [decode_nonce(m) for m in tr.sent] == [box.nonce, box.nonce]
    assert tr.sent[0][:4] == b"LBRN" and tr.sent[1][:1] == b"{" and box.hellos == 2 and box.owner is None
