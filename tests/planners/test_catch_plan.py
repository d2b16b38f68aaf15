"""The choice among swing-up variants of the cup-and-ball plan (the plan itself: tests/lbrcli/commands/test_plan_catch.py
and benchmarks/bench_catch.py)."""

import math
from types import SimpleNamespace

import planners.catch_plan as cp
from planners.catch_plan import (
    FALLBACK_HORIZONS,
    FLIGHT_ALLOWANCE,
    QUICK_GRID,
    QUICK_TIME,
    REFINED,
    SWING_HORIZONS,
    QUICK_FALLBACK,
    _rank,
    _refined,
    stages,
    fallback_variants,
    swing_variants,
)


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
        request=SimpleNamespace(max_time=max_time, min_success=0.95),
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


def test_without_a_max_time_a_plan_that_meets_the_goals_comes_before_a_slower_one_that_catches_more():
    quick = _result(True, True, 0.96, QUICK_TIME - 0.5)  # within QUICK_TIME and enough of the band
    slow = _result(True, True, 1.0, QUICK_TIME + 1.5)
    assert _rank(quick) > _rank(slow)
    assert _rank(_result(True, True, 0.94, 1.5)) < _rank(slow)  # too little of the band: the share decides
    assert _rank(_result(True, True, 0.99, 1.5)) > _rank(quick)  # among quick plans the share still decides
    assert _rank(_result(False, True, 1.0, 1.5)) < _rank(slow)  # the nominal ball missed: not valid, not quick
    # with a max_time the time asked is the deadline and the share decides, as before
    assert _rank(_result(True, True, 0.96, 1.5, 3.0)) < _rank(_result(True, True, 1.0, 2.5, 3.0))


def _cand(grid: float):
    return SimpleNamespace(variant=None, grid=grid)


def test_without_a_max_time_the_quick_variants_come_first_one_at_a_time_then_the_rest_release():
    (first, k1), (second, k2), (main, k3), *fallbacks = stages(None)
    assert (k1, k2, k3) == ("quick", "quick", "main") and all(k == "fallback" for _, k in fallbacks)
    (a,), (b,) = first, second
    assert a.cruise and b == QUICK_FALLBACK and a.quick == b.quick == QUICK_TIME and (a.slack, b.slack) == (0.25, 0.0)
    assert not any(v.cruise for v in main) and {v.horizon for v in main} == set(SWING_HORIZONS)
    assert [v.horizon for (v,), _ in fallbacks] == list(FALLBACK_HORIZONS)
    # with a max_time: both release kinds together, then the fallback
    (together, kind), *rest = stages(3.0)
    assert kind == "main" and {v.cruise for v in together} == {True, False} and [k for _, k in rest] == ["fallback"]


def test_a_quick_variant_is_refined_unless_its_grid_is_poor_the_others_the_best_by_grid_unless_poor_after_the_first():
    good, poor = _cand(0.73), _cand(QUICK_GRID - 0.1)  # 0.3 m: a grid of 0.73 refined to 95 % of the band
    assert _refined("quick", [good]) == [good] and _refined("quick", [poor]) == []
    by_grid = [_cand(1.09), _cand(1.06), _cand(0.98)]
    assert _refined("main", by_grid) == by_grid[:REFINED] == _refined("fallback", by_grid)
    # a poor grid after the stage's best is not refined (0.35 m with --max-time 3: 0.27, and none of the band),
    # the best is, however poor (a plan, if one that falls short, says what failed)
    low = [_cand(0.37), _cand(0.27)]
    assert _refined("main", low) == low[:1] and _refined("fallback", [poor]) == [poor]


def _planned(success: float, min_success: float = 0.95, t_entry: float = 5.0):
    res = _result(True, True, success, t_entry)
    res.notes = ()
    res.failure = lambda: None if success >= min_success else f"catches {100 * success:.0f} % of the band"
    return res


def _fake_planner(monkeypatch, success_by_horizon: dict) -> list:
    """plan_catch with its swing-ups and verdicts replaced: each variant's plan catches success_by_horizon[horizon]
    of the band. Returns the horizons planned, in order."""
    planned: list = []

    def candidates(r, arm, notes, variants):
        return [SimpleNamespace(variant=v, grid=1.0) for v in variants]

    def plan_variant(r, arm, c, progress):
        planned.append(c.variant.horizon)
        v = c.variant
        got = success_by_horizon[v] if v in success_by_horizon else success_by_horizon[v.horizon]
        return _planned(*got) if isinstance(got, tuple) else _planned(got)

    monkeypatch.setattr(cp, "_arm", lambda r, robot, limits: None)
    monkeypatch.setattr(cp, "_candidates", candidates)
    monkeypatch.setattr(cp, "_plan_variant", plan_variant)
    monkeypatch.setattr(cp, "replace", lambda res, **kw: res)
    return planned


def test_with_a_max_time_the_fallback_is_the_cruising_release_without_the_deadlines_slack(monkeypatch):
    (fb,) = fallback_variants(3.0)  # with a max_time: longer pumping is too late
    cruise, rest = swing_variants(3.0)
    assert fb.cruise and cruise.cruise and fb.deadline(3.0) < cruise.deadline(3.0) and fb not in (cruise, rest)
    r = SimpleNamespace(max_time=3.0)
    planned = _fake_planner(monkeypatch, {cruise: 0.75, rest: 0.96, fb: 0.99})
    assert cp.plan_catch(r, None, None).band.success == 0.96 and len(planned) == 2  # no failure: no fallback
    planned = _fake_planner(monkeypatch, {cruise: 0.75, rest: 0.86, fb: 0.99})
    assert cp.plan_catch(r, None, None).band.success == 0.99 and len(planned) == 3
    _fake_planner(monkeypatch, {cruise: 0.75, rest: 0.86, fb: 0.4})
    assert cp.plan_catch(r, None, None).band.success == 0.86  # (the better one is kept either way)


def test_the_fallback_swing_ups_are_planned_one_at_a_time_only_while_no_plan_catches_enough(monkeypatch):
    fbs = fallback_variants(None)
    assert [fb.horizon for fb in fbs] == list(FALLBACK_HORIZONS) and not any(fb.cruise for fb in fbs)
    assert len(FALLBACK_HORIZONS) >= 2 and set(FALLBACK_HORIZONS).isdisjoint(SWING_HORIZONS)  # other searches
    first, second, last = FALLBACK_HORIZONS[0], FALLBACK_HORIZONS[1], FALLBACK_HORIZONS[-1]
    short, long = SWING_HORIZONS
    cruise = QUICK_TIME + 1.25
    r = SimpleNamespace(max_time=None)

    def plan(by_horizon: dict) -> tuple[float, list]:
        planned = _fake_planner(monkeypatch, {cruise: 0.9, short: 0.75, long: 0.78} | by_horizon)
        return cp.plan_catch(r, None, None).band.success, planned

    success, planned = plan({short: 0.96} | dict.fromkeys(FALLBACK_HORIZONS, 1.0))
    assert success == 0.96 and not set(FALLBACK_HORIZONS) & set(planned)  # a plan without a failure: no fallback
    success, planned = plan(dict.fromkeys(FALLBACK_HORIZONS, 1.0))
    assert planned[-1] == first and success == 1.0  # the first fallback sufficed: no other
    success, planned = plan(dict.fromkeys(FALLBACK_HORIZONS, 0.5) | {first: 0.93, second: 0.97})
    assert planned[-2:] == [first, second] and success == 0.97  # the first fell short: the next one
    success, planned = plan(dict.fromkeys(FALLBACK_HORIZONS, 0.5) | {last: 0.99})
    assert planned[-len(FALLBACK_HORIZONS) :] == list(FALLBACK_HORIZONS) and success == 0.99  # each in turn
    success, planned = plan(dict.fromkeys(FALLBACK_HORIZONS, 0.5))
    assert success == 0.9  # (the better one is kept either way)


def test_without_a_max_time_a_quick_plan_that_meets_the_goals_ends_the_search(monkeypatch):
    short, long = SWING_HORIZONS
    cruise = QUICK_TIME + 1.25
    quick, fb = stages(None)[0][0][0], stages(None)[1][0][0]  # the two quick stages' variants
    r = SimpleNamespace(max_time=None, min_success=0.95)
    planned = _fake_planner(monkeypatch, {quick: (0.97, 0.95, 1.5), fb: 1.0, short: 1.0, long: 1.0})
    res = cp.plan_catch(r, None, None)
    assert planned == [cruise] and res.band.success == 0.97  # the first quick plan met the goals: nothing else
    planned = _fake_planner(monkeypatch, {quick: 0.9, fb: (1.0, 0.95, 1.6), short: 1.0, long: 1.0})
    res = cp.plan_catch(r, None, None)
    assert planned == [cruise, cruise] and res.band.success == 1.0  # the second one did
    planned = _fake_planner(monkeypatch, {quick: (0.97, 0.95, QUICK_TIME + 0.2), fb: 0.5, short: 1.0, long: 1.0})
    res = cp.plan_catch(r, None, None)
    assert planned[:3] == [cruise, cruise, short] and res.band.success == 1.0  # too late for the goals: the rest
