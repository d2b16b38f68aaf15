"""The arm as a cart on a rail (planners.rail): IK along base y, and bounds that keep the joints in their limits."""

from __future__ import annotations

import numpy as np
import pytest

from planners.rail import build_rail


@pytest.fixture(scope="module")
def rail(robot, limits, q_start):
    return build_rail(robot, q_start, limits, 0.3)


@pytest.fixture(scope="module")
def q_start():
    from tests.helpers.cli import Q_START

    return Q_START.copy()


def test_the_spline_puts_the_tcp_on_the_rail(rail, robot, q_start):
    p0 = robot.fk(q_start).translation
    assert np.allclose(rail.joints(0.0), q_start, atol=1e-6)
    for x in np.linspace(-0.3, 0.3, 23):
        p = robot.fk(rail.joints(x)).translation
        assert p[1] == pytest.approx(p0[1] + x, abs=2e-5) and p[0] == pytest.approx(p0[0], abs=2e-5)
        assert p[2] == pytest.approx(p0[2], abs=2e-5)
        assert rail.joints_list(x) == pytest.approx(rail.joints(x).tolist(), abs=1e-12)


def test_the_rail_runs_on_past_its_travel_where_the_arm_reaches(rail, robot, q_start):
    """A cart that coasted a little past ±travel (the controller extrapolated through lost messages) is still on the
    rail, not held at a clamped end — a clamp would stop the joints within one cycle."""
    p0 = robot.fk(q_start).translation
    for x in (0.305, 0.32, -0.305, -0.32):
        p = robot.fk(rail.joints(x)).translation
        assert p[1] == pytest.approx(p0[1] + x, abs=2e-5) and p[2] == pytest.approx(p0[2], abs=2e-5)
    assert rail.limits.travel == 0.3  # the cart's own bound is unchanged


def test_local_bounds_keep_every_joint_inside_its_limits(rail, limits):
    """Random cart states at the edge of the local bounds: the joint rates they give sit at, never above, 0.9 of the
    limits (the rail's margin); and the constant bounds are inside the local ones everywhere."""
    rng = np.random.default_rng(3)
    h = 1e-4
    for _ in range(300):
        x = rng.uniform(-0.29, 0.29)
        speed, lo, hi, jlo, jhi = rail.local_bounds(x, 0.0, 0.0)
        assert (
            speed >= rail.limits.velocity - 1e-9
            and hi >= rail.limits.acceleration - 1e-9
            and -lo >= rail.limits.acceleration - 1e-9
        )
        v = rng.uniform(-0.95, 0.95) * speed
        _, lo, hi, jlo, jhi = rail.local_bounds(x, v, 0.0)
        a = rng.choice([lo, hi]) * 0.999
        q = np.array([rail.joints(x + v * k * h + 0.5 * a * (k * h) ** 2) for k in (-1, 0, 1)])
        qd = (q[2] - q[0]) / (2 * h)
        qdd = (q[2] - 2 * q[1] + q[0]) / h**2
        assert np.all(np.abs(qd) <= 0.9 * limits.velocity + 1e-6)
        assert np.all(np.abs(qdd) <= 0.9 * limits.acceleration * 1.01)
        assert np.max(np.abs(qdd) / (0.9 * limits.acceleration)) > 0.95  # the bound is tight, not just safe


def test_an_unreachable_rail_is_refused(robot, limits, q_start):
    with pytest.raises(ValueError):
        build_rail(robot, q_start, limits, 2.0)
