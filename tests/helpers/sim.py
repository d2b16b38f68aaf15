"""The simulator tests' settings (lenient for a loaded machine) and the session's expected state sequence."""

from __future__ import annotations

from lbrcli.fri.testing import CA, CW, IDLE, MR, MW


TEST_DEFAULTS = dict(
    period_ms=4,
    commanding_after_s=0.05,
    quality_window=25,
    quality_good=0.5,
    quality_fair=0.3,
    quality_excellent=0.9,
    max_runtime_s=8.0,
    end_delay_s=0.05,  # lenient: the test machine may be loaded
)


def assert_sequence(states: list[int]) -> None:
    """MONITORING_WAIT first, then READY → COMMANDING_WAIT → COMMANDING_ACTIVE once, IDLE last."""
    assert states[0] == MW and states[-1] == IDLE
    i = states.index(CA)
    assert states[i - 1] == CW and states[i - 2] == MR
    assert states.count(CA) == 1 and states.count(CW) == 1
    assert set(states[: i - 1]) <= {MW, MR}
