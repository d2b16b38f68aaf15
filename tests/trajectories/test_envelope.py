"""The braking envelope: its stop distance against an independent fine-step integration, the clamp keeps every
state it admits brakeable, and the file check agrees with the per-cycle one."""

from __future__ import annotations

import math

import numpy as np
import pytest

from trajectories.envelope import BrakingEnvelope, brakeable, reverse_distance, stop_distance, velocity_peak
from trajectories.limits import default_limits

LIM = default_limits()


def _integrate_stop(v: float, a: float, a_max: float, j_max: float, h: float = 2e-6) -> tuple[float, float, float]:
    """An independent judge: integrate a jerk-limited stop with a bang-bang rule on a fine grid (semi-implicit
    Euler): each step, the jerk that brings the acceleration toward −a_max while the remaining velocity needs it,
    else toward 0. Returns (final displacement, largest, smallest displacement) [rad]."""
    s = 1.0 if (v > 0 or (v == 0 and a > 0)) else -1.0
    v, a = v * s, a * s
    x = hi = lo = 0.0
    for _ in range(2_000_000):
        # velocity still lost if the acceleration is ramped to zero from here (a < 0), or gained (a > 0)
        lost = a * abs(a) / (2 * j_max)
        if abs(v) < 1e-9 and abs(a) < 1e-6:
            break
        if v + lost > 0:  # must brake harder
            a = max(a - j_max * h, -a_max)
        else:  # ramp the braking back toward zero
            a = min(a + j_max * h, 0.0) if a < 0 else max(a - j_max * h, 0.0)
        v += a * h
        x += v * h
        hi, lo = max(hi, x), min(lo, x)
        if v < 0 and a >= 0:  # reversed (over-braking): the rest is the reverse stop
            break
    return s * x, max(s * hi, s * lo), min(s * hi, s * lo)


@pytest.mark.heavy
@pytest.mark.parametrize("seed", range(4))
def test_stop_distance_matches_a_fine_step_integration(seed: int) -> None:
    rng = np.random.default_rng(seed)
    a_max, j_max = float(LIM.acceleration[0]), float(LIM.jerk[0])
    for _ in range(12):
        v = float(rng.uniform(0.0, 1.7))
        a = float(rng.uniform(-a_max, a_max))
        if a < 0 and a * a > 2 * j_max * v:
            continue  # over-braking: checked below
        d = stop_distance(v, a, a_max, j_max)
        x, hi, _ = _integrate_stop(v, a, a_max, j_max)
        assert hi <= d + 1e-5, (v, a)  # the integration's reach is never beyond the bound …
        assert d - hi <= 2e-3 * max(d, 1e-3) + 1e-5, (v, a)  # … and the bound is tight
        assert stop_distance(-v, -a, a_max, j_max) == pytest.approx(-d)


@pytest.mark.heavy
def test_over_braking_stays_within_its_forward_and_reverse_bounds() -> None:
    a_max, j_max = float(LIM.acceleration[1]), float(LIM.jerk[1])
    for v, a in [(0.01, -8.0), (0.05, -8.5), (0.2, -8.57)]:
        assert a * a > 2 * j_max * v
        d = stop_distance(v, a, a_max, j_max)
        back = reverse_distance(v, a, a_max, j_max)
        _, hi, _ = _integrate_stop(v, a, a_max, j_max)
        assert 0 <= hi <= d + 1e-6 and back > 0
        # reversing at the peak, the velocity it reaches backwards is bounded by the bound's assumption
        assert a * a / (2 * j_max) - v <= a_max * a_max / (2 * j_max)


def test_the_velocity_peak_is_what_ramping_the_acceleration_down_adds() -> None:
    j = float(LIM.jerk[0])
    assert velocity_peak(1.0, 4.0, j) == pytest.approx(1.0 + 16.0 / (2 * j))
    assert velocity_peak(1.0, -4.0, j) == pytest.approx(1.0 - 16.0 / (2 * j))


def _walk(env: BrakingEnvelope, rng: np.random.Generator, n: int, jerk: bool, push: str) -> list[tuple[float, ...]]:
    """A history of commands a demanding client would ask for, admitted by the envelope."""
    dt = env.dt
    q0 = tuple(rng.uniform(-0.98, 0.98, 7) * LIM.position)
    h = [q0, q0, q0]
    sign = rng.choice([-1.0, 1.0], 7)
    for _ in range(n):
        q1, q2, q3 = h[-1], h[-2], h[-3]
        if push == "limit":  # toward the position limits at 1.5× the velocity limit
            des = [x + s * 1.5 * v * dt for x, s, v in zip(q1, sign, LIM.velocity)]
        else:  # random accelerations up to 3× the limit
            des = [2 * x - y + rng.normal() * 3 * a * dt * dt for x, y, a in zip(q1, q2, LIM.acceleration)]
        adm = env.admit(des, q1, q2, q3, jerk)
        assert adm.reason is None, adm.reason
        h.append(adm.q)
    return h


@pytest.mark.heavy
@pytest.mark.parametrize("jerk", [False, True])
@pytest.mark.parametrize("push", ["limit", "random"])
def test_every_admitted_state_is_brakeable_and_inside_the_limits(jerk: bool, push: str) -> None:
    env = BrakingEnvelope.from_limits(LIM, 1e-3)
    rng = np.random.default_rng(11 if jerk else 12)
    for _ in range(6):
        h = np.array(_walk(env, rng, 900, jerk, push))
        v = np.diff(h, axis=0) / env.dt
        a = np.diff(v, axis=0) / env.dt
        assert np.all(np.abs(h) <= LIM.position * (1 + 1e-9))
        assert np.all(np.abs(v) <= LIM.velocity * (1 + 1e-9))
        assert np.all(np.abs(a) <= LIM.acceleration * (1 + 1e-9))
        if jerk:
            assert np.all(np.abs(np.diff(a, axis=0)) / env.dt <= LIM.jerk * (1 + 1e-6))
        for k in range(3, len(h)):
            assert env.state_ok(h[k], h[k - 1], h[k - 2]) == -1
        peak, room = brakeable(h[3:], env.dt, LIM)
        assert np.all(np.abs(peak[2:]) <= LIM.velocity * (1 + 1e-9)) and room[2:].all()


def test_a_command_inside_the_envelope_is_left_alone_and_one_outside_is_clamped_to_its_edge() -> None:
    env = BrakingEnvelope.from_limits(LIM, 1e-3)
    dt = env.dt
    q1 = q2 = q3 = (0.0,) * 7
    ok = tuple(0.5 * a * dt * dt for a in LIM.acceleration)
    assert env.admit(ok, q1, q2, q3).clamped == 0.0
    # A1 cruising at the velocity limit and asked to accelerate further: held at the limit
    v = float(LIM.velocity[0])
    q2 = (-v * dt,) + (0.0,) * 6
    q3 = (-2 * v * dt,) + (0.0,) * 6
    adm = env.admit((v * dt + 1e-5,) + (0.0,) * 6, (0.0,) * 7, q2, q3)
    assert adm.reason is None and adm.joint == 0
    assert adm.q[0] == pytest.approx(v * dt, rel=1e-6)
    # at 0.95 of its velocity and accelerating hard: the clamp leaves the room the jerk-limited ramp-down needs
    w = 0.95 * v
    q2 = (-w * dt,) + (0.0,) * 6
    q3 = (-2 * w * dt,) + (0.0,) * 6
    adm = env.admit(((w + 8.0 * dt) * dt,) + (0.0,) * 6, (0.0,) * 7, q2, q3)
    a = (adm.q[0] - 0.0) / dt - w
    a /= dt
    assert 0 < a < 8.0 and velocity_peak(w + 1.5 * a * dt, a, float(LIM.jerk[0])) <= v * (1 + 1e-9)


def test_nan_and_wrong_length_are_reasons_not_clamps() -> None:
    env = BrakingEnvelope.from_limits(LIM, 1e-3)
    z = (0.0,) * 7
    assert "not a number" in env.admit((math.nan,) + z[1:], z, z, z).reason
    assert "6 values" in env.admit(z[:6], z, z, z).reason


def test_a_history_already_outside_leaves_no_admissible_command() -> None:
    env = BrakingEnvelope.from_limits(LIM, 1e-3)
    dt = env.dt
    v = float(LIM.velocity[0])
    a = float(LIM.acceleration[0])
    # at the velocity limit and still accelerating at the acceleration limit: no jerk-limited stop keeps the limit
    q1 = (0.0,) + (0.0,) * 6
    q2 = (-v * dt,) + (0.0,) * 6
    q3 = (-2 * v * dt + a * dt * dt,) + (0.0,) * 6
    adm = env.admit(q1, q1, q2, q3, jerk=True)
    assert adm.reason is not None and "A1" in adm.reason


def test_a_jerk_floor_widens_only_the_jerk_bound_to_the_paths_own_jerk() -> None:
    """From rest at 5 ms, an acceleration step of 1.5× the jerk limit (a file's own jerk): clamped to the limit with
    ``jerk``, admitted as it is with a floor of 1.6× the limit — and, with that floor, a step beyond the acceleration
    limit is still clamped to it."""
    env = BrakingEnvelope.from_limits(LIM, 5e-3)
    dt, zero = env.dt, (0.0,) * 7
    step = tuple(1.5 * j * dt * dt * dt for j in LIM.jerk)  # [rad]: acceleration 1.5·J·dt after one period
    floor = tuple(1.6 * j for j in LIM.jerk)
    clamped = env.admit(step, zero, zero, zero, jerk=True)
    assert clamped.reason is None and clamped.clamped > 0.3 * min(step)
    assert max(q / (j * dt**3) for q, j in zip(clamped.q, LIM.jerk)) == pytest.approx(1.0, rel=1e-6)
    assert env.admit(step, zero, zero, zero, jerk=True, jerk_floor=floor).clamped == 0.0
    over = tuple(1.2 * a * dt * dt for a in LIM.acceleration)  # (an unbounded floor: the acceleration limit holds)
    adm = env.admit(over, zero, zero, zero, jerk=True, jerk_floor=tuple(1e9 for _ in LIM.jerk))
    assert max(q / (a * dt * dt) for q, a in zip(adm.q, LIM.acceleration)) == pytest.approx(1.0, rel=1e-6)


@pytest.mark.parametrize("jerk", [False, True])
def test_the_compiled_quick_acceptance_decides_as_the_python_loop(jerk: bool, monkeypatch: pytest.MonkeyPatch) -> None:
    """trajectories._quick (built by setup.py) accepts a command only where the Python loop accepts every joint as
    it is, and the admission is then the same to the bit; on random commands around every bound, NaN and ints."""
    from trajectories import envelope as mod

    if mod._quick is None:
        pytest.skip("trajectories._quick is not built (no C compiler)")
    env = BrakingEnvelope.from_limits(LIM, 1e-3)
    rng = np.random.default_rng(11)
    pos, vel, acc = (np.asarray(x) for x in (LIM.position, LIM.velocity, LIM.acceleration))
    dt = 1e-3
    quick_yes = slow_yes = 0
    for i in range(4000):
        p3 = rng.uniform(-1.0, 1.0, 7) * pos
        v = rng.uniform(-1.05, 1.05, 7) * vel * rng.choice([0.01, 0.5, 1.0])
        a = rng.uniform(-1.1, 1.1, 7) * acc * rng.choice([0.001, 0.3, 1.0])
        p2 = p3 + v * dt
        p1 = p2 + (v + a * dt) * dt
        q = p1 + (v + a * dt * rng.uniform(0.9, 1.1, 7)) * dt
        args = [tuple(x.tolist()) for x in (q, p1, p2, p3)]
        if i % 97 == 0:
            args[0] = args[0][:3] + (float("nan"),) + args[0][4:]
        if i % 89 == 0:
            args[0] = list(args[0][:6]) + [0]  # an int and a list
        floor = tuple(rng.uniform(0, 2, 7) * np.asarray(LIM.jerk)) if i % 2 else None
        fast = env.admit(*args, jerk, floor)
        monkeypatch.setattr(mod, "_quick", None)
        slow = env.admit(*args, jerk, floor)
        monkeypatch.undo()
        assert (fast.q, fast.clamped, fast.joint, fast.reason) == (slow.q, slow.clamped, slow.joint, slow.reason)
        quick_yes += mod._quick.admit(*args, env._packed_bounds, None if floor is None or not jerk else
                                      np.asarray(floor, float).tobytes(), jerk, 1.000000001e-3, 1e6, dt)  # fmt: skip
        slow_yes += slow.clamped == 0.0 and slow.reason is None
    assert 100 < quick_yes <= slow_yes < 3900  # both answers were exercised
