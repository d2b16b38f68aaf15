"""The choice among swing-up variants of the cup-and-ball plan (the plan itself: tests/lbrcli/commands/test_plan_catch.py
and benchmarks/bench_catch.py)."""

import math
from types import SimpleNamespace

from planners.catch_plan import FLIGHT_ALLOWANCE, QUICK_TIME, SWING_HORIZONS, _rank, swing_variants


def test_both_release_kinds_are_tried_and_without_max_time_both_horizons():
    quick = swing_variants(3.0)
    assert {v.cruise for v in quick} == {True, False}
    rest, cruise = (next(v for v in quick if v.cruise == c) for c in (False, True))
    assert (rest.horizon, rest.slack) == (4.0, 0.0)
    # the cruising search with its release deadline a quarter second later (a plan that then enters the cup after
    # max_time is not valid: _rank below)
    assert (cruise.horizon, cruise.slack) == (4.25, 0.25)
    default = swing_variants(None)
    assert {v.cruise for v in default} == {True, False}
    assert {v.horizon for v in default if not v.cruise} == set(SWING_HORIZONS)  # the rest release as before, 6 s too
    assert all(v.deadline(None) == math.inf for v in default if not v.cruise)  # as soon as the band allows
    # the cruising release searched as for a plan within QUICK_TIME, with the same slack as with --max-time
    (quick,) = (v for v in default if v.cruise)
    assert quick.deadline(None) == cruise.deadline(QUICK_TIME) == QUICK_TIME - FLIGHT_ALLOWANCE + 0.25
    assert quick.horizon == cruise.horizon and "as for 3 s" in quick.describe()
    assert rest.deadline(3.0) == 3.0 - FLIGHT_ALLOWANCE  # with --max-time: the time asked, less the flight


def _result(caught, ok, success, t_entry, max_time=None):
    nominal = SimpleNamespace(caught=caught, t_entry=t_entry)
    return SimpleNamespace(
        nominal=nominal,
        request=SimpleNamespace(max_time=max_time),
        check=SimpleNamespace(ok=ok),
        band=SimpleNamespace(success=success),
    )


def test_the_plan_kept_is_valid_first_then_catches_more_of_the_band_then_sooner():
    valid_low = _result(True, True, 0.7, 3.0)
    invalid_high = _result(False, True, 0.9, None)  # the nominal ball missed
    over_limits = _result(True, False, 1.0, 2.0)
    late = _result(True, True, 1.0, 3.5, max_time=3.0)
    assert _rank(valid_low) > max(_rank(invalid_high), _rank(over_limits), _rank(late))
    assert _rank(_result(True, True, 0.9, 5.0)) > _rank(valid_low)
    assert _rank(_result(True, True, 0.9, 2.0)) > _rank(_result(True, True, 0.9, 5.0))
