"""A feedback client: swing the pendulum module's rod up and balance it upright (``lbr control upright``).

The arm is a cart on a rail along base y (:class:`planners.rail.Rail`); the module's encoder arrives over the serial
port (:class:`lbrcli.lab.pendulum_serial.PendulumReader`, a background thread). The experiment is
:class:`planners.feedback.session.UprightSession`: wait for the rod to hang still, identify it from a short push
(length, friction, the encoder's offset and sign, the delay; the fit runs in a worker process — ``fitter``), swing
it up, balance it for ``hold_s`` without a fall (a fall is caught again within ``recatch_s`` or the run fails), bring
it down gently and park; every phase has a time limit, so the session always ends. Each command cycle a new reading
goes to the session, the session steps the cart within the rail's exact joint bounds, and the rail's spline turns the
cart position into the joint command. Before all that, a jerk-limited move to the rail's start (``move_to_start``).
Ends with :class:`StopSession`: completed only when the hold was met.
"""

from __future__ import annotations

import time
from typing import Any, Sequence

from planners.feedback import Cart, UprightOptions
from planners.feedback.session import SessionOptions, UprightSession
from planners.feedback.upright import balance_gain
from planners.rail import Rail
from trajectories.limits import JointLimits

from lbrcli.fri import LBRClient, LBRState, OnlineMove, Phase, StopSession
from lbrcli.fri.moves import extrapolated, fade_factor
from lbrcli.fri.outcome import cost_figures_us

LOG_COLUMNS = ("mode", "est_phi", "est_omega", "cart_x", "cart_v", "cart_a")  # -, [rad], [rad/s], [m], [m/s], [m/s²]
# the log's mode: −1 before the controller runs (waiting, identifying), then the controller's (0 swing-up,
# 1 balance, 2 park, 3 lowering)
_FADE = 0.98  # per cycle: the fastest the commands return onto the rail after the controller extrapolated them …
_FADE_JERK = 0.07  # … and the share of each joint's jerk limit that return may use (the rail's bounds keep the
# cart's own commands within 0.9 of it)
_PHASES = {"wait": Phase.WAIT, "identify": Phase.MOVE, "fit": Phase.WAIT, "swing": Phase.TRAJECTORY,
           "balance": Phase.TRAJECTORY, "lower": Phase.SETTLE, "park": Phase.SETTLE, "done": Phase.SETTLE}  # fmt: skip


class UprightClient(LBRClient):
    """Swing-up and balance of a rod of nominal equivalent length ``length`` [m] on ``rail``."""

    def __init__(self, rail: Rail, length: float, limits: JointLimits, *, session: SessionOptions = SessionOptions(),
                 sensor_rate_hz: float = 200.0, options: UprightOptions = UprightOptions(), move_to_start: bool = False,
                 move_scale: float = 0.2, start_tolerance: float = 1e-3, reader=None, fitter=None) -> None:  # fmt: skip
        self.rail, self.length, self.limits = rail, length, limits
        self.session_options, self.sensor_rate_hz, self.options = session, sensor_rate_hz, options
        self._nominal_gain = balance_gain(length, options)  # scipy's Riccati solver: never inside a cycle
        self.move_to_start, self.move_scale, self.start_tolerance = move_to_start, move_scale, start_tolerance
        self.reader = reader  # PendulumReader (set by the runner when the module is attached)
        self.fitter = fitter  # runs the identification outside the loop (lbrcli.control.fitter.ProcessFitter)
        self._q_start = tuple(rail.q_start)
        self._move: OnlineMove | None = None
        self._last: Sequence[float] | None = None
        self._last2: Sequence[float] | None = None  # the command before _last
        self._off: list[float] | None = None  # [rad] commands − rail after an extrapolation (fading), and …
        self._off_prev: list[float] = []  # … one cycle earlier
        self._fade = _FADE  # the fade's factor per cycle (jerk-limited: :func:`~lbrcli.fri.moves.fade_factor`)
        self._reading: Any = None
        self._period = 0.0
        self.cart: Cart | None = None
        self.session: UprightSession | None = None
        self.cost_ns: list[int] = []  # per-cycle controller cost (session + rail) [ns]

    # -- monitoring ------------------------------------------------------------------------------------------
    def _check_start(self, state: LBRState) -> None:
        q = state.measured_joint_position
        d = max(abs(a - b) for a, b in zip(q, self._q_start))
        if d > self.start_tolerance and not self.move_to_start:
            raise StopSession(
                f"the robot is {d:.4f} rad from the rail's start pose (more than {self.start_tolerance:g} "
                "rad); move it there first (lbr ptp) or let the session move it there (UprightClient.move_to_start)",
                completed=False,
            )

    def monitor(self, state: LBRState) -> None:
        self._check_start(state)
        self.phase = Phase.NONE

    def wait_for_command(self, state: LBRState) -> None:
        self.hold_ipo(state)
        self.phase = Phase.NONE

    # -- commanding ------------------------------------------------------------------------------------------
    def command(self, state: LBRState) -> Sequence[float] | None:
        if self._last is None:
            self._check_start(state)
            period = self.command_period_s
            self._period = period
            self._move = OnlineMove(self.limits, period, self.move_scale)
            self._move.start(state.ipo_joint_position, self._q_start)
            self._last = state.ipo_joint_position
            self.cart = Cart(self.rail.limits, period, bounds=self.rail.local_bounds)
            self.session = UprightSession(self.length, self.cart, 1.0 / self.sensor_rate_hz, self.session_options,
                                          self.options, self.fitter, self._nominal_gain)  # fmt: skip
        if not self.reply_due:
            return self._last
        if self.skipped:
            self._bridged(self.skipped)
        move = self._move
        if not move.done:  # type: ignore[union-attr]
            self._last2, self._last = self._last, move.next()  # type: ignore[union-attr]
            self.phase = Phase.MOVE
            return self._last
        t0 = time.perf_counter_ns()
        session = self.session
        r = self.reader.latest if self.reader is not None else None
        if r is not None and r is not self._reading:
            self._reading = r
            session.reading(r.theta)  # type: ignore[union-attr]
        session.step()  # type: ignore[union-attr]
        if session.done:  # type: ignore[union-attr]
            raise StopSession(session.verdict or session.error or "done", completed=session.succeeded)  # type: ignore[union-attr]
        q = self.rail.joints_list(self.cart.x)  # type: ignore[union-attr]
        if self._off is not None:
            q = self._offset(q)
        self.cost_ns.append(time.perf_counter_ns() - t0)
        self._last2, self._last = self._last, q
        self.phase = _PHASES[session.phase]  # type: ignore[union-attr]
        return q

    def _bridged(self, n: int) -> None:
        """The controller extrapolated our last command at constant joint velocity for ``n`` periods (its messages
        were lost): a move goes on in step with its plan; the cart (nearly straight on its rail over a few periods)
        coasts as the joints did and the observer is predicted through the gap."""
        if self._last2 is None:
            return
        dt = self._period
        q, self._last2, _ = extrapolated(self._last, self._last2, n, dt)
        self._last = q
        if not self._move.done:  # type: ignore[union-attr]
            self._move.skip(n)  # type: ignore[union-attr]
            return
        cart = self.cart
        obs = self.session.obs if self.session is not None else None
        # the cart's acceleration resumes where it was: ramping it up from 0 again would starve the balance of
        # acceleration at every gap (the extrapolation's own jump is the controller's)
        for _ in range(n):
            cart.x += cart.v * dt  # type: ignore[union-attr]
            if obs is not None:
                obs.predict(0.0)
        # the extrapolation left the rail's curve along its tangent: the commands carry that offset on, and fade it,
        # so that the next command's second difference is the rail's own (no doubled curvature term)
        on_rail = self.rail.joints_list(cart.x)  # type: ignore[union-attr]
        before = self.rail.joints_list(cart.x - cart.v * dt)  # type: ignore[union-attr]
        self._off = [a - b for a, b in zip(q, on_rail)]
        self._off_prev = [a - b for a, b in zip(self._last2, before)]
        jerk = [_FADE_JERK * j for j in self.limits.jerk]
        self._fade = fade_factor(self._off, self._off_prev, jerk, dt, _FADE)

    def _offset(self, q: Sequence[float]) -> tuple[float, ...]:
        """``q`` plus the off-rail offset of an extrapolation, decaying with a double pole at ``_fade`` per cycle."""
        off, prev, f = self._off, self._off_prev, self._fade
        nxt = [2.0 * f * a - f * f * b for a, b in zip(off, prev)]  # type: ignore[arg-type]
        self._off_prev, self._off = off, nxt  # type: ignore[assignment]
        if max(abs(v) for v in nxt) < 1e-15 and max(abs(v) for v in off) < 1e-15:  # type: ignore[arg-type]
            self._off = None
        return tuple(a + b for a, b in zip(q, nxt))

    # -- log and figures -------------------------------------------------------------------------------------
    def log_values(self, mon=None) -> tuple[float, ...]:
        s = self.session
        if s is None or s.ctl is None or s.obs is None:
            c = self.cart
            return (-1.0, 0.0, 0.0, c.x, c.v, c.a) if c is not None else (-1.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        c = self.cart
        return (float(s.ctl.mode), s.obs.phi, s.obs.omega, c.x, c.v, c.a)  # type: ignore[union-attr]

    def figures(self) -> dict:
        f = self.session.figures() if self.session is not None else {"succeeded": False}
        f["cart_trimmed_cycles"] = self.cart.trimmed if self.cart else 0
        f.update(cost_figures_us(self.cost_ns))
        return f
