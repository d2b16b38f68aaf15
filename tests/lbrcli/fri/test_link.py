"""The link to the controller (``lbrcli.fri.link.Link``) on its own: the period learnt from the first message outside
IDLE builds the executed motion and its supervision once; lost messages are counted, bridged by the motion's
extrapolation while the robot is commanded, and a gap longer than any controller bridges ends the link."""

from __future__ import annotations

from lbrcli.fri.testing import CA, IDLE, MR, Cycle, ScriptedController
from tests.helpers.fri_session import LIM, Q0

from lbrcli.fri.clock import SessionClock
from lbrcli.fri.codec import FriCodec
from lbrcli.fri.link import Link


def _message(seq: int, state: int, send_period: int = 1):
    """The scripted controller's monitoring message (decoded) with sequence counter ``seq``."""
    ctl = ScriptedController(0, [], Q0)
    ctl.sock.close()
    ctl.foreign_sock.close()
    return FriCodec("1.15").decode_monitoring(ctl._message(Cycle(state=state, send_period=send_period), seq, 0))


def _link(reply_gap_s: float | None = None) -> Link:
    return Link(SessionClock(60.0, 1.0, None), LIM, 100.0, 10.0, 5, None, reply_gap_s, None)


def test_the_period_builds_the_motion_and_its_supervision_once():
    link = _link()
    idle = _message(1, IDLE, send_period=2)
    link.received(idle, 0, False, False, 0.0)
    assert not link.learn_period(idle) and link.motion is None and link.clock.period_s is None
    ready = _message(2, MR, send_period=2)
    link.received(ready, 1, False, False, 0.002)
    assert link.learn_period(ready) and link.clock.period_s == 0.002 and link.motion.period_s == 0.002
    assert link.sup is not None and link.motion.prev == Q0
    assert not link.learn_period(_message(3, MR, send_period=2))  # once


def test_lost_messages_are_counted_bridged_while_commanded_and_a_long_gap_ends_the_link():
    link = _link(reply_gap_s=0.01)  # [s] 10 messages at 1 ms
    first = _message(1, CA)
    link.received(first, 0, False, False, 0.0)
    link.learn_period(first)
    assert link.received(_message(4, CA), 3, False, False, 0.003) == 0  # not commanded yet: nothing to bridge
    assert link.missed == 2 and link.extrapolated_cycles == 0
    link.motion.sent(Q0, CA)  # a command executed: the robot is commanded from here
    assert link.received(_message(7, CA), 3, False, True, 0.006) == 2  # two periods bridged by extrapolation
    assert link.missed == 4 and link.extrapolated_cycles == 2
    assert link.received(_message(19, CA), 12, False, True, 0.018) == -1  # 11 lost > 10: no command is safe
