"""The CLI's FRI session defaults (``lbrcli.fri_runner``)."""

from __future__ import annotations

from lbrcli.fri_runner import default_busy_wait_s


def test_the_busy_wait_polls_a_whole_1ms_period_only_where_that_is_safe():
    assert default_busy_wait_s(embedded=True, realtime=False) == 0.0  # the simulator in-process shares the cores
    assert default_busy_wait_s(embedded=True, realtime=True) == 0.0
    assert default_busy_wait_s(embedded=False, realtime=False) >= 0.9e-3  # a robot: never sleep at 1 ms
    # SCHED_FIFO: the loop must sleep well over 5 % of each period, or the kernel's real-time throttling
    # (sched_rt_runtime_us = 95 %) stops it for 50 ms a second
    assert 0.0 < default_busy_wait_s(embedded=False, realtime=True) <= 0.5e-3
