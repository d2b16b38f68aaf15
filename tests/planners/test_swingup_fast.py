"""Fast swing-up: reaches 115° within 3 s from rest inside every joint limit; claims vs independent simulations."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from planners.cartpole import rhs
from planners.pendulum import SampledAcceleration
from planners.swingup import SwingUpRequest
from planners import swingup_fast
from planners.swingup_fast import FastParams, FastProblem, SearchSettings, optimise, simulate_fast
from planners.swingup_plan import StopProfile, TaskBounds
from trajectories.check import check_trajectory
from trajectories.differences import derivatives

from tests.helpers.shared import shared_swing_up

THETA_D = math.radians(115)


@pytest.fixture(scope="module")
def fast(robot, limits, tmp_path_factory):
    # the request of the tutorial's `lbr plan swing-up --method fast … --side +y`: planned once per run for both
    request = SwingUpRequest(length=0.25, mass=0.0139, theta_d=THETA_D, method="fast", side=1)
    return shared_swing_up(tmp_path_factory)(request, robot, limits)


@pytest.mark.heavy
def test_reaches_115_deg_from_rest_within_3_s(fast):
    ver = fast.verification
    k = int(np.flatnonzero(np.abs(ver.theta) >= THETA_D)[0])
    assert ver.t[k] < 3.0
    assert ver.theta[0] == 0.0 and fast.plan.theta_dot[0] == 0.0  # from the ball at rest
    assert fast.reached and fast.failure() is None


@pytest.mark.heavy  # the module's fast plan: an optimisation of many seconds
def test_inside_all_joint_limits_including_jerk(fast, limits):
    rep = check_trajectory(fast.trajectory, limits, jerk=True)
    assert rep.ok, [v.describe() for v in rep.violations]
    for q, r in rep.ratios().items():
        assert r.max() < 1.0, q
    # the bounds are really used (not a trivially slow plan)
    assert rep.ratios()["acceleration"].max() > 0.5


@pytest.mark.heavy  # the module's fast plan: an optimisation of many seconds
def test_pivot_stays_in_the_band_on_base_y_and_ends_at_rest(fast, robot):
    pos, _ = robot.fk_path(fast.trajectory.q)
    start = pos[0]
    assert np.abs(pos[:, 1] - start[1]).max() <= 0.3
    assert np.abs(pos[:, [0, 2]] - start[[0, 2]]).max() < 1e-6
    tail = fast.trajectory.t >= fast.plan.t_rest
    assert tail.sum() > 10
    qd = derivatives(fast.trajectory.q, fast.trajectory.dt, 1)[0]
    assert np.abs(qd[-5:]).max() < 1e-6  # the arm ends at rest (its null-space motion has settled too)
    assert np.abs(qd[tail]).max() < 1e-2
    assert np.ptp(pos[tail, 1]) < 1e-9  # the pivot rests from t_rest on


@pytest.mark.heavy  # the module's fast plan: an optimisation of many seconds
def test_claim_agrees_with_the_ball_simulated_under_the_joint_path(fast):
    ver, plan = fast.verification, fast.plan
    taut = ver.t < ver.first_slack  # the planar claim holds while the real (one-sided) string is taut
    assert taut.sum() > 100
    assert np.abs(ver.theta[taut] - plan.theta[taut]).max() < math.radians(3)
    assert fast.figures()["claimed"]["max_theta_difference_deg"] < 3
    # and with an independent planar integration of the written pivot samples
    acc = SampledAcceleration(plan.t, np.column_stack([0 * plan.x, plan.x, 0 * plan.x]))
    sol = solve_ivp(
        lambda t, y: rhs(y, acc(t)[1], 0.25),
        (0, plan.t[-1]),
        [0, 0, 0, 0],
        method="LSODA",
        t_eval=plan.t,
        rtol=1e-10,
        atol=1e-12,
        max_step=plan.dt,
    )
    assert np.abs(sol.y[2] - plan.theta).max() < math.radians(1)


@pytest.mark.heavy  # the module's fast plan: an optimisation of many seconds
def test_reports_slack_honestly(fast):
    figures = fast.figures()
    assert figures["taut"] is False and figures["first_slack_s"] is not None
    # the string goes slack near the top of the swing, past 90°, where the taut angle stops: the ball then flies
    k = np.searchsorted(fast.verification.t, figures["first_slack_s"])
    assert abs(fast.verification.theta[k]) > math.radians(90)
    assert 90 < figures["max_taut_theta_deg"] <= figures["max_theta_deg"]
    assert np.isnan(fast.verification.tension[k + 1])  # no tension in a slack string


@pytest.mark.heavy
def test_taut_constraint_gives_the_highest_taut_angle():
    bounds = TaskBounds(v_max=0.8, a_max=3.9, j_max=25.0)
    problem = FastProblem(length=0.25, theta_d=THETA_D, bounds=bounds, taut=True)
    params, outcome = optimise(problem, SearchSettings(popsize=6, maxiter=12, workers=2))
    plan = simulate_fast(problem, params)
    # taut means taut until θ_d is reached (FastProblem.taut), or short of it until the highest angle
    end = outcome.t_reach if outcome.t_reach is not None else plan.t[int(np.argmax(np.abs(plan.theta)))]
    assert plan.tension[plan.t <= end].min() >= problem.min_tension
    assert math.radians(75) < plan.max_theta
    assert (outcome.t_reach is None) == (plan.max_theta < plan.reach_angle)


def test_stop_profile_reaches_rest_within_the_bounds():
    b = TaskBounds(v_max=0.8, a_max=4.0, j_max=30.0)
    stop = StopProfile(0.5, 3.0, b)  # still accelerating: v peaks at 0.5 + 3²/(2·30) = 0.65
    tau = np.linspace(0, stop.duration + 0.1, 2001)
    x, v, a = stop.at(tau)
    assert v[-1] == 0.0 and a[-1] == 0.0
    assert np.abs(a).max() <= b.a_max + 1e-9 and np.abs(v).max() <= b.v_max + 1e-9
    jerk = np.diff(a) / np.diff(tau)
    assert np.abs(jerk).max() <= b.j_max * 1.001
    assert stop.distance == pytest.approx(x[-1]) and stop.distance > 0


def test_candidates_are_picklable():
    import pickle

    problem = FastProblem(length=0.25, theta_d=THETA_D, bounds=TaskBounds(0.8, 3.9, 25.0))
    again = pickle.loads(pickle.dumps((problem, FastParams())))
    assert again == (problem, FastParams())


# -- the compiled pendulum step (planners._planar) against the pure-Python one: the same values to the last bit, and
# the fallback taken when the extension is not built

_compiled = pytest.mark.skipif(swingup_fast._planar is None, reason="planners._planar not built (no C compiler)")


@_compiled
def test_compiled_step_equals_python_to_the_last_bit() -> None:
    rng = np.random.default_rng(11)
    for _ in range(2000):  # beyond the swing-up's range: loops, hard pivot accelerations, steps either way
        th, om = rng.uniform(-7.0, 7.0), rng.uniform(-30.0, 30.0)
        a0, a1 = rng.uniform(-40.0, 40.0, 2)
        h, length = float(rng.choice([0.005, 0.001, -0.002, 0.0125])), rng.uniform(0.05, 2.0)
        assert swingup_fast.planar_rk4(np.float64(th), om, a0, a1, h, length) == swingup_fast.planar_rk4_py(
            th, om, float(a0), float(a1), h, length
        )
    with pytest.raises(TypeError):
        swingup_fast._planar.rk4(0.1, 0.0, 0.0, 0.0, 0.005, 0.3)
    with pytest.raises(TypeError):
        swingup_fast._planar.rk4("0.1", 0.0, 0.0, 0.0, 0.005, 0.3, 9.81)


def test_search_without_the_extension_finds_the_same_swing_up(monkeypatch: pytest.MonkeyPatch) -> None:
    bounds = TaskBounds(1.0, 6.0, 60.0)
    problem = FastProblem(
        length=0.3, theta_d=math.radians(100), bounds=bounds, travel=0.3, horizon=3.0, band=(0.97, 1.03)
    )
    params = FastParams(0.8, 0.6, 1.0, 0.0)
    compiled = simulate_fast(problem, params)
    monkeypatch.setattr(swingup_fast, "_planar", None)
    pure = simulate_fast(problem, params)
    assert np.array_equal(compiled.theta, pure.theta) and np.array_equal(compiled.x, pure.x)
    assert np.array_equal(compiled.info["band"]["theta"], pure.info["band"]["theta"])  # the band's strings too
    th, om = swingup_fast.planar_rk4(1e-3, 0.0, 0.0, 0.0, 0.001, 0.3)  # small swing at rest: θ₀ cos(ω t)
    assert abs(th - 1e-3 * math.cos(math.sqrt(9.81 / 0.3) * 0.001)) < 1e-12 and om < 0.0
    assert pure.max_theta > math.radians(30)  # it swings up (not a trivial run)
