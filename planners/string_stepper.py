"""The string model (``string_model``) stepped interval by interval: the FRI simulator's ball, the planners' fast search.

Within an interval [t, t + h] the anchor's acceleration goes linearly from a0 to a1 and its position and velocity are
the exact integrals of that from (p0, v0) — the same realisation of a sampled path as ``string_sim.PivotMotion``.
Taut: classical RK4 of (s, ṡ); if the tension ends the interval ≤ 0 the release time is found by bisection on the
tension and the rest of the interval is flown. Slack: RK4 of (b, ḃ) (gravity and drag); when the ball ends the
interval beyond the string's length or inside the cup's solid, the event time is found by bisection on a cubic
Hermite of the ball's path, the impulse applied there and the rest of the interval stepped again. In the cup: the
ball moves with the cup until the bottom stops pushing it. Pure Python floats: one interval of a taut ball costs
≈ 20 µs, which the simulator's 1 kHz loop affords; the event-driven ``string_sim`` is the reference it is checked
against.
"""

from __future__ import annotations

import math

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
from .string_sim import BallEvent

_NUDGE = 1e-9  # [m]
_BISECT = 30  # halvings of an interval when an event is located (1 ms → 1e-12 s)


class Interval:
    """The anchor over one interval: p(τ), ṗ(τ), p̈(τ) for 0 ≤ τ ≤ h (acceleration linear from a0 to a1)."""

    __slots__ = ("p0", "v0", "a0", "j", "h")

    def __init__(self, p0: Vec3, v0: Vec3, a0: Vec3, a1: Vec3, h: float) -> None:
        self.p0, self.v0, self.a0, self.h = p0, v0, a0, h
        self.j = ((a1[0] - a0[0]) / h, (a1[1] - a0[1]) / h, (a1[2] - a0[2]) / h)

    def at(self, tau: float) -> tuple[Vec3, Vec3, Vec3]:
        p0, v0, a0, j = self.p0, self.v0, self.a0, self.j
        t2, t3 = 0.5 * tau * tau, tau * tau * tau / 6.0
        return (
            (
                p0[0] + v0[0] * tau + a0[0] * t2 + j[0] * t3,
                p0[1] + v0[1] * tau + a0[1] * t2 + j[1] * t3,
                p0[2] + v0[2] * tau + a0[2] * t2 + j[2] * t3,
            ),
            (v0[0] + a0[0] * tau + j[0] * t2, v0[1] + a0[1] * tau + j[1] * t2, v0[2] + a0[2] * tau + j[2] * t2),
            (a0[0] + j[0] * tau, a0[1] + j[1] * tau, a0[2] + j[2] * tau),
        )


def _add(a: Vec3, b: Vec3, k: float) -> Vec3:
    return (a[0] + k * b[0], a[1] + k * b[1], a[2] + k * b[2])


def _rk4(y: tuple[Vec3, Vec3], deriv, tau0: float, dt: float) -> tuple[Vec3, Vec3]:
    """One RK4 step of (x, ẋ) with ẍ = deriv(τ, x, ẋ)."""
    x, v = y
    h2 = 0.5 * dt
    k1 = deriv(tau0, x, v)
    x2, v2 = _add(x, v, h2), _add(v, k1, h2)
    k2 = deriv(tau0 + h2, x2, v2)
    x3, v3 = _add(x, v2, h2), _add(v, k2, h2)
    k3 = deriv(tau0 + h2, x3, v3)
    x4, v4 = _add(x, v3, dt), _add(v, k3, dt)
    k4 = deriv(tau0 + dt, x4, v4)
    s6 = dt / 6.0
    xn = tuple(x[i] + s6 * (v[i] + 2.0 * v2[i] + 2.0 * v3[i] + v4[i]) for i in range(3))
    vn = tuple(v[i] + s6 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]) for i in range(3))
    return xn, vn  # type: ignore[return-value]


def _hermite(b0: Vec3, v0: Vec3, b1: Vec3, v1: Vec3, dt: float, u: float) -> tuple[Vec3, Vec3]:
    """Cubic Hermite position and velocity at fraction u of an interval of length dt."""
    u2, u3 = u * u, u * u * u
    h00, h10, h01, h11 = 2 * u3 - 3 * u2 + 1, u3 - 2 * u2 + u, -2 * u3 + 3 * u2, u3 - u2
    d00, d10, d01, d11 = (6 * u2 - 6 * u) / dt, 3 * u2 - 4 * u + 1, (-6 * u2 + 6 * u) / dt, 3 * u2 - 2 * u
    pos = tuple(h00 * b0[i] + h10 * dt * v0[i] + h01 * b1[i] + h11 * dt * v1[i] for i in range(3))
    vel = tuple(d00 * b0[i] + d10 * v0[i] + d01 * b1[i] + d11 * v1[i] for i in range(3))
    return pos, vel  # type: ignore[return-value]


class StringStepper:
    """The ball's state (taut, slack or resting in the cup) advanced one interval at a time.

    Starts taut with direction ``s0`` and rate ``sdot0`` [1/s] below the anchor at ``p0`` [m] (hanging at rest by
    default). ``axis`` is the cup's opening direction in the base frame (given again with every interval when it
    changes). ``events`` collects what happened (``string_sim.BallEvent``).
    """

    def __init__(
        self,
        model: StringModel,
        p0: Vec3,
        axis: Vec3 = (0.0, 0.0, 1.0),
        s0: Vec3 = (0.0, 0.0, -1.0),
        sdot0: Vec3 = (0.0, 0.0, 0.0),
    ) -> None:
        model.validate()
        self.m = model
        self.l, self.k, self.cup, self.r = model.length, model.drag, model.cup, model.ball.radius
        self.phase = TAUT
        self.s, self.sd = s0, sdot0
        self.b, self.v = axpy(self.l, s0, p0), axpy(self.l, sdot0, (0.0, 0.0, 0.0))
        self.p = p0
        self.axis = axis
        self.offset: Vec3 = (0.0, 0.0, 0.0)
        self._pv: Vec3 = (0.0, 0.0, 0.0)
        self.t = 0.0
        self.events: list[BallEvent] = []

    # -- what the outside reads ----------------------------------------------------------------------------------
    @property
    def phase_code(self) -> int:
        """TAUT, SLACK or IN_CUP (the ball centre inside the cup, resting or not)."""
        if self.phase == TAUT:
            return TAUT
        return IN_CUP if self.inside else SLACK

    @property
    def resting(self) -> bool:
        """Resting on the cup (its bottom, or its rim)."""
        return self.phase == RESTING

    @property
    def inside(self) -> bool:
        """The ball centre is inside the cup (below the rim plane, within the inner radius)."""
        return self.cup is not None and self.phase != TAUT and in_cup(sub(self.b, self.p), self.axis, self.cup)

    def direction(self) -> Vec3:
        """Unit vector from the anchor to the ball."""
        if self.phase == TAUT:
            return self.s
        d = sub(self.b, self.p)
        n = norm(d)
        return (d[0] / n, d[1] / n, d[2] / n)

    def direction_rate(self) -> Vec3:
        """d/dt of ``direction`` [1/s] (from the relative velocity when slack)."""
        if self.phase == TAUT:
            return self.sd
        d = sub(self.b, self.p)
        n = norm(d)
        s = (d[0] / n, d[1] / n, d[2] / n)
        vr = sub(self.v, self._pv)
        return axpy(-dot(vr, s) / n, s, (vr[0] / n, vr[1] / n, vr[2] / n))

    # -- one interval --------------------------------------------------------------------------------------------
    def advance(self, h: float, p0: Vec3, v0: Vec3, a0: Vec3, a1: Vec3, axis: Vec3 | None = None) -> None:
        """Advance by h [s] while the anchor starts at p0 [m] with velocity v0 [m/s] and its acceleration goes
        linearly from a0 to a1 [m/s²]."""
        if axis is not None:
            self.axis = axis
        iv = Interval(p0, v0, a0, a1, h)
        tau = 0.0
        for _ in range(64):  # events within one interval (a chattering ball is cut short)
            if tau >= h - 1e-15:
                break
            if self.phase == TAUT:
                tau = self._taut(iv, tau, h)
            elif self.phase == SLACK:
                tau = self._slack(iv, tau, h)
            else:
                tau = self._rest(iv, tau, h)
        self.t += h
        self.p, self._pv, _ = iv.at(h)
        if self.phase == TAUT:
            self.b, self.v = axpy(self.l, self.s, self.p), axpy(self.l, self.sd, self._pv)
        elif self.phase == RESTING:
            self.b, self.v = axpy(1.0, self.offset, self.p), self._pv

    def _taut(self, iv: Interval, tau: float, h: float) -> float:
        l, k, c = self.l, self.k, self.m.damping

        def deriv(tt, s, sd):
            _, pv, pa = iv.at(tt)
            return taut_accel(s, sd, pv, pa, l, k, c)

        def tension(tt, s, sd):
            _, pv, pa = iv.at(tt)
            return tension_per_mass(s, sd, pv, pa, l, k)

        y0 = (self.s, self.sd)
        if tension(tau, *y0) <= 0.0:
            self._release(iv, tau)
            return tau
        y1 = _rk4(y0, deriv, tau, h - tau)
        if tension(h, *y1) > 0.0:
            self.s, self.sd = _unit(y1)
            return h
        lo, hi = tau, h  # tension > 0 at lo, ≤ 0 at hi
        for _ in range(_BISECT):
            mid = 0.5 * (lo + hi)
            ym = _rk4(y0, deriv, tau, mid - tau)
            if tension(mid, *ym) > 0.0:
                lo = mid
            else:
                hi = mid
        self.s, self.sd = _unit(_rk4(y0, deriv, tau, hi - tau))
        self._release(iv, hi)
        return hi

    def _release(self, iv: Interval, tau: float) -> None:
        p, pv, _ = iv.at(tau)
        s, sd = self.s, self.sd
        self.b, self.v = axpy(self.l - _NUDGE, s, p), axpy(self.l, sd, pv)
        self.phase = SLACK
        self.events.append(
            BallEvent(
                self.t + tau,
                "slack",
                {"theta_deg": math.degrees(math.acos(max(-1.0, min(1.0, -s[2])))), "speed_m_s": norm(self.v)},
            )
        )

    def _slack(self, iv: Interval, tau: float, h: float) -> float:
        k, l, cup, r = self.k, self.l, self.cup, self.r

        def deriv(tt, b, v):
            return flight_accel(v, k)

        b0, v0 = self.b, self.v
        dt = h - tau
        b1, v1 = _rk4((b0, v0), deriv, tau, dt)

        def state(u):  # (the Hermite curve's ends are exactly its end points: no arithmetic there)
            return (b1, v1) if u == 1.0 else (b0, v0) if u == 0.0 else _hermite(b0, v0, b1, v1, dt, u)

        def string_gap(u):
            return norm(sub(state(u)[0], iv.at(tau + u * dt)[0])) - l

        def cup_gap_at(u):
            return cup_gap(sub(state(u)[0], iv.at(tau + u * dt)[0]), self.axis, cup)[0] - r

        events = []
        rel1 = sub(b1, iv.at(tau + dt)[0])
        if norm(rel1) > l:  # string_gap(1.0) > 0
            events.append((_root(string_gap), "string"))
        # the cup's solid lies within ``extent`` of the anchor: a ball centre farther than that plus its radius
        # cannot touch it (the exact gap is computed only near the cup)
        if cup is not None and dot(rel1, rel1) <= (cup.extent + r + 1e-6) ** 2 and cup_gap_at(1.0) < 0.0:
            events.append((_root(lambda u: -cup_gap_at(u)), "contact"))
        u_end = min(events)[0] if events else 1.0
        if cup is not None:
            self._rim_crossing(iv, tau, dt, state, u_end)
        if not events:
            self.b, self.v = b1, v1
            return h
        u, kind = min(events)
        te = tau + u * dt
        b, v = state(u)
        p, pv, pa = iv.at(te)
        rel, v_rel = sub(b, p), sub(v, pv)
        m = self.m
        if kind == "string":
            dist = norm(rel)
            s = (rel[0] / dist, rel[1] / dist, rel[2] / dist)
            self.events.append(BallEvent(self.t + te, "retension", {"radial_speed_m_s": dot(v_rel, s)}))
            taut, v_new = retension_outcome(s, v_rel, pv, pa, m)
            if taut:
                self.phase, self.s, self.sd = TAUT, s, (v_new[0] / l, v_new[1] / l, v_new[2] / l)
            else:
                self.b, self.v = axpy(-_NUDGE, s, b), axpy(1.0, v_new, pv)
            return te
        rests, v_new, seg, speed = contact_outcome(rel, v_rel, pa, self.axis, m)
        self.events.append(BallEvent(self.t + te, "contact", {"segment": seg, "normal_speed_m_s": speed}))
        if rests:
            self.phase, self.offset = RESTING, rel
            self.b, self.v = b, pv
            self.events.append(BallEvent(self.t + te, "rest", {"on": "bottom" if seg == 4 else "rim"}))
            return te
        n = cup_gap(rel, self.axis, cup)[1]
        self.b, self.v = axpy(_NUDGE, n, b), axpy(1.0, v_new, pv)
        return te

    def _rim_crossing(self, iv: Interval, tau: float, dt: float, state, u_end: float) -> None:
        """Record a downward crossing of the rim plane before ``u_end`` in the interval (an entry attempt)."""
        cup = self.cup

        def height(u):
            return dot(sub(state(u)[0], iv.at(tau + u * dt)[0]), self.axis) - cup.rim_height

        if height(0.0) > 0.0 >= height(u_end):
            u = u_end * _root(lambda uu: -height(u_end * uu))
            b, v = state(u)
            p, pv, _ = iv.at(tau + u * dt)
            rel_v = sub(v, pv)
            ax = self.axis
            self.events.append(
                BallEvent(
                    self.t + tau + u * dt,
                    "entry",
                    {
                        "margin_m": entry_margin(sub(b, p), ax, cup, self.r),
                        "relative_speed_m_s": norm(rel_v),
                        "relative_axial_speed_m_s": -dot(rel_v, ax),
                        "relative_lateral_speed_m_s": norm(axpy(-dot(rel_v, ax), ax, rel_v)),
                    },
                )
            )

    def _rest(self, iv: Interval, tau: float, h: float) -> float:
        _, _, a1 = iv.at(h)
        if rest_load(a1, self.axis) > 0.0:
            return h
        _, _, a0 = iv.at(tau)
        l0, l1 = rest_load(a0, self.axis), rest_load(a1, self.axis)
        te = tau + (h - tau) * l0 / (l0 - l1) if l0 > 0.0 else tau
        p, pv, _ = iv.at(te)
        self.b, self.v = axpy(1.0, self.offset, p), pv
        self.phase = SLACK
        self.events.append(BallEvent(self.t + te, "lift", {}))
        return te


def _unit(y: tuple[Vec3, Vec3]) -> tuple[Vec3, Vec3]:
    """Re-project (s, ṡ) onto the sphere: |s| = 1, ṡ ⟂ s."""
    s, sd = y
    n = norm(s)
    s = (s[0] / n, s[1] / n, s[2] / n)
    return s, axpy(-dot(sd, s), s, sd)


def _root(f) -> float:
    """u in (0, 1] where f goes from ≤ 0 (at 0) to > 0 (at 1), by bisection."""
    lo, hi = 0.0, 1.0
    for _ in range(_BISECT):
        mid = 0.5 * (lo + hi)
        if f(mid) > 0.0:
            hi = mid
        else:
            lo = mid
    return hi


def step_path(
    model: StringModel,
    pivot,
    t_end: float,
    substeps: int = 1,
    *,
    s0: Vec3 = (0.0, 0.0, -1.0),
    sdot0: Vec3 = (0.0, 0.0, 0.0),
    state: StringStepper | None = None,
    shift: float = 0.0,
    record: bool = False,
    until_missed: bool = False,
):
    """Step the ball along a ``string_sim.PivotMotion`` to ``t_end`` [s], ``substeps`` intervals per sample step:
    from the pivot's first sample (hanging, or s0, ṡ0), or on from ``state`` (a stepper at its time ``t``, which is
    advanced in place). ``shift`` [s]: once the ball is slack the anchor is read at t − shift — the cup's motion
    after the release that much late (negative: early), continuing from where the anchor is then (a pivot that is
    moving then does not jump). ``until_missed``: stop once the ball's first downward crossing of the rim plane
    passed outside the opening (a search's shortcut: such a ball is missed unless a later bounce brings it in).
    Returns the stepper and, with ``record``, the (times, ball positions, phase codes) at the interval ends."""
    h = pivot.h / substeps
    if state is None:
        t = pivot.t0
        p, v, a = pivot.state(t)
        st = StringStepper(model, p, pivot.axis(t), s0, sdot0)
        st.t = t
    else:
        st = state
    t0 = st.t
    rec = ([], [], []) if record else None
    lag = 0.0
    offset: Vec3 = (0.0, 0.0, 0.0)
    n = int(math.floor((t_end - t0) / h + 1e-9))
    seen = len(st.events)
    nxt = None  # the anchor's state at the end of the last interval: the start of the next one
    for i in range(n):
        t = t0 + i * h
        if shift and not lag and st.phase != TAUT:
            lag, nxt = shift, None
            # the cup goes on from where it is: a pivot moving when the shift begins does not jump (at rest: 0)
            offset = sub(pivot.state(t)[0], pivot.state(t - lag)[0])
        p, v, a = nxt if nxt is not None else pivot.state(t - lag)
        nxt = pivot.state(t + h - lag)
        if lag:
            p = axpy(1.0, offset, p)
        st.advance(h, p, v, a, nxt[2], pivot.axis(t - lag))
        if rec is not None:
            rec[0].append(st.t), rec[1].append(st.b), rec[2].append(st.phase_code)
        if until_missed and len(st.events) > seen:
            seen = len(st.events)
            if _missed(st.events):
                break
    return st, rec


def _missed(events) -> bool:
    """The first downward crossing of the rim plane among ``events`` passed outside the opening."""
    first = next((e for e in events if e.kind == "entry"), None)
    return first is not None and first.info["margin_m"] <= 0.0
