"""The FRI fault campaign (fault_campaign.py): every case ends as expected, no command beyond the velocity or the
acceleration limit relative to what the robot executed, no traceback, every log readable by the project's reader."""

from __future__ import annotations

import pytest
from fault_campaign import cases, run_case

CASES = cases()


def test_the_campaign_is_wide():
    assert len(CASES) >= 60
    assert len({c.name for c in CASES}) == len(CASES)
    assert len({c.category for c in CASES}) >= 15


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_case(case, tmp_path):
    r = run_case(case, tmp_path)
    assert r.traceback is None, r.traceback
    assert r.expected, f"{r.outcome} / {r.reason}: {r.detail}"
    assert r.step_ratio <= 1.0 + 1e-9, r
    assert r.second_ratio <= 1.0 + 1e-9, r
    assert r.log_readable, r
