"""Supervisor (lbrcli.fri.supervision): the controller's clock, replies reaching it, the robot following; and the
reply check end to end against the scripted controller."""

from __future__ import annotations

import pytest

import math

from lbrcli.campaign.execute import LIM, Q0, ramp
from lbrcli.fri.testing import active, preamble
from lbrcli.fri.testing import CA, Cycle, ScriptedController

from lbrcli.fri import ClientApplication, EndReason, TrajectoryPlayer
from trajectories.envelope import stop_distance as stopping_distance
from lbrcli.fri.supervision import RX_WINDOW, Supervisor


def sup(period=5e-3):
    return Supervisor.from_limits(LIM.velocity, period)


def test_a_clock_that_agrees_never_trips_even_late_or_coarse():
    s = sup()
    for seq in range(2000):
        late = 3_000_000 if seq % 7 == 0 else 0  # [ns] jitter: some messages stamped late
        ns = 1_000_000_000 + seq * 5_000_000 + late
        assert s.clock(seq, ns // 10**9, ns % 10**9) is None
    coarse = sup()
    for seq in range(2000):  # whole seconds only
        assert coarse.clock(seq, 100 + seq * 5 // 1000, 0) is None
    none = sup()
    assert all(none.clock(seq, 0, 0) is None for seq in range(100))  # a controller without timestamps


def test_a_controller_faster_than_its_period_trips_within_ten_messages():
    s = sup()
    for seq in range(1, 40):
        ns = seq * 2_000_000  # 2 ms real, 5 ms claimed
        text = s.clock(seq, ns // 10**9, ns % 10**9)
        if text:
            break
    assert text and "2.00 ms, not every 5 ms" in text and seq <= 10


def test_tracking_bound_defaults_from_the_velocity_limit_and_the_period():
    assert sup(1e-3).max_tracking_error[0] == LIM.velocity[0] * 0.02
    assert math.isclose(sup(5e-3).max_tracking_error[0], LIM.velocity[0] * 0.04)
    s = sup()
    q = tuple(Q0)
    assert s.tracking(q, q) is None
    pushed = (q[0], q[1], q[2] + 0.2, *q[3:])
    assert "A3" in s.tracking(pushed, q)


def test_stopping_distance_is_an_upper_bound_of_a_jerk_limited_stop():
    # v²/2a + v·a/2j from a = 0 at 1.5 rad/s on A1: 0.131 + 0.0475
    assert math.isclose(stopping_distance(1.5, 0.0, 8.57, 135.0), 1.5**2 / 17.14 + 1.5 * 8.57 / 270, rel_tol=1e-12)
    assert stopping_distance(-1.5, 0.0, 8.57, 135.0) < 0
    assert stopping_distance(1.0, 5.0, 8.57, 135.0) > stopping_distance(1.0, 0.0, 8.57, 135.0)
    assert stopping_distance(1.0, -8.57, 8.57, 135.0) < stopping_distance(1.0, 0.0, 8.57, 135.0)


@pytest.mark.heavy
def test_replies_that_stop_reaching_the_controller_end_the_stream():
    rows = ramp(900, speed=0.3)
    player = TrajectoryPlayer(rows, LIM, period_s=1e-3)
    app = ClientApplication(player, "127.0.0.1", 0, bind_host="127.0.0.1", version="1.15", limits=LIM,
                            first_message_timeout_s=10, silence_timeout_s=3)  # fmt: skip
    app.connect()
    script = preamble() + active(1300, {300: [Cycle(state=CA, drop_reply=True)] * 120})
    ctl = ScriptedController(app.port, script, tuple(Q0), tolerate_unanswered=1000, reply_timeout=0.3).start()
    try:
        res = app.run()
    finally:
        ctl.finish(app)
    assert res.reason is EndReason.SUPERVISION and "replies lost" in res.detail
    assert 50 <= res.largest_reply_gap <= 52  # tripped as the gap passed 50 ms


def test_joint_values_outside_the_limits_or_not_finite_are_not_a_robots() -> None:
    from lbrcli.fri.supervision import POSITION_SLACK, joints_ok
    from trajectories.limits import default_limits

    lim = tuple(default_limits().position)
    assert joints_ok((0.0,) * 7, lim) and joints_ok(lim, lim)
    assert not joints_ok((0.0,) * 6, lim)
    for bad in (float("nan"), float("inf"), -float("inf")):
        for j in range(7):
            assert not joints_ok(tuple(bad if i == j else 0.0 for i in range(7)), lim)
    assert not joints_ok((float("inf"), -float("inf")) + (0.0,) * 5, lim)  # inf - inf is NaN, still refused
    for j in range(7):
        near = tuple(lim[i] + (0.9 if i == j else 0.0) * POSITION_SLACK for i in range(7))
        beyond = tuple(-lim[i] - (1.1 if i == j else 0.0) * POSITION_SLACK for i in range(7))
        assert joints_ok(near, lim) and not joints_ok(beyond, lim)


def test_tracking_names_the_joint_that_left_its_bound_even_as_nan() -> None:
    s = Supervisor((0.01,) * 7, 50, 1e-3)
    q = (0.1,) * 7
    assert s.tracking(q, q) is None and s.largest_tracking_error == 0.0
    near = tuple(0.1 + (0.009 if j == 6 else 0.0) for j in range(7))
    assert s.tracking(near, q) is None and abs(s.largest_tracking_error - 0.009) < 1e-12
    for j in range(7):
        for bad in (0.1 + 0.02, float("nan")):
            m = tuple(bad if i == j else 0.1 for i in range(7))
            assert f"A{j + 1} " in s.tracking(m, q)


def _first_problem(s: Supervisor, stamps) -> tuple[int, str] | tuple[None, None]:
    """Feed (seq, timestamp [ns], kernel receive time [ns] or None); the first message with a problem."""
    for seq, ts, rx in stamps:
        text = s.clock(seq, ts // 10**9, ts % 10**9, rx)
        if text:
            return seq, text
    return None, None


def test_a_clock_that_freezes_mid_session_trips_within_a_few_messages():
    p = 1_000_000  # [ns] 1 ms
    stamps = [(k, 10**9 + 123 + k * p if k < 500 else 10**9 + 123 + 500 * p, 5 * 10**9 + k * p) for k in range(700)]
    seq, text = _first_problem(sup(1e-3), stamps)
    assert seq is not None and 500 < seq <= 500 + 10 and ("froze" in text or "advanced" in text)


def test_a_clock_that_jumps_back_or_ahead_trips_at_once():
    p = 1_000_000
    back = [(k, 10**9 + k * p - (50 * p if k >= 300 else 0), None) for k in range(400)]
    seq, text = _first_problem(sup(1e-3), back)
    assert seq == 300 and "went back" in text
    ahead = [(k, 10**9 + k * p + (500 * p if k >= 300 else 0), None) for k in range(400)]
    seq, text = _first_problem(sup(1e-3), ahead)
    assert seq == 300 and "jumped" in text


def test_a_period_change_mid_session_trips_within_the_window_not_the_whole_session():
    # 2000 messages at 1 ms, then the controller sends every 0.3 ms while its timestamps and period still say 1 ms
    p = 1_000_000
    rx = [5 * 10**9 + k * p for k in range(2000)] + [5 * 10**9 + 2000 * p + k * p * 3 // 10 for k in range(1, 200)]
    stamps = [(k, 10**9 + k * p, r) for k, r in enumerate(rx)]
    seq, text = _first_problem(sup(1e-3), stamps)
    assert seq is not None and 2000 < seq <= 2000 + RX_WINDOW and "messages advanced" in text
    # the same change on its own clock too: found within a few messages
    stamps = [(k, 10**9 + (r - 5 * 10**9), r) for k, r in enumerate(rx)]
    seq, text = _first_problem(sup(1e-3), stamps)
    assert seq is not None and 2000 < seq <= 2000 + 6 and "timestamps advanced" in text


def test_a_frozen_clock_that_sends_faster_than_its_period_is_caught_by_the_receive_times():
    # claims 5 ms, sends every 2 ms; its timestamps stand still (a coarse clock's worth: whole seconds)
    stamps = [(k, 7 * 10**9, 3 * 10**9 + k * 2_000_000) for k in range(100)]
    s = sup(5e-3)
    seq, text = _first_problem(s, stamps)
    assert seq is not None and seq <= 10 and "2.00 ms, not every 5 ms" in text
    assert s.measured_period_s is not None and abs(s.measured_period_s - 2e-3) < 1e-4


def test_a_much_slower_controller_trips_only_when_both_clocks_agree():
    p = 1_000_000
    slow = [(k, 10**9 + k * 2 * p, 5 * 10**9 + k * 2 * p) for k in range(300)]  # 2 ms real, 1 ms claimed
    seq, text = _first_problem(sup(1e-3), slow)
    assert seq is not None and seq <= 110 and "not every 1 ms" in text
    # our receive times late in a burst (this process or the network stalled), its own clock on time: no problem
    rx = [5 * 10**9 + k * p + (30 * p if 100 <= k < 130 else 0) for k in range(400)]
    assert _first_problem(sup(1e-3), [(k, 10**9 + k * p, r) for k, r in enumerate(rx)]) == (None, None)


def test_receive_jitter_of_a_loaded_machine_never_trips():
    import numpy as np

    rng = np.random.default_rng(3)
    p = 1_000_000
    # sends on a 1 ms grid, each up to 0.5 ms late (never two closer than 0.9 period); timestamps exact
    late = np.minimum(rng.exponential(0.1 * p, 5000), 0.5 * p).astype(int)
    rx = [5 * 10**9 + k * p + int(d) for k, d in enumerate(late)]
    assert _first_problem(sup(1e-3), [(k, 10**9 + k * p, r) for k, r in enumerate(rx)]) == (None, None)


def test_the_compiled_joint_checks_answer_as_the_python_ones(monkeypatch: pytest.MonkeyPatch) -> None:
    """supervision.within and Supervisor.tracking with trajectories._quick give what their Python gives: on values
    around the bound, NaN, inf and the wrong count."""
    import numpy as np

    from lbrcli.fri import supervision as mod

    if mod._quick is None:
        pytest.skip("trajectories._quick is not built (no C compiler)")
    rng = np.random.default_rng(3)
    bound = tuple(rng.uniform(0.5, 3.0, 7).tolist())
    assert mod.within is mod._quick.within
    src = "def within(values, bound):\n    return len(values) == 7 and all(map(_le, map(abs, values), bound))\n"
    ns: dict = {"_le": mod._le}
    exec(src, ns)  # the Python definition, as the module has it without the extension
    answers = set()
    for i in range(3000):
        v = (np.asarray(bound) * rng.uniform(-1.05, 1.05, 7)).tolist()
        if i % 50 == 0:
            v[i % 7] = float("nan") if i % 100 else float("inf")
        if i % 77 == 0:
            v = v[:6]
        answers.add(mod.within(v, bound))
        assert mod.within(v, bound) == ns["within"](v, bound)
        sup_c, sup_py = mod.Supervisor(bound, 50, 1e-3), mod.Supervisor(bound, 50, 1e-3)
        cmd = (np.asarray(v[:7] if len(v) == 7 else v + [0.0]) * rng.uniform(0.0, 2.0)).tolist()
        a = sup_c.tracking(v if len(v) == 7 else v + [0.0], cmd)
        monkeypatch.setattr(mod, "_quick", None)
        b = sup_py.tracking(v if len(v) == 7 else v + [0.0], cmd)
        monkeypatch.undo()
        assert (
            a == b
            and sup_c.largest_tracking_error == sup_py.largest_tracking_error
            or (math.isnan(sup_c.largest_tracking_error) and math.isnan(sup_py.largest_tracking_error))
        )
    assert answers == {True, False}
