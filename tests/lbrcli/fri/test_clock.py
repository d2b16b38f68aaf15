"""The session clock's silence rule: the controller is silent when no message came for ``silence_timeout_s`` while we
were waiting — time this process spent in its own cycle (a long callback, a stall on a busy PC) is not its silence."""

from __future__ import annotations

from lbrcli.fri.clock import SessionClock


def _clock(t_message: float = 100.0) -> SessionClock:
    c = SessionClock(first_message_timeout_s=10.0, silence_timeout_s=1.0, duration_s=None)
    c.received(t_message, 0, 1)
    return c


def test_a_stall_in_our_own_cycle_is_not_the_controllers_silence():
    c = _clock()
    c.quiet_from = 101.5  # our cycle took 1.5 s; the first wait after it began here and found nothing
    assert c.expired(101.6, False) is None
    what, seconds = c.expired(102.6, False)
    assert what == "silent" and abs(seconds - 1.1) < 1e-9


def test_silence_counts_from_the_last_message_when_we_were_waiting():
    c = _clock()
    c.quiet_from = 100.001
    assert c.expired(100.9, False) is None
    assert c.expired(101.1, False)[0] == "silent"


def test_without_a_wait_the_last_message_counts_and_a_message_ends_the_wait():
    c = _clock()
    assert c.expired(101.2, False)[0] == "silent"  # e.g. garbage kept arriving: no empty wait, still silent
    c.quiet_from = 101.5
    c.received(101.6, 1, 1)
    assert c.quiet_from is None and c.expired(102.5, False) is None
