"""The per-cycle guard: its fast path (one comparison per joint away from the limits) decides exactly as the full
per-joint check, and a command that could not stop before a position limit is refused."""

from __future__ import annotations

import numpy as np
import pytest

from lbrcli.fri.guard import CommandGuard
from trajectories.envelope import stop_distance as stopping_distance
from trajectories.limits import default_limits


def _full_check(guard: CommandGuard, q, prev, prev2, room: bool) -> str | None:
    for j in range(7):
        problem = guard._joint_problem(j, q[j], q[j] - prev[j], (q[j] - prev[j]) - (prev[j] - prev2[j]), room)
        if problem is not None:
            return problem
    return None


@pytest.mark.heavy
@pytest.mark.parametrize("period_s", [1e-3, 5e-3])
def test_fast_path_decides_as_the_full_check_everywhere(period_s: float) -> None:
    limits = default_limits()
    guard = CommandGuard.from_limits(limits, period_s)
    rng = np.random.default_rng(7)
    upper = np.asarray(limits.position)
    v, a = np.asarray(limits.velocity), np.asarray(limits.acceleration)
    refused = near = 0
    for _ in range(20000):
        # positions anywhere up to just beyond the limits, velocities/accelerations up to 1.2x theirs
        p1 = rng.uniform(-1.02, 1.02, 7) * upper
        vel = rng.uniform(-1.2, 1.2, 7) * v
        acc = rng.uniform(-1.2, 1.2, 7) * a
        step = vel * period_s
        second = acc * period_s**2
        p2 = p1 - (step - second)
        q = p1 + step
        qt, p1t, p2t = tuple(q.tolist()), tuple(p1.tolist()), tuple(p2.tolist())
        for room in (True, False):
            fast = guard.refuse_position(qt, p1t, p2t, room)
            assert fast == _full_check(guard, qt, p1t, p2t, room)
            refused += fast is not None
        near += bool(np.any(np.abs(q) > np.asarray(guard.free)))
    assert refused > 1000 and near > 1000  # both paths were exercised


def test_nan_and_a_stop_past_the_limit_are_refused() -> None:
    limits = default_limits()
    guard = CommandGuard.from_limits(limits, 1e-3)
    q0 = (0.0,) * 7
    assert "A3" in guard.refuse_position((0.0, 0.0, float("nan"), 0.0, 0.0, 0.0, 0.0), q0, q0)
    # A1 at 1.5 rad/s, 0.05 rad inside its limit: its stop needs ~0.15 rad
    lim = limits.position[0]
    step = 1.5e-3
    q = (lim - 0.05,) + (0.0,) * 6
    prev = (lim - 0.05 - step,) + (0.0,) * 6
    prev2 = (lim - 0.05 - 2 * step,) + (0.0,) * 6
    assert stopping_distance(1.5, 0.0, limits.acceleration[0], limits.jerk[0]) > 0.05
    assert "cannot stop" in guard.refuse_position(q, prev, prev2, True)
    assert guard.refuse_position(q, prev, prev2, False) is None  # the braking stop itself is exempt
    far = (0.0,) + (0.0,) * 6
    assert guard.refuse_position((far[0] + step,) + far[1:], far, (far[0] - step,) + far[1:]) is None


def test_the_compiled_quick_acceptance_refuses_as_the_python_loop(monkeypatch: pytest.MonkeyPatch) -> None:
    """With and without trajectories._quick the guard gives the same answer, on commands around every bound."""
    from lbrcli.fri import guard as mod

    if mod._quick is None:
        pytest.skip("trajectories._quick is not built (no C compiler)")
    limits = default_limits()
    guard = CommandGuard.from_limits(limits, 1e-3)
    rng = np.random.default_rng(5)
    upper, v, a = (np.asarray(x) for x in (limits.position, limits.velocity, limits.acceleration))
    refused = 0
    for i in range(4000):
        p1 = rng.uniform(-1.02, 1.02, 7) * upper * rng.choice([0.5, 1.0])
        step = rng.uniform(-1.1, 1.1, 7) * v * 1e-3
        p2 = p1 - step + rng.uniform(-1.1, 1.1, 7) * a * 1e-6
        q = p1 + step
        args = [tuple(x.tolist()) for x in (q, p1, p2)]
        if i % 101 == 0:
            args[0] = (float("inf"),) + args[0][1:]
        for room in (False, True):
            fast = guard.refuse_position(*args, room)
            monkeypatch.setattr(mod, "_quick", None)
            assert guard.refuse_position(*args, room) == fast
            monkeypatch.undo()
            refused += fast is not None
    assert 1000 < refused < 7000
