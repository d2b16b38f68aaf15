"""Back onto the client's path after the controller bridged a command: a jerk-limited offset that decays to zero.

When a message shows that the controller bridged our last command (it held the velocity: its acceleration stepped
to 0), the history it executed is no longer the one the client planned from. Rather than admitting the client's next
command against it (its acceleration jumps back to the path's within one period), the core sends the client's
command plus an offset e(t) — the executed history minus the client's commands — that ruckig (position interface,
each joint on its own) brings to rest at zero within ``REJOIN_SCALE`` of the velocity, acceleration and jerk limits.
The offset starts from the continuous state of its discrete history (step velocity + half a period of its
acceleration, as :class:`~lbrcli.fri.braking.BrakingStop`), so its first sampled step continues the executed history
within its share of the jerk limit; a client within the rest of the limits stays within them. Computed only while an
offset is left (a loss, not the hot path).
"""

from __future__ import annotations

from typing import Any, Sequence

from ruckig import InputParameter, OutputParameter, Result, Ruckig, RuckigError, Synchronization

from trajectories.limits import JointLimits

from .braking import set_continuous_state

HOLD_TOL = 1e-9  # [rad] a step this small is no step: the controller held
REJOIN_SCALE = 1.0  # the offset's share of the velocity and jerk limits (the envelope clamps the sum; a clamp beyond
# rounding re-plans the offset from there)
REJOIN_ACCELERATION_SCALE = 0.25  # ... of the acceleration limit: a bridge during the way back zeroes the executed
# acceleration, and the offset's own acceleration adds to that step


class Rejoin:
    """The offset [rad] to add to the client's commands; ``start()`` it with the offset's last three values, then
    ``next()`` once per command until ``done``."""

    def __init__(self, limits: JointLimits, period_s: float, scale: float = REJOIN_SCALE,
                 acceleration_scale: float = REJOIN_ACCELERATION_SCALE) -> None:  # fmt: skip
        self.period_s = period_s
        self._otg = Ruckig(7, period_s)
        self._inp = InputParameter(7)
        self._out = OutputParameter(7)
        self._inp.synchronization = Synchronization.No
        lim = limits.scaled(scale)
        self._inp.max_velocity = lim.velocity.tolist()
        self._inp.max_acceleration = (limits.acceleration * acceleration_scale).tolist()
        self._inp.max_jerk = lim.jerk.tolist()
        self._inp.target_position = [0.0] * 7
        self._inp.target_velocity = [0.0] * 7
        self._inp.target_acceleration = [0.0] * 7
        self.done = True
        self.cycles = 0  # offsets computed since the last start
        self.failed = 0  # starts ruckig found no profile for (no offset then: the envelope's clamps instead)

    def start(self, e: Sequence[float], e_1: Sequence[float], e_2: Sequence[float]) -> None:
        """Bring the offset to zero from its values ``e`` (newest), ``e_1`` and ``e_2`` [rad], one period apart."""
        inp = self._inp
        set_continuous_state(inp, e, e_1, e_2, self.period_s)
        self.cycles = 0
        self.done = not (any(inp.current_position) or any(inp.current_velocity) or any(inp.current_acceleration))

    def shift(self, d: Sequence[float]) -> None:
        """The offset sent was ``d`` [rad] off the plan (the envelope clamped the command): go on from the state that
        step leaves — the plan's, plus the step's change of position, continuous velocity (step velocity + half a
        period of its acceleration) and acceleration. (A re-start from the offset's discrete history would lag the
        acceleration a period: re-started every few commands, a ramp of it never ends and the offset runs away.)"""
        inp, dt = self._inp, self.period_s
        inp.current_position = [p + x for p, x in zip(inp.current_position, d)]
        inp.current_velocity = [v + 1.5 * x / dt for v, x in zip(inp.current_velocity, d)]
        inp.current_acceleration = [a + x / (dt * dt) for a, x in zip(inp.current_acceleration, d)]

    def next(self) -> tuple[float, ...]:
        """The offset for the next command [rad] (zeros once ``done``)."""
        if self.done:
            return (0.0,) * 7
        try:
            res = self._otg.update(self._inp, self._out)
        except (RuckigError, ValueError):  # (its numerics on a degenerate offset; a result code the binding lacks)
            res = Result.Error
        self.cycles += 1
        if res not in (Result.Working, Result.Finished):  # no profile: no offset
            self.done = True
            self.failed += 1
            return (0.0,) * 7
        e = tuple(self._out.new_position)
        self._out.pass_to_input(self._inp)
        if res == Result.Finished:
            self.done = True
        return e


def far(a: Sequence[float], b: Sequence[float]) -> float:
    """[rad] the largest joint distance of two positions."""
    return max(abs(x - y) for x, y in zip(a, b))


def path_jerk(q: Sequence[float], c1: Sequence[float], c2: Sequence[float], c3: Sequence[float],
              period_s: float) -> tuple[float, ...]:  # fmt: skip
    """[rad/s³] per joint, |the jerk| of a path's command ``q`` after ``c1``, ``c2``, ``c3`` (one period apart)."""
    k = 1.0 / period_s**3
    return tuple(abs(a - 3.0 * b + 3.0 * c - d) * k for a, b, c, d in zip(q, c1, c2, c3))


def held(step: float, before: float) -> float:
    """[rad/period] the velocity after a step of the controller's own that left the limits: 0 after a hold (no step:
    the robot stopped), else the velocity ``before`` it (a jump to a late command neither stops nor speeds it)."""
    return 0.0 if abs(step) <= HOLD_TOL else before


def gap_offsets(history: Sequence[Sequence[float]], c1: Sequence[float], c2: Sequence[float], n: int,
                q: Sequence[float]) -> list[tuple[float, ...]]:  # fmt: skip
    """The executed ``history`` (three positions [rad], newest first) minus the client's path over a gap of ``n``
    periods: the parabola through its last two commands before the gap (``c1`` newest, ``c2``) and its first after
    (``q``), at the same three instants — the offset to start a :class:`Rejoin` from."""
    t0, t1 = -(n + 2.0), -(n + 1.0)  # (Lagrange weights at t = −1, −2, −3 periods before q)
    out = []
    for t, h in zip((-1.0, -2.0, -3.0), history):
        w0, w1, w2 = (t - t1) * t / ((t0 - t1) * t0), (t - t0) * t / ((t1 - t0) * t1), (t - t0) * (t - t1) / (t0 * t1)
        out.append(tuple(x - (w0 * a + w1 * b + w2 * c) for x, a, b, c in zip(h, c2, c1, q)))
    return out


def executed_history(envelope: Any, x: Sequence[float], x1: Sequence[float], x2: Sequence[float]) -> tuple:
    """The executed history (newest first) that ends at the reported ``x`` after ``x1`` and ``x2`` [rad]: these three
    if the state they leave is brakeable (``envelope.state_ok``: its acceleration within the limit); else the
    controller's own step left the limits (a hold of a moving robot, a jump to a late command) and the state is ``x``
    at the velocity it holds (:func:`held`), acceleration 0."""
    x, x1, x2 = tuple(x), tuple(x1), tuple(x2)
    if envelope.state_ok(x, x1, x2) < 0:
        return x, x1, x2
    s = tuple(held(a - b, b - c) for a, b, c in zip(x, x1, x2))
    return x, tuple(a - v for a, v in zip(x, s)), tuple(a - 2.0 * v for a, v in zip(x, s))


def gap_history(envelope: Any, x: Sequence[float], c: Sequence[float], c1: Sequence[float], n: int) -> tuple:
    """The executed history after a gap of ``n`` periods that ends at the reported ``x`` [rad], from our last two
    commands ``c`` (newest) and ``c1`` before it: at the velocity held over the gap (the average from ``c``)."""
    if n == 1:
        return executed_history(envelope, x, c, c1)
    s = tuple((a - b) / n for a, b in zip(x, c))
    return executed_history(envelope, x, tuple(a - v for a, v in zip(x, s)), tuple(a - 2.0 * v for a, v in zip(x, s)))
