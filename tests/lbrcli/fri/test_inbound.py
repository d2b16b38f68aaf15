"""The monitoring side of a session (``lbrcli.fri.inbound.Inbound``) on its own: the wire format detected from the
first datagram, sequence steps, stale and repeated messages dropped, undecodable and inconsistent ones counted and
never accepted, and the busy-wait's warming restoring the last accepted message."""

from __future__ import annotations

import math

import pytest
from lbrcli.fri.testing import CA, MR, Cycle, ScriptedController
from tests.helpers.fri_session import LIM, Q0

from lbrcli.fri.inbound import Inbound
from lbrcli.fri.messages import FriVersion


def _datagram(version: str, seq: int, state: int = MR, **kw) -> bytes:
    """The scripted controller's monitoring datagram with sequence counter ``seq``."""
    ctl = ScriptedController(0, [], Q0, version=version)
    ctl.sock.close()
    ctl.foreign_sock.close()
    return ctl._message(Cycle(state=state, **kw), seq, 0)


def _far(m) -> None:  # a measured A1 no robot reports (beyond its position limit)
    m.monitorData.measuredJointPosition.value[0] = 10.0


@pytest.mark.parametrize("version", ["1.15", "2.7"])
def test_steps_stale_and_inconsistent_messages(version):
    inbound = Inbound(None, LIM.position)
    assert not inbound.open(b"\x00garbage") and inbound.malformed == 1 and inbound.codec is None
    first = _datagram(version, 7)
    assert inbound.open(first) and inbound.version is FriVersion(version)
    assert inbound.decode(first) == 0 and inbound.last_seq == 7 and inbound.last_data == first
    assert inbound.state.session_state == MR and inbound.state.measured_joint_position == pytest.approx(Q0)
    assert inbound.decode(_datagram(version, 10, CA)) == 3  # two messages lost on the way
    assert inbound.decode(_datagram(version, 10, CA)) == -1 and inbound.stale == 1  # repeated
    assert inbound.decode(_datagram(version, 9, CA)) == -1 and inbound.stale == 2  # older
    far = _datagram(version, 11, CA, mutate=_far)
    assert inbound.decode(far) == -1 and inbound.malformed == 2 and inbound.last_seq == 10
    assert inbound.decode(b"\x01\x02\x03") == -1 and inbound.malformed == 3
    nxt = _datagram(version, 11, CA)
    assert inbound.decode(nxt) == 1 and inbound.last_data == nxt and (inbound.stale, inbound.malformed) == (2, 3)


def test_the_counter_wraps_and_a_given_version_is_kept():
    inbound = Inbound(FriVersion("1.15"), LIM.position)
    last = 0xFFFFFFFF
    assert inbound.open(_datagram("2.7", last)) and inbound.version is FriVersion("1.15")  # given, not detected
    assert inbound.decode(_datagram("1.15", last)) == 0
    assert inbound.decode(_datagram("1.15", 1)) == 2  # 0xFFFFFFFF → 0 → 1: one message lost across the wrap


def test_warming_restores_the_last_accepted_message():
    inbound = Inbound(None, LIM.position)
    good = _datagram("1.15", 1, CA)
    inbound.open(good)
    inbound.decode(good)
    inbound.decode(_datagram("1.15", 2, CA, mutate=_far))  # refused, but decoded into the one message
    assert inbound.mon.monitorData.measuredJointPosition.value[0] == 10.0
    inbound.warm((1, 1))
    assert inbound.mon.SerializeToString() == inbound.codec.decode_monitoring(good).SerializeToString()
    assert math.isclose(inbound.state.measured_joint_position[0], Q0[0])
