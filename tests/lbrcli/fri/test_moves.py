"""Moves to a start: the input-shaped move stays within its share of the limits, arrives exactly, leaves a ball on
the TCP at rest (judged by the independent spherical-pendulum integrator), and restarts unshaped from motion."""

from __future__ import annotations

import numpy as np
import pytest

from lbrcli.fri.moves import OnlineMove, ShapedMove, fade_factor
from planners.pendulum import natural_period
from planners.shapers import make_shaper
from planners.sway_judge import judge_sway
from trajectories.limits import default_limits
from trajectories.robot import Robot

LIM = default_limits()
HOME = np.array([0.0, 0.6, 0.0, -1.4, 0.0, 1.14, 0.0])
DT = 0.005  # [s]


def _moves(seed: int, n: int) -> list[tuple[np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(seed)
    return [(HOME + rng.uniform(-0.5, 0.5, 7), HOME + rng.uniform(-0.5, 0.5, 7)) for _ in range(n)]


def _play(move, a, b, v=None) -> np.ndarray:
    move.start(a, b, v)
    out = [tuple(a)]
    while not move.done:
        out.append(move.next())
    return np.array(out)


@pytest.fixture(scope="module")
def robot():
    return Robot()


@pytest.mark.heavy
@pytest.mark.parametrize("length", [0.25, 0.6, 1.0])
def test_shaped_move_leaves_the_ball_at_rest_within_a_fifth_of_the_limits(robot, length):
    shaper = make_shaper("zvd", natural_period(length))
    for a, b in _moves(int(length * 100), 3):
        plain = _play(OnlineMove(LIM, DT, 0.2), a, b)
        shaped = _play(ShapedMove(LIM, DT, 0.2, shaper.amplitudes, shaper.times, robot=robot), a, b)
        np.testing.assert_array_equal(shaped[-1], b)  # arrives exactly
        assert len(shaped) * DT == pytest.approx(len(plain) * DT + shaper.duration, abs=2 * DT)
        for k, lim in ((1, LIM.velocity), (2, LIM.acceleration), (3, LIM.jerk)):
            ratio = (np.abs(np.diff(shaped, k, axis=0)) / DT**k / lim).max()
            assert ratio <= 0.3, (k, ratio)  # ≤ 0.2 of the limits for the convolution, a few % for the TCP correction
        res_plain = judge_sway(robot.fk_path(plain)[0], DT, length, len(plain) * DT)[0]  # [deg]
        res_shaped = judge_sway(robot.fk_path(shaped)[0], DT, length, len(shaped) * DT)[0]
        assert res_plain > 1.0  # what the move to the start used to leave (the issue saw 6.9°)
        assert res_shaped < 0.15 and res_shaped < res_plain / 30, (res_plain, res_shaped)


@pytest.mark.heavy
def test_joint_space_shaping_alone_leaves_ten_times_more_sway(robot):
    shaper = make_shaper("zvd", natural_period(0.5))
    a, b = _moves(5, 1)[0]
    joint = _play(ShapedMove(LIM, DT, 0.2, shaper.amplitudes, shaper.times), a, b)
    tcp = _play(ShapedMove(LIM, DT, 0.2, shaper.amplitudes, shaper.times, robot=robot), a, b)
    r_joint = judge_sway(robot.fk_path(joint)[0], DT, 0.5, len(joint) * DT)[0]
    r_tcp = judge_sway(robot.fk_path(tcp)[0], DT, 0.5, len(tcp) * DT)[0]
    assert r_tcp < r_joint / 3, (r_joint, r_tcp)
    step = np.abs(np.diff(joint, axis=0)) / DT
    assert np.all(step <= 0.2 * LIM.velocity * (1 + 1e-9))  # a convex combination: exactly within the scaled limits


def test_a_restart_from_motion_is_unshaped_and_continues_the_velocity(robot):
    shaper = make_shaper("zvd", natural_period(0.5))
    a, b = _moves(9, 1)[0]
    v = 0.1 * LIM.velocity * np.sign(b - a)  # [rad/s]
    q = _play(ShapedMove(LIM, DT, 0.2, shaper.amplitudes, shaper.times, robot=robot), a, b, v)
    np.testing.assert_array_equal(q[-1], b)
    first = (q[1] - q[0]) / DT
    assert np.all(np.abs(first - v) <= 0.2 * LIM.acceleration * DT + 1e-9)  # no velocity jump
    plain = _play(OnlineMove(LIM, DT, 0.2), a, b, v)
    assert len(q) == pytest.approx(len(plain), abs=2)  # not lengthened by the shaper


def test_a_shaped_move_of_nothing_takes_no_time(robot):
    shaper = make_shaper("zvd", natural_period(0.5))
    move = ShapedMove(LIM, DT, 0.2, shaper.amplitudes, shaper.times, robot=robot)
    assert move.start(HOME, HOME) == 0.0  # not the shaper's second: nothing swings
    assert move.next() == tuple(HOME) and move.done


def test_a_fade_back_onto_the_rail_keeps_its_jerk_budget_and_is_as_fast_as_allowed_when_small():
    """The double-pole fade of an offset the controller's extrapolation left (1 µrad to 10 mrad, with a step of up
    to 1 mrad per period between its last two values): its third difference, run to the end, stays within the
    budget on every joint; a tiny offset fades at the fastest rate."""
    lim, dt = default_limits(), 1e-3
    budget = 0.07 * lim.jerk  # [rad/s³]
    rng = np.random.default_rng(3)
    slow = 0
    for _ in range(120):
        off = rng.normal(0.0, 10 ** rng.uniform(-6, -2), 7)
        prev = off - rng.normal(0.0, 10 ** rng.uniform(-7, -3), 7)
        f = fade_factor(off, prev, budget, dt, 0.98)
        assert 0.98 <= f < 1.0
        slow += f > 0.98
        o = [prev, off]
        for _ in range(int(30 / (1 - f))):
            o.append(2 * f * o[-1] - f * f * o[-2])
        third = np.abs(np.diff(np.array(o), 3, axis=0)).max(axis=0) / dt**3
        assert np.all(third <= budget), (third / budget).max()
        assert np.abs(o[-1]).max() < 1e-3 * np.abs(o[:2]).max() + 1e-12  # it does fade
    assert slow > 40  # (the budget is what sets the rate for the larger offsets)
    assert fade_factor([1e-9] * 7, [1e-9] * 7, budget, dt, 0.98) == 0.98
