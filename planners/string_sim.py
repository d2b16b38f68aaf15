"""Event-driven simulation of the ball on its string with the cup (``string_model``), driven by a sampled pivot path.

Each phase is integrated with scipy's ``solve_ivp`` and ends at an event located by its root finder: taut (state s, ṡ;
DOP853, event: tension = 0), slack (state b, ḃ; RK45 with steps ≤ 1 ms, events: |b − p| = l → re-tension jerk,
distance to the cup = r → contact impulse; the rim-plane crossings are recorded), in the cup (the ball moves with
the cup until the bottom stops pushing it). The pivot realises the path as a position-controlled robot does: the
acceleration at sample k is the second difference of the samples, linear in between (``pendulum.SampledAcceleration``),
and its position and velocity are the exact integrals of that acceleration from rest at the first sample.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .pendulum import HANGING, SampledAcceleration
from .string_model import (
    IN_CUP,
    RESTING,
    SLACK,
    TAUT,
    StringModel,
    Vec3,
    axpy,
    contact_outcome,
    cup_gap,
    dot,
    entry_margin,
    flight_accel,
    in_cup,
    norm,
    rest_load,
    retension_outcome,
    sub,
    taut_accel,
    tension_per_mass,
)

MAX_EVENTS = 400  # contacts, releases and re-tensions in one run before it is cut short (a chattering ball)
_NUDGE = 1e-9  # [m] a new phase starts this far on the right side of the event that began it


class PivotMotion:
    """The anchor's path p(t), ṗ(t), p̈(t) [m, m/s, m/s²] from positions (n, 3) sampled every h from t[0]; at rest
    before t[0] and after the last sample. ``axes`` (3,) or (n, 3): the cup axis in the base frame (unit)."""

    def __init__(self, t: np.ndarray, positions: np.ndarray, axes: np.ndarray | None = None) -> None:
        t = np.asarray(t, dtype=float)
        p = np.asarray(positions, dtype=float)
        self.t0, self.h, self.n = float(t[0]), float(t[1] - t[0]), len(t)
        a = SampledAcceleration(t, p).samples()
        h = self.h
        v = np.zeros_like(p)
        x = np.zeros_like(p)
        x[0] = p[0]
        v[1:] = np.cumsum(0.5 * h * (a[:-1] + a[1:]), axis=0)
        x[1:] = p[0] + np.cumsum(h * v[:-1] + h * h * (2.0 * a[:-1] + a[1:]) / 6.0, axis=0)
        self.a, self.v, self.x = a, v, x
        self._a = [tuple(r) for r in a.tolist()]
        self._v = [tuple(r) for r in v.tolist()]
        self._x = [tuple(r) for r in x.tolist()]
        ax = np.broadcast_to(np.asarray((0.0, 0.0, 1.0) if axes is None else axes, dtype=float), p.shape)
        ax = ax / np.linalg.norm(ax, axis=1, keepdims=True)
        self.axes = ax
        self._ax = [tuple(r) for r in ax.tolist()]
        self.t_end = self.t0 + (self.n - 1) * h

    def state(self, t: float) -> tuple[Vec3, Vec3, Vec3]:
        """(p, ṗ, p̈) at time t [s] as tuples."""
        x = (t - self.t0) / self.h
        if x < 0.0:
            return self._x[0], (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
        k = int(x)
        if k >= self.n - 1:
            tau = t - self.t_end
            p, v = self._x[-1], self._v[-1]
            if tau == 0.0:
                return p, v, self._a[-1]
            return axpy(tau, v, p), v, (0.0, 0.0, 0.0)
        tau = (x - k) * self.h
        a0, a1, v0, p0 = self._a[k], self._a[k + 1], self._v[k], self._x[k]
        w = tau / self.h
        j = [(a1[i] - a0[i]) / self.h for i in range(3)]
        acc = tuple(a0[i] + w * (a1[i] - a0[i]) for i in range(3))
        vel = tuple(v0[i] + a0[i] * tau + 0.5 * j[i] * tau * tau for i in range(3))
        pos = tuple(p0[i] + v0[i] * tau + 0.5 * a0[i] * tau * tau + j[i] * tau**3 / 6.0 for i in range(3))
        return pos, vel, acc  # type: ignore[return-value]

    def axis(self, t: float) -> Vec3:
        """Cup axis at t [s] (that of the sample at or before t)."""
        k = min(max(int((t - self.t0) / self.h), 0), self.n - 1)
        return self._ax[k]

    def acc_samples_after(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Sample times ≥ t and the accelerations there (for the rest phase's lift-off search)."""
        k = max(0, int(math.ceil((t - self.t0) / self.h - 1e-12)))
        times = self.t0 + np.arange(k, self.n) * self.h
        return times, self.a[k:]


@dataclass(frozen=True)
class BallEvent:
    """Something that happened to the ball: time [s], kind and figures (JSON-able)."""

    t: float
    kind: str  # "slack", "retension", "contact", "entry", "rest", "lift", "cut"
    info: dict = field(default_factory=dict, hash=False, compare=False)


@dataclass(frozen=True)
class BallRun:
    """Sampled run: ball position and velocity (n, 3) [m, m/s], phase (n,) (TAUT/SLACK/IN_CUP), tension per mass
    (n,) [m/s²] (NaN unless taut), the pivot (n, 3) [m] and the events in order."""

    t: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    phase: np.ndarray
    tension: np.ndarray
    pivot: np.ndarray
    events: tuple[BallEvent, ...]
    model: StringModel
    final_phase: int  # TAUT / SLACK / RESTING (on the cup) at the end
    final_inside: bool  # the ball centre is inside the cup at the end

    def of_kind(self, kind: str) -> list[BallEvent]:
        return [e for e in self.events if e.kind == kind]

    @property
    def string_direction(self) -> np.ndarray:
        """(n, 3) unit vectors from the anchor to the ball."""
        d = self.position - self.pivot
        return d / np.linalg.norm(d, axis=1, keepdims=True)

    @property
    def theta_y(self) -> np.ndarray:
        """Signed angle of the anchor→ball direction in the y–z plane from hanging, toward +y [rad]."""
        d = self.position - self.pivot
        return np.arctan2(d[:, 1], -d[:, 2])

    @property
    def theta(self) -> np.ndarray:
        """Tilt of the anchor→ball direction from hanging [rad], 0..π."""
        return np.arccos(np.clip(-self.string_direction[:, 2], -1.0, 1.0))

    @property
    def first_slack(self) -> float | None:
        ev = self.of_kind("slack")
        return ev[0].t if ev else None

    @property
    def caught(self) -> bool:
        """The ball ends resting in the cup."""
        return self.final_phase == RESTING and self.final_inside


def _as_tuple(y: np.ndarray, i: int) -> Vec3:
    return (float(y[i]), float(y[i + 1]), float(y[i + 2]))


class _Runner:
    """One simulation: phases integrated in turn, events applied, dense pieces kept for sampling."""

    def __init__(self, model: StringModel, pivot: PivotMotion, t_end: float, rtol: float, atol: float) -> None:
        self.m, self.pv, self.t_end = model, pivot, t_end
        self.rtol, self.atol = rtol, atol
        self.l, self.k = model.length, model.drag
        self.cup = model.cup
        self.events: list[BallEvent] = []
        self.pieces: list[tuple[float, float, int, object]] = []  # (t_a, t_b, phase, evaluator)

    # -- taut ---------------------------------------------------------------------------------------------------
    def taut(self, t: float, s: Vec3, sd: Vec3) -> tuple[float, Vec3, Vec3] | None:
        from scipy.integrate import solve_ivp

        l, k, pv, c = self.l, self.k, self.pv, self.m.damping

        def f(tt, y):
            s_, v_ = _as_tuple(y, 0), _as_tuple(y, 3)
            _, pvel, pacc = pv.state(tt)
            return (*v_, *taut_accel(s_, v_, pvel, pacc, l, k, c))

        def tension(tt, y):
            _, pvel, pacc = pv.state(tt)
            return tension_per_mass(_as_tuple(y, 0), _as_tuple(y, 3), pvel, pacc, l, k)

        tension.terminal, tension.direction = True, -1
        sol = solve_ivp(
            f,
            (t, self.t_end),
            (*s, *sd),
            method="DOP853",
            events=tension,
            dense_output=True,
            rtol=self.rtol,
            atol=self.atol,
            max_step=pv.h,
        )
        if sol.status < 0:
            raise RuntimeError(f"string simulation (taut) failed: {sol.message}")
        t1 = float(sol.t[-1])
        self.pieces.append((t, t1, TAUT, sol.sol))
        if sol.status == 1 and sol.t_events[0].size:
            te = float(sol.t_events[0][0])
            y = sol.y_events[0][0]
            s1 = _as_tuple(y, 0)
            n = norm(s1)
            s1 = (s1[0] / n, s1[1] / n, s1[2] / n)
            sd1 = axpy(-dot(_as_tuple(y, 3), s1), s1, _as_tuple(y, 3))
            p, pvel, _ = pv.state(te)
            b = axpy(self.l - _NUDGE, s1, p)
            v = axpy(self.l, sd1, pvel)
            self.events.append(
                BallEvent(
                    te,
                    "slack",
                    {"theta_deg": math.degrees(math.acos(max(-1.0, min(1.0, -s1[2])))), "speed_m_s": norm(v)},
                )
            )
            return te, b, v
        return None

    # -- slack --------------------------------------------------------------------------------------------------
    def slack(self, t: float, b: Vec3, v: Vec3) -> tuple[str, float, Vec3, Vec3] | None:
        from scipy.integrate import solve_ivp

        l, k, pv, cup = self.l, self.k, self.pv, self.cup
        r = self.m.ball.radius

        def f(tt, y):
            return (y[3], y[4], y[5], *flight_accel(_as_tuple(y, 3), k))

        def string(tt, y):
            return norm(sub(_as_tuple(y, 0), pv.state(tt)[0])) - l

        string.terminal, string.direction = True, 1
        events = [string]
        if cup is not None:

            def contact(tt, y):
                return cup_gap(sub(_as_tuple(y, 0), pv.state(tt)[0]), pv.axis(tt), cup)[0] - r

            def rim_plane(tt, y):
                return dot(sub(_as_tuple(y, 0), pv.state(tt)[0]), pv.axis(tt)) - cup.rim_height

            contact.terminal, contact.direction = True, -1
            rim_plane.terminal, rim_plane.direction = False, -1
            events += [contact, rim_plane]
        sol = solve_ivp(
            f,
            (t, self.t_end),
            (*b, *v),
            method="RK45",
            events=events,
            dense_output=True,
            rtol=self.rtol,
            atol=self.atol,
            max_step=min(pv.h, 1e-3),
        )
        if sol.status < 0:
            raise RuntimeError(f"string simulation (slack) failed: {sol.message}")
        t1 = float(sol.t[-1])
        self.pieces.append((t, t1, SLACK, sol.sol))
        if cup is not None:
            for te, y in zip(sol.t_events[2], sol.y_events[2]):
                self._entry(float(te), _as_tuple(y, 0), _as_tuple(y, 3))
        if sol.status != 1:
            return None
        for idx, name in enumerate(("string", "contact")[: len(events)]):
            if sol.t_events[idx].size:
                y = sol.y_events[idx][0]
                return name, float(sol.t_events[idx][0]), _as_tuple(y, 0), _as_tuple(y, 3)
        return None

    def _entry(self, t: float, b: Vec3, v: Vec3) -> None:
        p, pvel, _ = self.pv.state(t)
        ax = self.pv.axis(t)
        rel_v = sub(v, pvel)
        self.events.append(
            BallEvent(
                t,
                "entry",
                {
                    "margin_m": entry_margin(sub(b, p), ax, self.cup, self.m.ball.radius),
                    "relative_speed_m_s": norm(rel_v),
                    "relative_axial_speed_m_s": -dot(rel_v, ax),
                    "relative_lateral_speed_m_s": norm(axpy(-dot(rel_v, ax), ax, rel_v)),
                },
            )
        )

    # -- in the cup ---------------------------------------------------------------------------------------------
    def rest(self, t: float, offset: Vec3) -> tuple[float, Vec3, Vec3] | None:
        """The ball rests at b = p + offset from t until the bottom stops pushing it; (t_lift, b, v) or None."""
        pv = self.pv
        times, acc = pv.acc_samples_after(t)
        lift = None
        prev_t, prev_load = t, rest_load(pv.state(t)[2], pv.axis(t))
        for tk, ak in zip(times, acc):
            load = rest_load(tuple(ak), pv.axis(tk))
            if load <= 0.0 < prev_load:
                lift = prev_t + (tk - prev_t) * prev_load / (prev_load - load)
                break
            prev_t, prev_load = tk, load
        if lift is not None and lift >= self.t_end:
            lift = None
        end = self.t_end if lift is None else lift

        def at(tt):
            p, pvel, _ = pv.state(tt)
            return p, pvel

        self.pieces.append((t, end, RESTING, (offset, at)))
        if lift is None:
            return None
        p, pvel, _ = pv.state(lift)
        self.events.append(BallEvent(lift, "lift", {}))
        return lift, axpy(1.0, offset, p), pvel

    # -- the whole run ------------------------------------------------------------------------------------------
    def run(self, s0: Vec3, sd0: Vec3) -> int:
        m, pv, cup = self.m, self.pv, self.cup
        t = pv.t0
        phase = TAUT
        s, sd = s0, sd0
        b = v = (0.0, 0.0, 0.0)
        count = 0
        while t < self.t_end:
            count += 1
            if count > MAX_EVENTS:
                self.events.append(BallEvent(t, "cut", {"reason": f"more than {MAX_EVENTS} events"}))
                break
            if phase == TAUT:
                _, pvel, pacc = pv.state(t)
                if tension_per_mass(s, sd, pvel, pacc, self.l, self.k) <= 0.0:
                    p = pv.state(t)[0]
                    b, v = axpy(self.l - _NUDGE, s, p), axpy(self.l, sd, pvel)
                    phase = SLACK
                    continue
                out = self.taut(t, s, sd)
                if out is None:
                    return TAUT
                t, b, v = out
                phase = SLACK
            elif phase == SLACK:
                out = self.slack(t, b, v)
                if out is None:
                    return SLACK
                kind, t, b, v = out
                p, pvel, pacc = pv.state(t)
                rel = sub(b, p)
                v_rel = sub(v, pvel)
                if kind == "string":
                    dist = norm(rel)
                    s = (rel[0] / dist, rel[1] / dist, rel[2] / dist)
                    self.events.append(BallEvent(t, "retension", {"radial_speed_m_s": dot(v_rel, s)}))
                    taut, v_new = retension_outcome(s, v_rel, pvel, pacc, m)
                    if taut:
                        phase, sd = TAUT, (v_new[0] / self.l, v_new[1] / self.l, v_new[2] / self.l)
                    else:
                        b, v = axpy(-_NUDGE, s, b), axpy(1.0, v_new, pvel)
                    continue
                ax = pv.axis(t)
                rests, v_new, seg, speed = contact_outcome(rel, v_rel, pacc, ax, m)
                self.events.append(BallEvent(t, "contact", {"segment": seg, "normal_speed_m_s": speed}))
                if rests:
                    self.events.append(BallEvent(t, "rest", {"on": "bottom" if seg == 4 else "rim"}))
                    out = self.rest(t, rel)
                    if out is None:
                        return RESTING
                    t, b, v = out
                    continue
                b, v = axpy(_NUDGE, cup_gap(rel, ax, cup)[1], b), axpy(1.0, v_new, pvel)
        return phase

    def sample(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Ball position, velocity, phase, tension and pivot position at ``times`` from the dense pieces."""
        n = len(times)
        pos, vel, piv = np.full((n, 3), np.nan), np.full((n, 3), np.nan), np.zeros((n, 3))
        phase = np.full(n, -1, dtype=np.int8)
        tension = np.full(n, np.nan)
        starts = np.array([pc[0] for pc in self.pieces])
        for i, tt in enumerate(times):
            p, pvel, pacc = self.pv.state(float(tt))
            piv[i] = p
            j = int(np.searchsorted(starts, tt, side="right")) - 1
            if j < 0:
                continue
            t_a, t_b, ph, ev = self.pieces[j]
            tt = min(float(tt), t_b)
            if ph == TAUT:
                y = ev(tt)
                s, sd = _as_tuple(y, 0), _as_tuple(y, 3)
                ns = norm(s)
                s = (s[0] / ns, s[1] / ns, s[2] / ns)
                pos[i] = axpy(self.l, s, p)
                vel[i] = axpy(self.l, sd, pvel)
                tension[i] = tension_per_mass(s, sd, pvel, pacc, self.l, self.k)
            elif ph == SLACK:
                y = ev(tt)
                pos[i], vel[i] = y[:3], y[3:]
                if self.cup is not None and in_cup(sub(_as_tuple(y, 0), p), self.pv.axis(tt), self.cup):
                    ph = IN_CUP
            else:
                offset, at = ev
                pos[i] = axpy(1.0, offset, p)
                vel[i] = pvel
                ph = IN_CUP if in_cup(offset, self.pv.axis(tt), self.cup) else SLACK
            phase[i] = ph
        return pos, vel, phase, tension, piv


def simulate_string(
    model: StringModel,
    pivot: PivotMotion,
    t_end: float,
    sample_times: np.ndarray | None = None,
    s0: np.ndarray = HANGING,
    sdot0: np.ndarray | None = None,
    *,
    rtol: float = 1e-9,
    atol: float = 1e-11,
) -> BallRun:
    """Simulate the ball from a taut start (direction s0, rate ṡ0 [1/s]; default hanging at rest) at the pivot's first
    sample until ``t_end`` [s]; sampled at ``sample_times`` (default: the pivot's samples, continued at its step)."""
    model.validate()
    s0 = np.asarray(s0, dtype=float) / np.linalg.norm(s0)
    sd0 = np.zeros(3) if sdot0 is None else np.asarray(sdot0, dtype=float)
    runner = _Runner(model, pivot, float(t_end), rtol, atol)
    final = runner.run(tuple(float(x) for x in s0), tuple(float(x) for x in sd0))
    if sample_times is None:
        sample_times = pivot.t0 + np.arange(int(math.floor((t_end - pivot.t0) / pivot.h + 1e-9)) + 1) * pivot.h
    times = np.asarray(sample_times, dtype=float)
    pos, vel, phase, tension, piv = runner.sample(times)
    inside = False
    if model.cup is not None:
        p = runner.pv.state(float(t_end))[0]
        last = runner.pieces[-1]
        if last[2] == RESTING:
            inside = in_cup(last[3][0], runner.pv.axis(float(t_end)), model.cup)
        elif last[2] == SLACK:
            y = last[3](min(float(t_end), last[1]))
            inside = in_cup(sub(_as_tuple(y, 0), p), runner.pv.axis(float(t_end)), model.cup)
    return BallRun(
        t=times,
        position=pos,
        velocity=vel,
        phase=phase,
        tension=tension,
        pivot=piv,
        events=tuple(sorted(runner.events, key=lambda e: e.t)),
        model=model,
        final_phase=final,
        final_inside=inside,
    )
