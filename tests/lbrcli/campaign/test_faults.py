"""The fault campaign (lbrcli.campaign): every CSV-player case and a sample of every other surface ends as expected,
no command beyond the velocity, acceleration or jerk limit relative to what the robot executed (the jerk of a user's
own client apart), every stop the client
initiates a braking stop (efforts ramped out), no traceback, every log readable by the project's reader. The whole
campaign (≥ 250 cases) is `benchmarks/bench_faults.py`."""

from __future__ import annotations

import pytest

from lbrcli.campaign import execute_cases
from lbrcli.campaign.surfaces import all_surfaces, surface_cases
from lbrcli.fri.testing.campaign import run_case

EXECUTE = execute_cases()
# a sample of the other surfaces (the benchmark runs them all)
PICK = {
    "ptp: 5 % of messages lost",
    "ptp: SIGTERM",
    "serve: NaN target",
    "serve: the source dies mid-motion",
    "serve: replayed old targets",
    "serve: 2 replies lost",
    "damp: sensor reads 0 (the ball hangs still for it)",
    "upright: encoder reversed sign",
    "upright: loss 30",
    "torque: SIGTERM",
    "torque: torque beyond its bound",
    "wrench: loss 5",
    "user: returns NaN",
    "user: sine 0.5 rad at 3 Hz (5× the velocity limit)",
    "user: timestamps frozen",
}
OTHERS = [c for s in all_surfaces() for c in surface_cases(s) if c.name in PICK]


@pytest.mark.heavy
def test_the_campaign_is_wide():
    from lbrcli.campaign import all_cases

    cases = all_cases()
    assert len(cases) >= 250 and len({c.name for c in cases}) == len(cases)
    assert len({c.surface for c in cases}) >= 8 and len({c.category for c in cases}) >= 15


@pytest.mark.heavy
@pytest.mark.parametrize("case", EXECUTE + OTHERS, ids=[c.name for c in EXECUTE + OTHERS])
def test_case(case, tmp_path):
    r = run_case(case, tmp_path)
    assert r.traceback is None, r.traceback
    assert r.expected, f"{r.outcome} / {r.reason}: {r.detail}"
    assert r.velocity_ratio <= 1.0 + 1e-9, r
    assert r.acceleration_ratio <= 1.0 + 1e-9, r
    assert r.jerk_ratio <= 1.0 + 1e-6 or not case.jerk_judged, r
    assert r.within_limits, r
    assert not r.non_braking_stop, r
    assert r.log_readable, r
