"""The upright session over the band of issue #33 on the fast simulation, and a few cases on the FRI simulator.

Fast simulation (``planners.feedback.simulate.simulate_session``: RK4 plant, 12-bit encoder sampled at 200 Hz,
delayed and jittered, the cart on the arm's own rail bounds at the thesis start pose): the controller assumes the CLI's
default rod (0.5 m uniform, 0.1 kg); the plant's rod is 0.8 / 1.0 / 1.2 × as long, with or without a 20 g tip mass
(not a uniform rod: the model's inertia is wrong, only the identification can find the equivalent length), 5 % dry
friction of its peak gravity torque or none, ±2 counts of encoder noise, a zero offset, 5 or 15 ms of encoder
delay, 2 or 6 cycles of actuation delay; 60 s hold with a 10° push 20 s after the catch. Figures: cases that
succeeded, falls, swing-up time, the largest angle from upright 2 s after the catch (before the push), after the
push, and whether the cart stayed on the rail.

Off the band's grid (``--parts off``, :func:`off_band_cases`): rods 0.75 and 1.25 × with and without the tip mass,
5 % friction, 8 ms of jitter on 5 or 15 ms of delay, 3 or 5 cycles of actuation delay, knocks of ±10° at other times.

A second judge, built to differ (:class:`StribeckRod`, not ``planners.rigid_pendulum``): the rod's bearing has
Stribeck friction — kinetic 3, 5 or 7 % of the peak gravity torque, static 1.3 × that below 0.05 rad/s, plus viscous —
integrated by scipy's adaptive ``solve_ivp`` (RK45) over every cycle instead of one RK4 step; rods 0.85 / 1.15 × the
model's length with the rod's mass 20 % off, with and without a 15 g tip; 8 or 12 ms of delay with 2 ms of jitter,
4 cycles of actuation delay, seeds the band does not use, and pushes of ±10° at times that are no whole number of
seconds after the catch (so that they meet the balance's 3 Hz dither at other phases than the band's).

The band's last corner (``--parts corner``, :func:`corner_cases`): the 1.2 × rod with a 20 g tip, 5 % friction and 15
ms of delay under another plant — :class:`StribeckRod` stepped by the explicit midpoint rule (neither the band's RK4
nor the judge's RK45), the rod's mass ±20 % — with knocks in both directions, 3 s after the catch, twice in one run,
and beyond the band (1.25 ×, 12°, 20 ms); and :func:`rail_travel_floor`, the knock's travel floor within the rail's
own speed-dependent bounds: why the rail (``lbr control upright``'s default ``--travel``, read from the command) is
longer than ±0.3 m.

FRI simulator (``lbr control upright --sim-lockstep``, the real arm model, the module's serial lines on a pty): the
nominal rod and the rod 20 % short and long with friction and noise, 10 ms of delay, and those rods again 15 ms
(+ 3 ms of jitter) and 5 ms (+ 8 ms) late; 60 s hold and the push.

``python benchmarks/bench_upright_band.py [--quick] [--parts fast,off,corner,fri,judge] [--processes N]`` writes
benchmarks/results/upright_band.json and benchmarks/results/upright_band.md (the docs' page) after each part it runs
(the parts not run keep what the file had; each part is stamped with its date and commit; ``--quick`` writes
nothing: a smoke run). The judge is the slowest part (scipy's RK45 over every 1 ms cycle, ≈ 2 min of CPU a case).
"""

from __future__ import annotations

import itertools
import json
import math
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from multiprocessing import Pool
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
NOMINAL_ROD = 0.5  # [m] lbr control upright's default --rod-length
HOLD_S = 60.0  # [s]
PUSH_AFTER_S = 20.0  # [s] after the catch
PUSH_DEG = 10.0

_RAIL = None


def _rail():
    global _RAIL
    if _RAIL is None:
        from planners.rail import build_rail
        from planners.swingup import THESIS_Q_START
        from trajectories.limits import default_limits
        from trajectories.robot import Robot

        _RAIL = build_rail(
            Robot(), THESIS_Q_START, default_limits(), cli_travel()
        )  # lbr control upright's default rail
    return _RAIL


def cli_travel() -> float:
    """``lbr control upright``'s default ``--travel`` [m] (read from the command, not typed here)."""
    import inspect

    from lbrcli.commands.control import upright

    return float(inspect.signature(upright).parameters["travel"].default)


def fast_case(args: tuple) -> dict:
    """One case of the band: (rod ×, tip [kg], dry friction share, delay [s], actuation [cycles], seed), and for the
    off-band cases also the jitter [s], the push's time after the catch [s] and its angle [deg]."""
    from planners.feedback.session import SessionOptions
    from planners.feedback.simulate import Sensor, simulate_session
    from planners.rigid_pendulum import RigidPendulum

    scale, tip, friction, delay, actuation, seed, *more = args
    jitter, push_s, push_deg = more or (0.001, PUSH_AFTER_S, PUSH_DEG)
    rail = _rail()
    shape = RigidPendulum(rod_length=NOMINAL_ROD * scale, tip_mass=tip)
    rod = RigidPendulum(rod_length=NOMINAL_ROD * scale, tip_mass=tip,
                        coulomb=friction * shape.mass * shape.com * 9.81)  # fmt: skip
    model = RigidPendulum(rod_length=NOMINAL_ROD)
    run = simulate_session(rod, rail.limits, model.equivalent_length, SessionOptions(hold_s=HOLD_S),
                           Sensor(noise=2, delay=delay, jitter=jitter, offset=17 * (seed + 1)), actuation_delay=actuation,
                           seed=seed, pushes=((push_s, math.radians(push_deg)),), bounds=rail.local_bounds)  # fmt: skip
    s = run.session
    t = np.asarray(run.t)
    up = np.degrees(np.abs(np.angle(np.exp(1j * (np.asarray(run.phi) - np.pi)))))
    bal = np.array([p == "balance" for p in run.phase])
    out = dict(scale=scale, tip_kg=tip, friction=friction, delay_ms=delay * 1e3, actuation_cycles=actuation, seed=seed,
               succeeded=bool(s.succeeded), falls=int(s.falls), swing_up_s=s.swing_up_s,
               on_rail=bool(np.all(np.abs(np.asarray(run.x)) <= rail.limits.travel + 1e-9)), verdict=s.verdict)  # fmt: skip
    if more:
        out.update(jitter_ms=jitter * 1e3, push_s=push_s, push_deg=push_deg)
    if bal.any():
        t_catch = t[np.flatnonzero(bal)[0]]
        before = bal & (t > t_catch + 2.0) & (t < t_catch + push_s)
        after = bal & (t > t_catch + push_s + 3.0)
        out["max_up_deg_settled"] = float(up[before].max()) if before.any() else None
        out["max_up_deg_after_push"] = float(up[after].max()) if after.any() else None
        pushed = (t > t_catch + push_s) & (t < t_catch + push_s + 4.0)
        out["max_cart_m_after_push"] = float(np.abs(np.asarray(run.x))[pushed].max()) if pushed.any() else None
    return out


def off_band_cases() -> list[tuple]:
    """Cases off the band's grid: rods 0.75 and 1.25 × (with and without the tip mass), 5 % friction, 8 ms of
    jitter on 5 or 15 ms of delay, 3 or 5 cycles of actuation delay, other seeds, knocks of ±10° at other times."""
    out = []
    for i, (scale, tip, delay) in enumerate(itertools.product((0.75, 1.25), (0.0, 0.02), (0.005, 0.015))):
        out.append((scale, tip, 0.05, delay, 3 + 2 * (i % 2), 50 + i, 0.008, round(14.7 + 1.3 * i, 2),
                    PUSH_DEG if i % 3 else -PUSH_DEG))  # fmt: skip
    return out


@dataclass(frozen=True)
class StribeckRod:
    """The judge's rod: uniform, ``rod_mass`` [kg] over ``rod_length`` [m] with ``tip_mass`` [kg] at its end, on a
    bearing with Stribeck friction — ``kinetic`` share of the peak gravity torque, ``static_ratio`` × that at rest
    (fading with rate ``stribeck`` [rad/s]), smoothed over ``smooth`` [rad/s] — and viscous [N·m·s/rad]."""

    rod_length: float
    rod_mass: float
    tip_mass: float
    kinetic: float
    static_ratio: float = 1.3
    stribeck: float = 0.05
    smooth: float = 0.005
    viscous: float = 5e-4

    def acceleration(self, phi: float, omega: float, a: float) -> float:
        """φ̈ [rad/s²] with the pivot accelerating at a [m/s²] along the swing's plane."""
        ml = self.rod_mass * self.rod_length / 2 + self.tip_mass * self.rod_length  # [kg·m]
        inertia = self.rod_mass * self.rod_length**2 / 3 + self.tip_mass * self.rod_length**2  # [kg·m²]
        dry = self.kinetic * ml * 9.81
        fric = (dry * (1.0 + (self.static_ratio - 1.0) * math.exp(-((omega / self.stribeck) ** 2)))
                * math.tanh(omega / self.smooth) + self.viscous * omega)  # fmt: skip
        return (-ml * (9.81 * math.sin(phi) + a * math.cos(phi)) - fric) / inertia

    def step(self, phi: float, omega: float, a0: float, a1: float, h: float) -> tuple[float, float]:
        """(φ, φ̇) after ``h`` [s] with the pivot's acceleration going linearly from a0 to a1: scipy's RK45."""
        from scipy.integrate import solve_ivp

        def f(t: float, y: np.ndarray) -> tuple[float, float]:
            return y[1], self.acceleration(y[0], y[1], a0 + (a1 - a0) * t / h)

        r = solve_ivp(f, (0.0, h), (phi, omega), method="RK45", rtol=1e-6, atol=1e-8)
        return float(r.y[0, -1]), float(r.y[1, -1])

    def midpoint(self, phi: float, omega: float, a0: float, a1: float, h: float) -> tuple[float, float]:
        """As :meth:`step` by the explicit midpoint rule in 4 steps of h/4: another integrator than the band's RK4
        and the judge's RK45 (stable here: the friction's stiffest slope times h/4 is below 0.1)."""
        k = h / 4
        for i in range(4):
            t = i * k
            w_dot = self.acceleration(phi, omega, a0 + (a1 - a0) * t / h)
            pm, wm = phi + 0.5 * k * omega, omega + 0.5 * k * w_dot
            phi, omega = phi + k * wm, omega + k * self.acceleration(pm, wm, a0 + (a1 - a0) * (t + 0.5 * k) / h)
        return phi, omega


def judge_cases() -> list[tuple]:
    """(scale, rod mass [kg], tip [kg], kinetic share, delay [s], seed, push time [s], push [deg]) of the judge."""
    out = []
    for i, (kinetic, scale, tip) in enumerate(itertools.product((0.03, 0.05), (0.85, 1.15), (0.0, 0.015))):
        out.append((scale, 0.08 if scale < 1 else 0.12, tip, kinetic, 0.008 if i % 2 else 0.012, 10 + i,
                    round(21.3 + 0.61 * i, 2), 10.0 if i % 3 else -10.0))  # fmt: skip
    out += [(0.85, 0.08, 0.0, 0.07, 0.010, 30, 24.7, 10.0), (1.15, 0.12, 0.0, 0.07, 0.010, 31, 24.9, -10.0)]
    return out


def judge_case(args: tuple) -> dict:
    from planners.feedback.session import SessionOptions
    from planners.feedback.simulate import Sensor, simulate_session
    from planners.rigid_pendulum import RigidPendulum

    scale, mass, tip, kinetic, delay, seed, push_t, push = args
    rail = _rail()
    rod = StribeckRod(NOMINAL_ROD * scale, mass, tip, kinetic)
    run = simulate_session(None, rail.limits, RigidPendulum(rod_length=NOMINAL_ROD).equivalent_length,
                           SessionOptions(hold_s=HOLD_S), Sensor(noise=2, delay=delay, jitter=0.002, offset=-23 * seed),
                           actuation_delay=4, seed=seed, pushes=((push_t, math.radians(push)),),
                           bounds=rail.local_bounds, plant_step=rod.step)  # fmt: skip
    s = run.session
    f = s.figures()
    return dict(scale=scale, rod_mass_kg=mass, tip_kg=tip, kinetic=kinetic, delay_ms=delay * 1e3, seed=seed,
                push_s=push_t, push_deg=push, succeeded=bool(s.succeeded), falls=int(s.falls),
                on_rail=bool(np.all(np.abs(np.asarray(run.x)) <= rail.limits.travel + 1e-9)),
                identified_coulomb_share=f.get("identified_coulomb_share"), verdict=s.verdict or s.error)  # fmt: skip


def corner_cases() -> list[tuple]:
    """The band's last corner under another plant (:func:`corner_case`): (rod ×, rod mass [kg], tip [kg], kinetic
    share, delay [s], actuation [cycles], seed, knocks ((t after the catch [s], [deg]), ...)) — the corner (1.2 ×, a
    20 g tip, 5 % friction, 15 ms) with the rod's mass ±20 %, both knock directions, knocks 3 s after the catch
    (the dither still ramping), two knocks in one run, and beyond the band: a 1.25 × rod, a 12° knock, 20 ms."""
    return [(1.2, 0.10, 0.02, 0.05, 0.015, 2, 70, ((20.0, 10.0),)),
            (1.2, 0.10, 0.02, 0.05, 0.015, 6, 71, ((20.0, -10.0),)),
            (1.2, 0.12, 0.02, 0.05, 0.015, 4, 72, ((3.0, 10.0),)),
            (1.2, 0.08, 0.02, 0.05, 0.015, 4, 73, ((12.35, -10.0), (31.1, 10.0))),
            (1.25, 0.10, 0.02, 0.05, 0.015, 2, 74, ((20.0, 10.0),)),
            (1.25, 0.12, 0.02, 0.05, 0.015, 6, 75, ((27.77, -10.0),)),
            (1.2, 0.10, 0.02, 0.05, 0.015, 2, 76, ((20.0, 12.0),)),
            (1.2, 0.10, 0.02, 0.05, 0.020, 2, 77, ((20.0, -10.0),))]  # fmt: skip


def corner_case(args: tuple) -> dict:
    """One :func:`corner_cases` case: the :class:`StribeckRod` (static friction 1.3 × the kinetic) stepped by the
    explicit midpoint rule, ±2 counts of noise, 2 ms of jitter; the largest excursion in the 4 s after each knock."""
    from planners.feedback.session import SessionOptions
    from planners.feedback.simulate import Sensor, simulate_session
    from planners.rigid_pendulum import RigidPendulum

    scale, mass, tip, kinetic, delay, actuation, seed, knocks = args
    rail = _rail()
    rod = StribeckRod(NOMINAL_ROD * scale, mass, tip, kinetic)
    pushes = tuple((t, math.radians(deg)) for t, deg in knocks)
    run = simulate_session(None, rail.limits, RigidPendulum(rod_length=NOMINAL_ROD).equivalent_length,
                           SessionOptions(hold_s=HOLD_S), Sensor(noise=2, delay=delay, jitter=0.002, offset=11 * seed),
                           actuation_delay=actuation, seed=seed, pushes=pushes, bounds=rail.local_bounds,
                           plant_step=rod.midpoint)  # fmt: skip
    s, t, x = run.session, np.asarray(run.t), np.abs(np.asarray(run.x))
    bal = np.flatnonzero(np.array([p == "balance" for p in run.phase]))
    after = []
    for t_k, _ in knocks:
        m = (t > t[bal[0]] + t_k) & (t < t[bal[0]] + t_k + 4.0) if bal.size else np.zeros(len(t), bool)
        after.append(float(x[m].max()) if m.any() else None)
    return dict(scale=scale, rod_mass_kg=mass, tip_kg=tip, kinetic=kinetic, delay_ms=delay * 1e3,
                actuation_cycles=actuation, seed=seed, knocks=[list(k) for k in knocks], succeeded=bool(s.succeeded),
                falls=int(s.falls), on_rail=bool(np.all(x <= rail.limits.travel + 1e-9)), excursion_after_m=after,
                swing_up_s=s.swing_up_s, verdict=s.verdict or s.error)  # fmt: skip


def fri_case(sim_scale: float, friction: float, noise: int, delay_ms: float = 10.0, jitter_ms: float = 0.0) -> dict:
    """``lbr control upright --sim-lockstep`` with the simulated rod ``sim_scale`` × the default, the module's lines
    ``delay_ms`` + up to ``jitter_ms`` [ms] late."""
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "up.csv"
        cmd = [sys.executable, "-m", "lbrcli", "control", "upright", "--sim-lockstep", "--hold", str(HOLD_S),
               "--sim-rod-length", f"{NOMINAL_ROD * sim_scale:g}", "--sim-friction", str(friction), "--sim-noise",
               str(noise), "--sim-delay", f"{delay_ms:g}", "--sim-jitter", f"{jitter_ms:g}", "--push", f"{PUSH_DEG:g}deg@40", "--log", str(log), "--json"]  # fmt: skip
        t0 = time.perf_counter()
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=900, cwd=ROOT)
        wall = time.perf_counter() - t0
        fig = json.loads(p.stdout) if p.stdout.strip().startswith("{") else {}
        out = dict(sim_scale=sim_scale, friction=friction, noise=noise, delay_ms=delay_ms, jitter_ms=jitter_ms,
                   exit_code=p.returncode, wall_s=round(wall, 1),
                   falls=fig.get("falls"), swing_up_s=fig.get("swing_up_s"),
                   longest_balance_s=fig.get("longest_balance_s"), verdict=fig.get("verdict"),
                   outcome=fig.get("outcome"), reason=fig.get("reason"), detail=fig.get("detail"),
                   stderr_tail=p.stderr.strip().splitlines()[-3:])  # fmt: skip
        if log.exists():
            import csv

            with open(log, newline="") as fh:
                rows = list(csv.reader(fh))
            col = {name: i for i, name in enumerate(rows[0])}
            data = np.array([[float(r[col[c]]) for c in ["state"] + [f"cmd_q{j}" for j in range(1, 8)]]
                             for r in rows[1:]])  # fmt: skip
            q = data[data[:, 0] == 4, 1:]
            from trajectories.limits import default_limits

            lim = default_limits()
            out["max_velocity_share"] = float((np.abs(np.diff(q, axis=0)) / 1e-3 / lim.velocity).max())
            out["max_acceleration_share"] = float((np.abs(np.diff(q, 2, axis=0)) / 1e-6 / lim.acceleration).max())
    return out


def push_travel_floor(length: float, share: float, accel: float, jerk: float, push_deg: float = PUSH_DEG,
                      horizon: float = 3.0, step: float = 0.01) -> float | None:  # fmt: skip
    """The least largest |x| [m] over which any cart with |a| ≤ ``accel`` [m/s²] and |jerk| ≤ ``jerk`` [m/s³] brings a
    rod of equivalent ``length`` [m], knocked ``push_deg`` from upright at rest, back to rest upright within
    ``horizon`` [s] (linear model; a linear programme, scipy's HiGHS). The bearing's dry friction (``share`` of the
    gravity torque) opposes the rod's rate along the plan: fixed-point passes on its sign (the plan with the larger
    excursion of the last two is kept). None when infeasible."""
    from scipy.linalg import expm
    from scipy.optimize import linprog

    from planners.feedback.lqr import cart_pendulum

    a, b = cart_pendulum(length, True)
    n = int(round(horizon / step))
    m = np.zeros((7, 7))
    m[:5, :5], m[:5, 5], m[4, 6] = a, b[:, 0], 1.0
    e = expm(m * step)
    ad, bd, dd = e[:5, :5], e[:5, 5], e[:5, 6]
    powers = [np.eye(5)]
    for _ in range(n):
        powers.append(ad @ powers[-1])
    cols = np.array([p @ bd for p in powers[:n]])  # (n, 5): a jerk held over step i seen k − i steps later
    z0 = np.array([0.0, 0.0, 0.0, math.radians(push_deg), 0.0])
    mu = share * 9.81 / length

    def solve(d: np.ndarray) -> tuple[float, np.ndarray] | None:
        rows_ub, rhs_ub, free, states = [], [], np.zeros(5), []
        for k in range(1, n + 1):
            s_k = np.zeros((5, n))
            s_k[:, :k] = cols[k - 1 :: -1][:k].T
            free = ad @ free + dd * d[k - 1]
            f_k = powers[k] @ z0 + free
            states.append((s_k, f_k))
            for row, lo, hi in ((0, None, None), (2, -accel, accel)):
                if lo is None:  # |x| ≤ s
                    rows_ub += [np.r_[s_k[0], -1.0], np.r_[-s_k[0], -1.0]]
                    rhs_ub += [-f_k[0], f_k[0]]
                else:
                    rows_ub += [np.r_[s_k[row], 0.0], np.r_[-s_k[row], 0.0]]
                    rhs_ub += [hi - f_k[row], f_k[row] - lo]
        s_n, f_n = states[-1]
        res = linprog(np.r_[np.zeros(n), 1.0], A_ub=np.array(rows_ub), b_ub=np.array(rhs_ub),
                      A_eq=np.c_[s_n, np.zeros(5)], b_eq=-f_n, bounds=[(-jerk, jerk)] * n + [(0, None)],
                      method="highs")  # fmt: skip
        if res.status != 0:
            return None
        rate = np.array([s_k[4] @ res.x[:n] + f_k[4] for s_k, f_k in states])
        return float(res.x[-1]), rate

    out = solve(np.zeros(n))
    best: list[float] = []
    for _ in range(6):
        if out is None:
            return None
        best.append(out[0])
        rate = out[1]
        out = solve(np.where(np.abs(rate) > 0.02, -mu * np.sign(rate), 0.0))
    return max(best[-2:])


def _knock_model(length: float, n: int, step: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """z_k = P_k·z0 + G_k·u + D_k·d, k = 1..n, of the upright linear model (planners.feedback.lqr) with the jerk u and
    a friction acceleration d of the rod held over each ``step`` [s]: P (n, 5, 5), G and D (n, 5, n)."""
    from scipy.linalg import expm

    from planners.feedback.lqr import cart_pendulum

    a, b = cart_pendulum(length, True)
    m = np.zeros((7, 7))
    m[:5, :5], m[:5, 5], m[4, 6] = a, b[:, 0], 1.0
    e = expm(m * step)
    ad, bd, dd = e[:5, :5], e[:5, 5], e[:5, 6]
    p, g, d = np.empty((n, 5, 5)), np.zeros((n, 5, n)), np.zeros((n, 5, n))
    pk = np.eye(5)
    for k in range(n):
        pk = ad @ pk
        p[k] = pk
        if k:
            g[k, :, :k], d[k, :, :k] = ad @ g[k - 1, :, :k], ad @ d[k - 1, :, :k]
        g[k, :, k], d[k, :, k] = bd, dd
    return p, g, d


def rail_travel_floor(length: float, share: float, bounds, push_deg: float = PUSH_DEG, horizon: float = 3.0,
                      step: float = 0.01, passes: int = 12) -> list[float] | None:  # fmt: skip
    """As :func:`push_travel_floor` from rest at the rail's centre, but within the rail's own bounds where the plan
    takes the cart: ``bounds(x, v, a)`` (:meth:`planners.rail.Rail.local_bounds` — the acceleration bound shrinks with
    the speed, which a constant bound leaves out). The bounds and the friction's sign are taken along the previous
    plans (a sequential linear programme, started from 0.6 × the bounds at rest; it does not settle on one plan):
    [least, largest] excursion [m] of the last 4 passes' plans that keep the rail's bounds along themselves (within
    2 %), or None."""
    from scipy.optimize import linprog

    n = int(round(horizon / step))
    p, g, d = _knock_model(length, n, step)
    z0 = np.array([0.0, 0.0, 0.0, math.radians(push_deg), 0.0])
    mu = share * 9.81 / length
    one, zero = np.ones((n, 1)), np.zeros((n, 1))
    a_ub = np.vstack([np.hstack(b) for b in ((g[:, 0], -one), (-g[:, 0], -one), (g[:, 1], zero), (-g[:, 1], zero),
                                             (g[:, 2], zero), (-g[:, 2], zero))])  # fmt: skip
    along, found = np.repeat(z0[None], n, axis=0), []
    for k in range(passes):
        rate = along[:, 4]
        free = p @ z0 + d @ np.where(np.abs(rate) > 0.02, -mu * np.sign(rate), 0.0)
        b = np.array([bounds(float(z[0]), float(z[1]), float(z[2])) for z in along]) * (0.6 if k == 0 else 1.0)
        fx, fv, fa = free[:, 0], free[:, 1], free[:, 2]
        rhs = np.concatenate([-fx, fx, b[:, 0] - fv, b[:, 0] + fv, b[:, 2] - fa, fa - b[:, 1]])
        jerk = float(min(-b[:, 3].max(), b[:, 4].min()))
        res = linprog(np.r_[np.zeros(n), 1.0], A_ub=a_ub, b_ub=rhs, A_eq=np.c_[g[-1], np.zeros(5)], b_eq=-free[-1],
                      bounds=[(-jerk, jerk)] * n + [(0, None)], method="highs")  # fmt: skip
        if res.status != 0:
            break
        new = free + g @ res.x[:n]
        own = np.array([bounds(float(z[0]), float(z[1]), float(z[2])) for z in new])
        if k >= passes - 4 and np.all(new[:, 2] <= 1.02 * own[:, 2]) and np.all(new[:, 2] >= 1.02 * own[:, 1]):
            found.append(float(np.abs(new[:, 0]).max()))
        along = new if k == 0 else 0.5 * (along + new)
    return [min(found), max(found)] if found else None


def knock_excursion(length: float, weights: tuple, friction: float, delay: float, limits, dt: float = 1e-3,
                    push: float = math.radians(PUSH_DEG), horizon: float = 3.0) -> float:  # fmt: skip
    """The cart's largest excursion [m] when a rod of equivalent ``length`` [m] with dry friction of ``friction`` of
    its gravity torque, balanced with the cart at rest at the rail's centre, is knocked by ``push`` [rad] — predicted
    by the balance's own closed loop (``planners.feedback``'s controller with LQR ``weights``, no dither; its observer
    fed a reading every 5 ms that arrives ``delay`` [s] late; commands acting 2 cycles late; the cart's governor on
    the constant ``limits``), not its linearisation; inf when the rod falls."""
    from dataclasses import replace

    from planners.feedback.cart import Cart
    from planners.feedback.observer import DelayedObserver
    from planners.feedback.upright import Mode, UprightController, UprightOptions, balance_gain

    options = replace(UprightOptions(), weights=tuple(weights))
    cart = Cart(limits, dt)
    ctl = UprightController(length, cart, options, balance_gain(length, options), reach=np.zeros((3, 1, 5)),
                            limit=math.inf)  # fmt: skip
    ctl.mode = Mode.BALANCE
    mu = friction * 9.81 / length
    obs = DelayedObserver(length, dt, delay, 0.005, actuation_delay=2, phi0=math.pi, coulomb=mu)
    lag, every = int(round(delay / dt)), int(round(0.005 / dt))
    seen, applied = [math.pi] * (lag + 1), [0.0] * 3  # rings: the true angle over the delay, the commands
    phi, omega, far = math.pi + push, 0.0, 0.0
    for k in range(int(round(horizon / dt))):
        a = applied[k % 3]
        omega += (-(9.81 * math.sin(phi) + a * math.cos(phi)) / length - mu * math.tanh(omega / 0.05)) * dt
        phi += omega * dt
        seen[k % len(seen)] = phi
        if k % every == 0:
            obs.correct(seen[(k + 1) % len(seen)])  # the angle ``lag`` cycles ago
        ctl.update(obs.phi, obs.omega)
        applied[k % 3] = cart.a
        obs.predict(cart.a)
        far = max(far, abs(cart.x))
        if ctl.mode is not Mode.BALANCE:
            return math.inf
    return far


def weight_scan(fast: list[dict]) -> list[dict]:
    """For the band's longer rods with 5 % friction: the knock's predicted excursion (:func:`knock_excursion`, the rail's
    bounds at its centre) with the fixed LQR weights against the measured one, and the least over a grid of 81 other
    weights (x, v, θ, θ̇ each over 3 values, 16 × apart): can any weights fit the knock's recovery into the rail?"""
    from planners.feedback.upright import UprightOptions
    from planners.rail import CartLimits
    from planners.rigid_pendulum import RigidPendulum

    rail = _rail()
    speed, _, a_hi, _, j_hi = rail.local_bounds(0.0, 0.0, 0.0)
    centre = CartLimits(rail.limits.travel, speed, a_hi, j_hi)
    fixed = UprightOptions().weights
    grid = [(x, v, fixed[2], t, w) for x, v, t, w in itertools.product((30, 120, 480), (10, 40, 160), (50, 200, 800),
                                                                        (1, 5, 20))]  # fmt: skip
    out = []
    for scale, tip, delay in ((1.0, 0.02, 0.015), (1.2, 0.0, 0.015), (1.2, 0.02, 0.005), (1.2, 0.02, 0.015)):
        length = RigidPendulum(rod_length=NOMINAL_ROD * scale, tip_mass=tip).equivalent_length
        sensor = delay + 0.0005  # the link's delay and half its jitter, as identified
        scanned = sorted((knock_excursion(length, w, 0.05, sensor, centre), w) for w in grid)
        measured = [r["max_cart_m_after_push"] for r in fast if (r["scale"], r["tip_kg"], r["friction"], r["delay_ms"])
                    == (scale, tip, 0.05, delay * 1e3) and r.get("max_cart_m_after_push") is not None]  # fmt: skip
        out.append(dict(scale=scale, tip_kg=tip, delay_ms=delay * 1e3,
                        fixed_m=knock_excursion(length, fixed, 0.05, sensor, centre),
                        fixed_no_friction_m=knock_excursion(length, fixed, 0.0, sensor, centre),
                        measured_m=[min(measured), max(measured)] if measured else None,
                        best_m=scanned[0][0], best_weights=list(scanned[0][1])))  # fmt: skip
    return out


def _summary(rows: list[dict], key: str) -> dict:
    """Cases, those balanced for the hold without a fall (on the rail), falls, per value of ``key``."""
    out = {}
    for value in sorted({r[key] for r in rows}):
        sel = [r for r in rows if r[key] == value]
        clean = [r for r in sel if r["succeeded"] and r["falls"] == 0 and r["on_rail"]]
        out[str(value)] = {"cases": len(sel), "without_fall": len(clean), "falls": sum(r["falls"] for r in sel)}
    return out


def _spread(rows: list[dict], friction: float, key: str) -> list[float] | None:
    """[median, max] of ``key`` over the cases with this friction that ran without a fall (None: no such case)."""
    values = [r[key] for r in rows if r["friction"] == friction and r["falls"] == 0 and r.get(key) is not None]
    return [float(np.median(values)), float(max(values))] if values else None


def write_page(result: dict, path: Path) -> None:
    """The docs' page of these figures (published as explanations/results/upright_band.md)."""
    lines = ["# Upright band (`python benchmarks/bench_upright_band.py`)", "",
             "The controller assumes the CLI's default rod (0.5 m uniform); every case "
             f"balances {HOLD_S:g} s and is knocked by 10° once. A case counts when the hold was met without a fall, "
             "the cart on the rail. Each part says when, and on which commit, it was measured (`--parts` runs some "
             "of them; a `+` after the commit: the work tree had changes).", ""]  # fmt: skip
    stamps = result.get("measured", {})

    def measured(part: str) -> list[str]:
        st = stamps.get(part)
        return ([f"Measured {st['date']} on commit {st['commit']}.", ""] if st else
                ["Measured by an earlier run that did not stamp its parts (no commit recorded).", ""])  # fmt: skip

    if "fast_by_friction" in result:
        lines += _fast_section(result, measured("fast"))
    if "fast_rerun" in result:
        lines += _rerun_section(result["fast_rerun"])
    if "off" in result:
        lines += _off_section(result, measured("off"))
    if "corner" in result:
        lines += _corner_section(result, measured("corner"))
    if "judge" in result:
        lines += _judge_section(result, measured("judge"))
    else:
        lines += ["## The second judge", "", "Not measured yet: `--parts judge`.", ""]
    if "fri" in result:
        lines += _fri_section(result, measured("fri"))
    tmp = path.with_suffix(".md.part")
    tmp.write_text("\n".join(lines) + "\n")
    tmp.replace(path)


def _fast_section(result: dict, head: list[str]) -> list[str]:
    f = result["fast_by_friction"]
    lines = ["## The band (fast simulation, RK4, dry friction)", "", *head,
             "| bearing's dry friction | cases | without a fall | falls |", "|---|---:|---:|---:|"]  # fmt: skip
    lines += [f"| {float(k):.0%} | {v['cases']} | {v['without_fall']} | {v['falls']} |" for k, v in f.items()]
    settled, travel = result["fast_settled_deg_by_friction"], result["fast_cart_m_after_push_by_friction"]
    lines += ["", f"Swing-up {result['fast_swing_up_s'][0]:.2f}–{result['fast_swing_up_s'][2]:.2f} s (median "
              f"{result['fast_swing_up_s'][1]:.2f} s). In the cases without a fall, median / largest over the cases:", "",
              "| bearing's dry friction | angle from upright, 2 s after the catch to the push [°] | the cart's excursion "
              f"in the 4 s after the push [m] (rail ±{result['rail_travel_m']:g} m) |", "|---|---:|---:|"]  # fmt: skip
    for k in settled:
        a, x = settled[k], travel[k]
        lines.append(f"| {float(k):.0%} | {'—' if a is None else f'{a[0]:.2f} / {a[1]:.2f}'} | "
                     f"{'—' if x is None else f'{x[0]:.3f} / {x[1]:.3f}'} |")  # fmt: skip
    if not result["fast_failures"]:
        lines += ["", "Every case counted (none fell, missed its hold or left the rail)."]
    else:
        lines += ["", "Cases that did not count (a fall, no hold, or off the rail):", "",
                  "| rod × | tip [kg] | friction | delay [ms] | actuation [cycles] | seed | falls | verdict |",
                  "|---:|---:|---:|---:|---:|---:|---:|---|"]  # fmt: skip
    lines += [f"| {r['scale']:g} | {r['tip_kg']:g} | {r['friction']:.0%} | {r['delay_ms']:g} | {r['actuation_cycles']} | "
              f"{r['seed']} | {r['falls']} | {r['verdict']} |" for r in result["fast_failures"]]  # fmt: skip
    lines += ["", "The travel floor of a 10° knock: the least largest excursion [m] any controller within the rail's bounds "
              "needs (linear model, dry friction along the plan; a linear programme — `push_travel_floor`):", "",
              "| rod × | tip [kg] | bounds as at | acceleration [m/s²] | jerk [m/s³] | no friction | 5 % friction |",
              "|---:|---:|---|---:|---:|---:|---:|"]  # fmt: skip
    for r in result["push_travel_floor"]:
        fl = r["floor_m"]
        cell = ["—" if fl[k] is None else f"{fl[k]:.3f}" for k in ("0.0", "0.05")]
        lines.append(f"| {r['scale']:g} | {r['tip_kg']:g} | x = {r['bounds_at_m']:g} m, at rest | {r['accel']:.1f} | "
                     f"{r['jerk']:.0f} | {cell[0]} | {cell[1]} |")  # fmt: skip
    if "weight_scan" in result:
        lines += ["", "Can other LQR weights fit the knock's recovery into the rail? The excursion [m] of a 10° knock "
                  "predicted by the balance's own closed loop (observer, delays, the governor on the rail's bounds at its "
                  "centre; `knock_excursion`) with 5 % friction, for the fixed weights (against the band's measured "
                  "range), without friction, and the least over 81 other weights (x, v, θ, θ̇ each over three values "
                  "16 × apart):", "",
                  "| rod × | tip [kg] | delay [ms] | fixed weights | measured | no friction | least of the grid | its "
                  "weights (x, v, a, θ, θ̇) |", "|---:|---:|---:|---:|---|---:|---:|---|"]  # fmt: skip
        for r in result["weight_scan"]:
            m = r["measured_m"]
            lines.append(f"| {r['scale']:g} | {r['tip_kg']:g} | {r['delay_ms']:g} | {r['fixed_m']:.3f} | "
                         f"{'—' if m is None else f'{m[0]:.3f}–{m[1]:.3f}'} | {r['fixed_no_friction_m']:.3f} | "
                         f"{r['best_m']:.3f} | {tuple(r['best_weights'])} |")  # fmt: skip
    return lines + [""]


def band_rerun(rows: list[dict], date: str, commit: str, how: str) -> dict:
    """The band's figures from ``rows`` (:func:`fast_case` over the fast part's grid) without the floors and the
    weight scan: a rerun of the grid after a change, kept beside the full part until that is run again."""
    ok = [r for r in rows if r["succeeded"] and r["falls"] == 0 and r["on_rail"]]
    swing = [r["swing_up_s"] for r in rows if r["swing_up_s"] is not None]
    return dict(date=date, commit=commit, how=how, cases=len(rows), without_fall=len(ok),
                falls=sum(r["falls"] for r in rows), by_friction=_summary(rows, "friction"),
                swing_up_s=[min(swing), float(np.median(swing)), max(swing)],
                settled_deg=_spread(rows, 0.05, "max_up_deg_settled"),
                cart_m_after_push={str(f): _spread(rows, f, "max_cart_m_after_push") for f in (0.0, 0.05)},
                failures=[r for r in rows if r not in ok], rows=rows)  # fmt: skip


def _rerun_section(r: dict) -> list[str]:
    lines = ["## The band rerun on the default rail (fast simulation; the floors and the weight scan not rerun)", "",
             f"Measured {r['date']} on commit {r['commit']} ({r['how']}).", "",
             f"{r['without_fall']} of {r['cases']} cases without a fall, {r['falls']} falls; swing-up "
             f"{r['swing_up_s'][0]:.2f}–{r['swing_up_s'][2]:.2f} s. The cart's excursion in the 4 s after the push "
             "[m], median / largest over the cases without a fall:", "", "| bearing's dry friction | excursion [m] |",
             "|---|---:|"]  # fmt: skip
    for k, v in r["cart_m_after_push"].items():
        lines.append(f"| {float(k):.0%} | {'—' if v is None else f'{v[0]:.3f} / {v[1]:.3f}'} |")
    lines += [f"- did not count: {f['scale']:g} ×, tip {f['tip_kg']:g} kg, {f['friction']:.0%}, {f['delay_ms']:g} ms, "
              f"{f['actuation_cycles']} cycles, seed {f['seed']}: {f['verdict']}" for f in r["failures"]]  # fmt: skip
    return lines + [""]


def _off_section(result: dict, head: list[str]) -> list[str]:
    lines = ["## Off the band's grid (fast simulation: rods 0.75 and 1.25 ×, 8 ms jitter, other knocks)", "", *head,
             f"{result['off_succeeded_without_fall']} of {result['off_cases']} cases without a fall, "
             f"{result['off_falls_total']} fall{'' if result['off_falls_total'] == 1 else 's'}.", "",
             "| rod × | tip [kg] | friction | delay + jitter [ms] | actuation [cycles] | push | excursion after it [m] | "
             "falls | verdict |", "|---:|---:|---:|---|---:|---|---:|---:|---|"]  # fmt: skip
    for r in result["off"]:
        run = r.get("max_cart_m_after_push")
        lines.append(f"| {r['scale']:g} | {r['tip_kg']:g} | {r['friction']:.0%} | {r['delay_ms']:g} + {r['jitter_ms']:g} | "
                     f"{r['actuation_cycles']} | {r['push_deg']:+g}° at {r['push_s']:g} s | "
                     f"{'—' if run is None else f'{run:.3f}'} | {r['falls']} | {r['verdict']} |")  # fmt: skip
    return lines + [""]


def _corner_section(result: dict, head: list[str]) -> list[str]:
    lines = ["## The band's last corner under another plant (Stribeck friction, explicit midpoint rule)", "", *head,
             f"{result['corner_succeeded_without_fall']} of {result['corner_cases']} cases without a fall, "
             f"{result['corner_falls_total']} fall{'' if result['corner_falls_total'] == 1 else 's'}; the largest excursion "
             f"after a knock {result['corner_max_excursion_m']:.3f} m (rail ±{result['corner_travel_m']:g} m). Static "
             "friction 1.3 × the kinetic, ±2 counts of noise, 2 ms of jitter; the last three rows are beyond the band.", "",
             "| rod × | rod mass [kg] | tip [kg] | kinetic | delay [ms] | actuation [cycles] | knocks (s after the catch: °) "
             "| excursion after each [m] | falls | verdict |", "|---:|---:|---:|---:|---:|---:|---|---|---:|---|"]  # fmt: skip
    for r in result["corner"]:
        knocks = ", ".join(f"{t:g}: {d:+g}" for t, d in r["knocks"])
        after = ", ".join("—" if e is None else f"{e:.3f}" for e in r["excursion_after_m"])
        lines.append(f"| {r['scale']:g} | {r['rod_mass_kg']:g} | {r['tip_kg']:g} | {r['kinetic']:.0%} | {r['delay_ms']:g} | "
                     f"{r['actuation_cycles']} | {knocks} | {after} | {r['falls']} | {r['verdict']} |")  # fmt: skip
    lines += ["", "Why the rail is longer than ±0.3 m rather than a recovery planned within it: the least largest excursion [m] "
              "of a 10° knock from rest at the rail's centre within the rail's own bounds along the plan — its "
              "acceleration bound shrinks with the cart's speed (`rail_travel_floor`, the range over the last passes of "
              "a sequential linear programme) — is a few centimetres short of 0.3 m for the corner's rod with friction, "
              "before the delay, the noise and a cart not at rest at the centre; the floor above, with constant bounds "
              "at rest, leaves the speed out:", "",
              "| rod × | tip [kg] | no friction | 5 % friction |", "|---:|---:|---|---|"]  # fmt: skip
    for r in result["rail_travel_floor"]:
        cell = ["—" if r["floor_m"][k] is None else "{:.3f}–{:.3f}".format(*r["floor_m"][k]) for k in ("0.0", "0.05")]
        lines.append(f"| {r['scale']:g} | {r['tip_kg']:g} | {cell[0]} | {cell[1]} |")
    if "rail_reach" in result:
        r = result["rail_reach"]
        lines += ["", f"The default rail (±{r['travel_m']:g} m at the thesis start pose): along it the joints use at most "
                  f"{r['joint_share']:.0%} of their position range (the start pose's own elbow, A4, is the largest); the "
                  f"acceleration bound at rest is {r['accel_end']:.2f} m/s² at its ends, {r['accel_centre']:.2f} m/s² at "
                  "its centre."]  # fmt: skip
    return lines + [""]


def _judge_section(result: dict, head: list[str]) -> list[str]:
    j = result["judge_by_friction"]
    lines = [
        "## The second judge (Stribeck friction, scipy RK45, other seeds, delays and push times)",
        "",
        *head,
        "| kinetic friction (static 1.3 ×) | cases | without a fall | falls |",
        "|---|---:|---:|---:|",
    ]
    lines += [f"| {float(k):.0%} | {v['cases']} | {v['without_fall']} | {v['falls']} |" for k, v in j.items()]
    lines += ["", "| rod × | rod mass [kg] | tip [kg] | kinetic | delay [ms] | push | falls | identified dry friction | "
              "verdict |", "|---:|---:|---:|---:|---:|---|---:|---:|---|"]  # fmt: skip
    for r in result["judge"]:
        share = r["identified_coulomb_share"]
        lines.append(f"| {r['scale']:g} | {r['rod_mass_kg']:g} | {r['tip_kg']:g} | {r['kinetic']:.0%} | {r['delay_ms']:g} | "
                     f"{r['push_deg']:+g}° at {r['push_s']:.2f} s | {r['falls']} | "
                     f"{'—' if share is None else f'{share:.1%}'} | {r['verdict']} |")  # fmt: skip
    return lines + [""]


def _fri_section(result: dict, head: list[str]) -> list[str]:
    lines = ["## The FRI simulator (`lbr control upright --sim-lockstep`)", "", *head,
              "| rod × | friction | noise [counts] | delay + jitter [ms] | exit | falls | swing-up [s] | velocity / limit | "
              "acceleration / limit |", "|---:|---:|---:|---|---:|---:|---:|---:|---:|"]  # fmt: skip
    for r in result["fri"]:
        lines.append(f"| {r['sim_scale']:g} | {r['friction']:.0%} | {r['noise']} | "
                     f"{r.get('delay_ms', 10.0):g} + {r.get('jitter_ms', 0.0):g} | {r['exit_code']} | {r['falls']} | "
                     f"{r['swing_up_s'] if r['swing_up_s'] is None else round(r['swing_up_s'], 2)} | "
                     f"{r.get('max_velocity_share', math.nan):.2f} | {r.get('max_acceleration_share', math.nan):.2f} |")  # fmt: skip
    return lines


PARTS = ("fast", "off", "corner", "fri", "judge")  # the order they run in (the slowest, the judge's RK45, last)


def _stamp() -> dict:
    """When and on which code a part was measured (the commit, ``+`` when the work tree had changes)."""

    def git(*args: str) -> str:
        p = subprocess.run(["git", *args], capture_output=True, text=True, cwd=ROOT)
        return p.stdout.strip() if p.returncode == 0 else ""

    dirty = git("status", "--porcelain", "--untracked-files=no")
    return {
        "date": time.strftime("%Y-%m-%d %H:%M"),
        "commit": git("rev-parse", "--short", "HEAD") + ("+" if dirty else ""),
    }


def fast_part(pool, quick: bool) -> dict:
    """The band on the fast simulation, and the travel floor of a 10° knock."""
    from planners.rigid_pendulum import RigidPendulum

    scales = (0.8, 1.2) if quick else (0.8, 1.0, 1.2)
    cases = list(itertools.product(scales, (0.0, 0.02), (0.0, 0.05), (0.005, 0.015), (2, 6), (0,) if quick else (0, 1)))
    t0 = time.perf_counter()
    fast = pool.map(fast_case, cases)
    fast_s = time.perf_counter() - t0
    ok = [r for r in fast if r["succeeded"] and r["falls"] == 0 and r["on_rail"]]
    settled = [r["max_up_deg_settled"] for r in fast if r.get("max_up_deg_settled") is not None]
    pushed = [r["max_up_deg_after_push"] for r in fast if r.get("max_up_deg_after_push") is not None]
    swing = [r["swing_up_s"] for r in fast if r["swing_up_s"] is not None]
    travel = [r["max_cart_m_after_push"] for r in fast if r.get("max_cart_m_after_push") is not None]
    rail = _rail()
    floors = []
    for scale, tip in ((0.8, 0.0), (1.0, 0.0), (1.2, 0.02)):
        length = RigidPendulum(rod_length=NOMINAL_ROD * scale, tip_mass=tip).equivalent_length
        for x in (0.0, 0.2):  # the rail's bounds at rest at its centre and 0.2 m out
            _, _, a_hi, _, j_hi = rail.local_bounds(x, 0.0, 0.0)
            floors.append(
                dict(
                    scale=scale,
                    tip_kg=tip,
                    bounds_at_m=x,
                    accel=a_hi,
                    jerk=j_hi,
                    floor_m={str(fr): push_travel_floor(length, fr, a_hi, j_hi) for fr in (0.0, 0.05)},
                )
            )
    return {
        "rail_travel_m": rail.limits.travel,
        "fast_cases": len(fast),
        "fast_succeeded_without_fall": len(ok),
        "fast_falls_total": sum(r["falls"] for r in fast),
        "fast_by_friction": _summary(fast, "friction"),
        "fast_swing_up_s": [min(swing), float(np.median(swing)), max(swing)] if swing else None,
        "fast_max_up_deg_settled": max(settled) if settled else None,
        "fast_settled_deg_by_friction": {str(fr): _spread(fast, fr, "max_up_deg_settled") for fr in (0.0, 0.05)},
        "fast_cart_m_after_push_by_friction": {str(fr): _spread(fast, fr, "max_cart_m_after_push")
                                               for fr in (0.0, 0.05)},
        "fast_max_up_deg_after_push": max(pushed) if pushed else None,
        "fast_max_cart_m_after_push": max(travel) if travel else None,
        "fast_wall_s": round(fast_s, 1),
        "push_travel_floor": floors,
        "weight_scan": weight_scan(fast),
        "fast_failures": [r for r in fast if r not in ok],
        "fast": fast,
    }  # fmt: skip


def off_part(pool) -> dict:
    """The cases off the band's grid (:func:`off_band_cases`)."""
    t0 = time.perf_counter()
    off = pool.map(fast_case, off_band_cases())
    return {
        "off_cases": len(off),
        "off_succeeded_without_fall": sum(r["succeeded"] and r["falls"] == 0 and r["on_rail"] for r in off),
        "off_falls_total": sum(r["falls"] for r in off),
        "off_wall_s": round(time.perf_counter() - t0, 1),
        "off": off,
    }


def judge_part(pool) -> dict:
    """The second judge's cases."""
    t0 = time.perf_counter()
    judge = pool.map(judge_case, judge_cases())
    return {
        "judge_cases": len(judge),
        "judge_succeeded_without_fall": sum(r["succeeded"] and r["falls"] == 0 and r["on_rail"] for r in judge),
        "judge_falls_total": sum(r["falls"] for r in judge),
        "judge_by_friction": _summary(judge, "kinetic"),
        "judge_wall_s": round(time.perf_counter() - t0, 1),
        "judge": judge,
    }


def rail_reach() -> dict:
    """What the default rail asks of the arm: its travel [m], the largest share of a joint's position range it uses,
    and the acceleration bound at rest at its ends [m/s²] (at its centre, for comparison)."""
    from trajectories.limits import default_limits

    rail, lim = _rail(), default_limits()
    travel = rail.limits.travel
    xs = np.linspace(-travel, travel, 81)
    share = max(float(np.max(np.abs(rail.joints(float(x))) / lim.position)) for x in xs)
    end = min(min(-b[1], b[2]) for b in (rail.local_bounds(travel, 0.0, 0.0), rail.local_bounds(-travel, 0.0, 0.0)))
    _, lo, hi, _, _ = rail.local_bounds(0.0, 0.0, 0.0)
    return dict(travel_m=travel, joint_share=share, accel_end=end, accel_centre=min(-lo, hi))


def corner_part(pool) -> dict:
    """The corner under another plant (:func:`corner_cases`), and why the rail needs to be longer than ±0.3 m for it:
    the knock's travel floor within the rail's own (speed-dependent) bounds (:func:`rail_travel_floor`)."""
    from planners.rigid_pendulum import RigidPendulum

    t0 = time.perf_counter()
    corner = pool.map(corner_case, corner_cases())
    wall = time.perf_counter() - t0
    rail = _rail()
    floors = []
    for scale, tip in ((1.0, 0.0), (1.2, 0.02)):
        length = RigidPendulum(rod_length=NOMINAL_ROD * scale, tip_mass=tip).equivalent_length
        floors.append(dict(scale=scale, tip_kg=tip,
                           floor_m={str(fr): rail_travel_floor(length, fr, rail.local_bounds) for fr in (0.0, 0.05)}))  # fmt: skip
    return {
        "corner_cases": len(corner),
        "corner_succeeded_without_fall": sum(r["succeeded"] and r["falls"] == 0 and r["on_rail"] for r in corner),
        "corner_falls_total": sum(r["falls"] for r in corner),
        "corner_max_excursion_m": max(
            (e for r in corner for e in r["excursion_after_m"] if e is not None), default=None
        ),
        "corner_travel_m": rail.limits.travel,
        "corner_wall_s": round(wall, 1),
        "corner": corner,
        "rail_travel_floor": floors,
        "rail_reach": rail_reach(),
    }


def _write(result: dict) -> None:
    out = ROOT / "benchmarks" / "results" / "upright_band.json"
    tmp = out.with_suffix(".json.part")
    tmp.write_text(json.dumps(result, indent=1) + "\n")
    tmp.replace(out)
    write_page(result, out.with_suffix(".md"))


def main(quick: bool = False, parts: tuple[str, ...] = PARTS, processes: int = 2) -> dict:
    """Run ``parts`` (of :data:`PARTS`) on ``processes`` worker processes and write the results file after each: the
    parts not run keep what the file had, each part stamped with when and on which commit it was measured
    (``measured``)."""
    out = ROOT / "benchmarks" / "results" / "upright_band.json"
    result = {} if quick or not out.exists() else json.loads(out.read_text())
    result.setdefault("measured", {})
    with Pool(processes) as pool:
        for part in (p for p in PARTS if p in parts):
            if part == "fast":
                result.update(fast_part(pool, quick))
                result.pop("fast_rerun", None)  # (a rerun of the grid kept beside an older full part: now replaced)
            elif part == "off":
                if quick:
                    continue
                result.update(off_part(pool))
            elif part == "judge":
                if quick:
                    continue
                result.update(judge_part(pool))
            elif part == "corner":
                if quick:
                    continue
                result.update(corner_part(pool))
            else:
                if quick:
                    continue
                result["fri"] = [fri_case(1.0, 0.0, 0), fri_case(0.8, 0.05, 2), fri_case(1.2, 0.05, 2),
                                 fri_case(0.8, 0.05, 2, 15.0, 3.0), fri_case(1.2, 0.05, 2, 15.0, 3.0),
                                 fri_case(1.2, 0.05, 2, 5.0, 8.0)]  # fmt: skip
            result["measured"][part] = _stamp()
            result["date"] = time.strftime("%Y-%m-%d")
            if not quick:
                _write(result)
    print(json.dumps({k: v for k, v in result.items()
                      if k not in ("fast", "fast_failures", "judge", "off", "corner", "push_travel_floor")}, indent=1))  # fmt: skip
    for r in result.get("fast_failures", []):
        print("failed:", r)
    for r in result.get("off", []):
        print("off the grid:", r)
    for r in result.get("judge", []):
        print("judge:", r)
    for r in result.get("corner", []):
        print("corner:", r)
    return result


if __name__ == "__main__":
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a smoke run of a few fast cases; writes nothing")
    ap.add_argument(
        "--parts",
        default=",".join(PARTS),
        help=f"comma-separated parts to run (of {', '.join(PARTS)}); the others keep what the file has",
    )
    ap.add_argument("--processes", type=int, default=2, help="worker processes (default 2)")
    args = ap.parse_args()
    chosen = tuple(p.strip() for p in args.parts.split(",") if p.strip())
    if not chosen or set(chosen) - set(PARTS):
        ap.error(f"--parts: expected some of {', '.join(PARTS)}, got {args.parts!r}")
    if args.processes < 1:
        ap.error(f"--processes: expected 1 or more, got {args.processes}")
    main(args.quick, chosen, args.processes)
