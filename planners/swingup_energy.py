"""Swing-up by energy shaping (thesis §5.2–5.3): u = k_E·θ̇·cos θ·(E − E_d) − k_p·x − k_d·ẋ.

E is in joules exactly as the thesis writes it (E = ½ m l² θ̇² − m g l cos θ, so k_E acts on m). The closed
loop is integrated with scipy's solve_ivp (events: |θ| reaching θ_d − tolerance, terminal; the string going
slack, recorded), the pivot is then brought to rest by a jerk-limited stop, and everything is sampled at the
FRI period. Energy shaping approaches θ_d asymptotically, hence the tolerance: pumping ends when |θ| first
reaches θ_d − tolerance/2; θ_d counts as reached from θ_d − tolerance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from trajectories.errors import PlanningError

from .cartpole import desired_energy, energy, rhs
from .pendulum import G, natural_period
from .swingup_plan import PivotPlan, StopProfile, TaskBounds, first_reach, time_grid
from .tension import tension_margin


@dataclass(frozen=True)
class EnergyParams:
    """Thesis energy-shaping swing-up: string, target, gains and integration settings."""

    length: float  # [m]
    mass: float  # [kg]
    theta_d: float  # [rad] desired apex
    k_e: float = 1.7  # [1/(J·s)·m/s² per rad/s] energy gain, thesis example
    k_p: float = 0.05  # [1/s²]
    k_d: float = 0.05  # [1/s]
    theta0: float = 0.0  # [rad] initial ball angle
    theta_dot0: float = 0.0  # [rad/s] initial ball rate
    push: float = 0.0  # [m/s²] amplitude of a one-period sine start push at the natural period (0: none)
    duration: float = 60.0  # [s] longest pumping time before giving up
    dt: float = 0.005  # [s] output sample step (FRI period)
    tolerance: float = math.radians(2.0)  # [rad] θ_d counts as reached at θ_d − tolerance; the plan aims at
    # θ_d − tolerance/2 so that the robot's realisation lands inside the band
    rtol: float = 1e-9
    atol: float = 1e-11


def push_acceleration(t: float, peak: float, length: float) -> float:
    """Start push [m/s²]: peak·sin(2π t/T0) for one natural period T0, zero afterwards.

    Resonant, and it leaves the pivot at rest (zero net velocity), displaced by peak·T0²/(2π).
    """
    t0 = natural_period(length)
    return peak * math.sin(2.0 * math.pi * t / t0) if 0.0 <= t < t0 else 0.0


def control(p: EnergyParams, t: float, state: np.ndarray, e_d: float) -> float:
    """Pivot acceleration u [m/s²] of the thesis law (5.6) plus the optional start push."""
    x, v, th, om = state
    e = energy(th, om, p.length, p.mass)
    u = p.k_e * om * math.cos(th) * (e - e_d) - p.k_p * x - p.k_d * v
    return u + (push_acceleration(t, p.push, p.length) if p.push else 0.0)


def plan_energy(p: EnergyParams, bounds: TaskBounds) -> PivotPlan:
    """Integrate the thesis law until θ_d (− tolerance) or ``duration``, then stop the pivot within ``bounds``.

    Raises PlanningError when the ball starts at exact rest without a push (the law gives u ≡ 0).
    """
    if p.theta0 == 0.0 and p.theta_dot0 == 0.0 and p.push == 0.0:
        raise PlanningError(
            "from exact rest the energy law produces no motion (θ = θ̇ = 0 gives u = 0); "
            "start from a small angle (EnergyParams.theta0, e.g. 0.1 rad) or give a start push (EnergyParams.push, "
            "e.g. 0.5 m/s²)"
        )
    e_d = desired_energy(p.theta_d, p.length, p.mass)
    reach_angle = p.theta_d - p.tolerance
    l = p.length
    pump = _pump(p, e_d)
    t_sw = float(pump.t[-1])
    y_sw = pump.y[:, -1]
    stop = StopProfile(y_sw[1], control(p, t_sw, y_sw, e_d), bounds)
    t_end = t_sw + stop.duration + 0.5 * natural_period(l)
    coast = _coast(p, stop, t_sw, y_sw, t_end)

    t = time_grid(t_end, p.dt)
    before = t <= t_sw
    states = np.empty((4, t.size))
    states[:, before] = pump.sol(t[before])
    states[:, ~before] = coast.sol(np.minimum(t[~before], t_end))
    u = np.empty(t.size)
    u[before] = [control(p, tk, states[:, k], e_d) for k, tk in enumerate(t[before])]
    disp, vel, acc = stop.at(t[~before] - t_sw)
    states[0, ~before] = y_sw[0] + disp
    states[1, ~before] = vel
    u[~before] = acc
    theta, theta_dot = states[2], states[3]
    slack_times = pump.t_events[1]
    return PivotPlan(
        method="energy",
        t=t,
        x=states[0],
        v=states[1],
        u=u,
        theta=theta,
        theta_dot=theta_dot,
        tension=tension_margin(theta, theta_dot, u, 0.0, l),
        theta_d=p.theta_d,
        reach_angle=reach_angle,
        t_reach=first_reach(t, theta, reach_angle),
        t_rest=t_sw + stop.duration,
        info={
            "t_switch_s": t_sw,
            "first_slack_s": float(slack_times[0]) if slack_times.size else None,
            "desired_energy_j": e_d,
            "g": G,
        },
    )


def _pump(p: EnergyParams, e_d: float):
    """The energy law integrated from the start state until |θ| reaches the aim (θ_d − tolerance / 2) or
    ``duration``: the solve_ivp solution (dense), with the slack events (tension ≤ 0) as its second event."""
    from scipy.integrate import solve_ivp

    aim = p.theta_d - 0.5 * p.tolerance
    l = p.length

    def f(t, y):
        return rhs(y, control(p, t, y, e_d), l)

    def reach(t, y):
        return abs(y[2]) - aim

    reach.terminal, reach.direction = True, 1.0

    def slack(t, y):
        return tension_margin(y[2], y[3], control(p, t, y, e_d), 0.0, l)

    slack.terminal, slack.direction = False, -1.0

    y0 = np.array([0.0, 0.0, p.theta0, p.theta_dot0])
    pump = solve_ivp(
        f,
        (0.0, p.duration),
        y0,
        method="DOP853",
        events=(reach, slack),
        dense_output=True,
        rtol=p.rtol,
        atol=p.atol,
        max_step=min(0.02, p.dt),
    )
    if pump.status < 0:
        raise PlanningError(f"energy-shaping integration failed: {pump.message}")
    return pump


def _coast(p: EnergyParams, stop: StopProfile, t_sw: float, y_sw: np.ndarray, t_end: float):
    """The pendulum while the pivot follows ``stop`` from ``t_sw`` [s] (state ``y_sw``) until ``t_end`` [s]: the
    solve_ivp solution (dense)."""
    from scipy.integrate import solve_ivp

    l = p.length

    def g(t, y):
        return rhs(y, float(stop.at(t - t_sw)[2][0]), l)

    coast = solve_ivp(
        g, (t_sw, t_end), y_sw, method="DOP853", dense_output=True, rtol=p.rtol, atol=p.atol, max_step=min(0.02, p.dt)
    )
    if coast.status < 0:
        raise PlanningError(f"energy-shaping integration failed while stopping: {coast.message}")
    return coast
