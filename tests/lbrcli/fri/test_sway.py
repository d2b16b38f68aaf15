"""The sway watch and the player's wait for the ball at the first row: the window, the calm decision, the restart
when the robot arrives, the time-out, lost messages while waiting, and no sensor at all (scripted controller)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from lbrcli.fri.testing import CA, Cycle
from tests.helpers.fri_session import LIM, min_jerk, preamble, run, sent_positions

from lbrcli.fri import Outcome, TrajectoryPlayer
from lbrcli.fri.sway import IoSway, SwayWatch, window_for_length


def _state(theta=None, name="ball_theta", sample_time=1e-3):
    ios = (
        []
        if theta is None
        else [SimpleNamespace(name="other", analogValue=9.0), SimpleNamespace(name=name, analogValue=theta)]
    )
    msg = SimpleNamespace(monitorData=SimpleNamespace(readIORequest=ios))
    return SimpleNamespace(message=msg, sample_time=sample_time)


def test_io_sway_reads_the_named_analog_input_or_none():
    src = IoSway("ball_theta")
    assert src(_state(0.25)) == 0.25 and src(_state(-0.5)) == -0.5
    assert IoSway("ball_theta")(_state(None)) is None  # a message without it: no reading (checked once)


def test_window_covers_half_a_swing_period():
    assert window_for_length(0.25) == pytest.approx(0.6 * 2 * math.pi * math.sqrt(0.25 / 9.80665))
    assert window_for_length(None) == window_for_length(0) == 1.2


def test_watch_amplitude_is_the_largest_tilt_of_the_last_window_and_calm_needs_a_whole_quiet_window():
    rng = np.random.default_rng(3)
    t = np.arange(3000) * 1e-3
    theta = 0.05 * np.exp(-t / 0.4) * np.cos(2 * np.pi * t / 1.0) + rng.normal(0, 1e-5, t.size)  # [rad]
    watch = SwayWatch(lambda s: s.x, threshold=1e-3, window_s=0.2, max_wait_s=1.0)
    calm_at = None
    quiet = 0
    for k, x in enumerate(theta):
        watch.update(SimpleNamespace(x=x, sample_time=1e-3))
        quiet = quiet + 1 if abs(x) < 1e-3 else 0
        assert watch.amplitude == pytest.approx(np.abs(theta[max(0, k - 199) : k + 1]).max())
        assert watch.calm == (quiet >= 200)
        if watch.calm and calm_at is None:
            calm_at = k
    assert calm_at is not None and np.all(np.abs(theta[calm_at - 199 : calm_at + 1]) < 1e-3)
    assert np.abs(theta[calm_at - 200]) >= 1e-3  # not a message earlier


def test_watch_ignores_missing_and_nan_readings_and_restarts():
    vals = iter([0.0, None, 0.0, math.nan, 0.0, 0.0, 0.0, 0.02, 0.0])
    watch = SwayWatch(lambda _s: next(vals), threshold=0.01, window_s=3e-3, max_wait_s=1.0)
    seen = []
    for _ in range(9):
        watch.update(_state(None))
        seen.append(watch.calm)
    assert watch.readings == 7
    assert seen == [False, False, False, False, False, False, True, False, False]  # a gap restarts the quiet count
    watch.restart()
    assert watch.amplitude is None and not watch.calm
    with pytest.raises(ValueError):
        SwayWatch(None, 0.0, 1.0, 1.0)
    with pytest.raises(ValueError):
        SwayWatch(None, 0.01, 1.0, -1.0)


# -- the player's wait, against the scripted controller (1 ms messages, ball_theta scripted per cycle) ----------
def _decaying(n: int, a0: float = 0.02, tau: float = 150.0) -> list[float]:
    k = np.arange(n)
    return list(np.abs(a0 * np.exp(-k / tau) * np.cos(2 * np.pi * k / 80.0)))


@pytest.mark.heavy
def test_the_first_row_is_held_until_the_ball_has_been_calm_for_a_window():
    traj = min_jerk(40)
    balls = _decaying(3000)
    script = preamble(ball=0.02) + [Cycle(state=CA, ball=b) for b in balls]
    watch = SwayWatch(IoSway(), threshold=1e-3, window_s=0.05, max_wait_s=5.0)
    player = TrajectoryPlayer(traj, LIM, period_s=1e-3, move_to_start=True, sway=watch)
    res, ctl, _, err = run(script, player)
    assert err is None and res.outcome is Outcome.COMPLETED
    quiet, expect = 0, None
    for i, b in enumerate(balls):  # the CA message at which 50 readings in a row were below 1e-3 rad
        quiet = quiet + 1 if b < 1e-3 else 0
        if quiet >= 50:
            expect = i
            break
    f = player.figures()
    assert f["sway_wait_rows"] == expect > 100
    q = sent_positions(ctl)
    np.testing.assert_array_equal(q[:expect], np.repeat(traj[:1], expect, axis=0))  # held exactly at row 0
    np.testing.assert_array_equal(q[expect : expect + len(traj)], traj)  # then every row
    assert f["start_sway_rad"] == pytest.approx(max(balls[expect - 49 : expect + 1]))
    assert f["start_sway_above_threshold"] is False and f["sway_wait_s"] == pytest.approx(expect * 1e-3)


def test_a_sway_that_does_not_decay_is_waited_for_at_most_max_wait_then_reported():
    traj = min_jerk(40)
    script = preamble(ball=0.03) + [Cycle(state=CA, ball=0.03)] * 400
    player = TrajectoryPlayer(traj, LIM, period_s=1e-3, move_to_start=True,
                              sway=SwayWatch(IoSway(), 1e-3, 0.05, max_wait_s=0.1))  # fmt: skip
    res, ctl, _, err = run(script, player)
    assert err is None and res.outcome is Outcome.COMPLETED
    f = player.figures()
    assert f["sway_wait_rows"] == 100 and f["start_sway_above_threshold"] is True
    assert f["start_sway_deg"] == pytest.approx(math.degrees(0.03))
    np.testing.assert_array_equal(sent_positions(ctl)[100 : 100 + len(traj)], traj)


def test_without_move_to_start_the_sway_is_reported_not_waited_for():
    traj = min_jerk(40)
    balls = [0.03 * abs(math.cos(k / 10)) for k in range(200)]
    script = preamble(ball=0.03) + [Cycle(state=CA, ball=b) for b in balls]
    player = TrajectoryPlayer(traj, LIM, period_s=1e-3, sway=SwayWatch(IoSway(), 1e-3, 0.05, 5.0))
    res, ctl, _, err = run(script, player)
    assert err is None and res.outcome is Outcome.COMPLETED
    f = player.figures()
    assert f["sway_wait_rows"] == 0 and f["start_sway_above_threshold"] is True
    assert f["start_sway_rad"] == pytest.approx(0.03)  # the largest of the last 50 readings (the preamble's)
    np.testing.assert_array_equal(sent_positions(ctl)[: len(traj)], traj)


def test_without_a_sway_reading_nothing_waits_and_no_sway_is_reported():
    traj = min_jerk(40)
    player = TrajectoryPlayer(traj, LIM, period_s=1e-3, move_to_start=True, sway=SwayWatch(IoSway(), 1e-3, 0.05, 5.0))
    res, ctl, _, err = run(preamble(ball=None) + [Cycle(state=CA, ball=None)] * 100, player)
    assert err is None and res.outcome is Outcome.COMPLETED
    f = player.figures()
    assert f["sway_wait_rows"] == 0 and f["start_sway_rad"] is None
    np.testing.assert_array_equal(sent_positions(ctl)[: len(traj)], traj)


@pytest.mark.heavy
def test_after_a_move_the_swing_is_judged_from_the_arrival_on():
    traj = min_jerk(40) + np.array([0, 0, 0, 0.02, 0, 0, 0])
    script = preamble(ball=0.0) + [Cycle(state=CA, ball=0.0)] * 3000
    player = TrajectoryPlayer(traj, LIM, period_s=1e-3, move_to_start=True,
                              sway=SwayWatch(IoSway(), 1e-3, 0.05, 5.0))  # fmt: skip
    res, ctl, _, err = run(script, player)
    assert err is None and res.outcome is Outcome.COMPLETED and player.move_rows > 50
    # calm all along, yet the readings during the move do not count: a whole window at rest after the arrival
    assert player.figures()["sway_wait_rows"] == 50
    q = sent_positions(ctl)
    m = player.move_rows
    np.testing.assert_array_equal(q[m : m + 50], np.repeat(traj[:1], 50, axis=0))
    np.testing.assert_array_equal(q[m + 50 : m + 50 + len(traj)], traj)


@pytest.mark.heavy
def test_messages_lost_while_waiting_skip_no_row():
    traj = min_jerk(400)
    script = preamble(ball=0.03) + [Cycle(state=CA, ball=0.03)] * 60 + [Cycle(state=CA, ball=0.03, seq_jump=3)]
    script += [Cycle(state=CA, ball=0.0)] * 1000
    player = TrajectoryPlayer(traj, LIM, period_s=1e-3, move_to_start=True, sway=SwayWatch(IoSway(), 1e-3, 0.05, 5.0))
    res, ctl, _, err = run(script, player)
    assert err is None and res.outcome is Outcome.COMPLETED and res.extrapolated_cycles == 3
    assert player.trajectory_rows == len(traj)  # the gap fell in the wait: every row is still streamed
    q = sent_positions(ctl)
    w = player.figures()["sway_wait_rows"]
    np.testing.assert_array_equal(q[w : w + len(traj)], traj)
    assert max(ctl.command_ratios(LIM.velocity, LIM.acceleration)) <= 1.0
