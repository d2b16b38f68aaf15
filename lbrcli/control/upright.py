"""A feedback client: swing the pendulum module's rod up and balance it upright (``lbr control upright``).

The arm is a cart on a rail along base y (:class:`planners.rail.Rail`); the module's encoder arrives over the serial
port (:class:`lbrcli.lab.pendulum_serial.PendulumReader`, a background thread). Each command cycle: a new reading
corrects the delay-compensating observer, the controller (:class:`planners.feedback.UprightController`) steps the
cart within the rail's exact joint bounds, and the rail's spline turns the cart position into the joint command.

Sequence: a jerk-limited move to the rail's start (``move_to_start``; else the robot must already be there), a wait
for readings with the rod hanging calm, the swing-up, ``hold_s`` seconds balanced (measured from the first catch;
a fall re-swings and the hold goes on), then the cart is parked at the rail's centre and the session ends. No
catch within ``swing_timeout_s`` parks and ends as refused (exit 1).
"""

from __future__ import annotations

import math
import time
from typing import Sequence

from planners.feedback import Cart, DelayedObserver, Mode, UprightController, UprightOptions
from planners.feedback.upright import balance_gain
from planners.rail import Rail
from planners.rigid_pendulum import wrap_angle
from trajectories.limits import JointLimits

from lbrcli.fri import LBRClient, LBRState, OnlineMove, Phase, StopSession
from lbrcli.fri.moves import extrapolated
from lbrcli.fri.outcome import cost_figures_us

LOG_COLUMNS = ("mode", "est_phi", "est_omega", "cart_x", "cart_v", "cart_a")  # -, [rad], [rad/s], [m], [m/s], [m/s²]
_CALM = math.radians(3.0)  # [rad] the rod counts as hanging still below this …
_CALM_RATE = 0.2  # [rad/s] … and this
_FADE = 0.98  # per cycle: how fast commands return onto the rail after the controller extrapolated them


class UprightClient(LBRClient):
    """Swing-up and balance of a rod of equivalent length ``length`` [m] on ``rail``."""

    def __init__(self, rail: Rail, length: float, limits: JointLimits, *, hold_s: float = 60.0,
                 swing_timeout_s: float = 30.0, sensor_delay_s: float = 0.006, sensor_rate_hz: float = 200.0,
                 options: UprightOptions = UprightOptions(), move_to_start: bool = False, move_scale: float = 0.2,
                 start_tolerance: float = 1e-3, wait_s: float = 10.0, reader=None) -> None:  # fmt: skip
        self.rail, self.length, self.limits = rail, length, limits
        self.hold_s, self.swing_timeout_s, self.wait_s = hold_s, swing_timeout_s, wait_s
        self.sensor_delay_s, self.sensor_rate_hz = sensor_delay_s, sensor_rate_hz
        self.options = options
        self._gain = balance_gain(length, options)  # scipy's Riccati solver: never inside a cycle
        self.move_to_start, self.move_scale, self.start_tolerance = move_to_start, move_scale, start_tolerance
        self.reader = reader  # PendulumReader (set by the runner when the module is attached)
        self._q_start = tuple(rail.q_start)
        self._move: OnlineMove | None = None
        self._last: Sequence[float] | None = None
        self._last2: Sequence[float] | None = None  # the command before _last
        self._off: list[float] | None = None  # [rad] commands − rail after an extrapolation (fading), and …
        self._off_prev: list[float] = []  # … one cycle earlier
        self._reading = None
        self._calm = 0  # commands in a row with the rod hanging still
        self._waited = 0
        self._t = 0.0  # [s] since the controller started
        self.cart: Cart | None = None
        self.ctl: UprightController | None = None
        self.obs: DelayedObserver | None = None
        # figures
        self.swing_up_s: float | None = None  # [s] from the start of the swing-up to the first catch
        self.balanced_s = 0.0  # [s] in BALANCE in total
        self.longest_balance_s = 0.0  # [s]
        self._run = 0.0
        self.max_theta_balanced = 0.0  # [rad] largest |estimated angle from upright| while balancing after 1 s in
        self.readings = 0
        self.cost_ns: list[int] = []  # per-cycle controller cost (observer + controller + rail) [ns]
        self.finished_reason: str | None = None

    # -- monitoring ------------------------------------------------------------------------------------------
    def _check_start(self, state: LBRState) -> None:
        q = state.measured_joint_position
        d = max(abs(a - b) for a, b in zip(q, self._q_start))
        if d > self.start_tolerance and not self.move_to_start:
            raise StopSession(f"the robot is {d:.4f} rad from the rail's start pose (more than {self.start_tolerance:g} "
                              "rad); move it there first (lbr ptp) or use --move-to-start", completed=False)

    def monitor(self, state: LBRState) -> None:
        self.phase = Phase.NONE
        if self._last is None:
            self._check_start(state)

    def wait_for_command(self, state: LBRState) -> None:
        self.hold_ipo(state)
        self.phase = Phase.NONE

    # -- commanding ------------------------------------------------------------------------------------------
    def command(self, state: LBRState) -> Sequence[float] | None:
        if self._last is None:
            self._check_start(state)
            period = state.sample_time * state.receive_multiplier
            self._period = period
            self._move = OnlineMove(self.limits, period, self.move_scale)
            self._move.start(state.ipo_joint_position, self._q_start)
            self._last = state.ipo_joint_position
        if not self.reply_due:
            return self._last
        if self.skipped:
            self._bridged(self.skipped)
        move = self._move
        if not move.done:
            self._last2, self._last = self._last, move.next()
            self.phase = Phase.MOVE
            return self._last
        if self.ctl is None:
            self._wait_for_readings()
            self._last2 = self._last = self._q_start
            self.phase = Phase.WAIT
            return self._last
        t0 = time.perf_counter_ns()
        q = self._control()
        if self._off is not None:
            q = self._offset(q)
        self.cost_ns.append(time.perf_counter_ns() - t0)
        self._last2, self._last = self._last, q
        self.phase = Phase.TRAJECTORY
        return q

    def _bridged(self, n: int) -> None:
        """The controller extrapolated our last command at constant joint velocity for ``n`` periods (its messages
        were lost): a move is re-planned from there; the cart (nearly straight on its rail over a few periods) coasts
        as the joints did and the observer is predicted through the gap."""
        if self._last2 is None:
            return
        dt = self._period
        q, self._last2, vel = extrapolated(self._last, self._last2, n, dt)
        self._last = q
        if not self._move.done:
            self._move.skip(n)  # it goes on in step with its plan
        elif self.cart is not None:
            # the cart's acceleration resumes where it was: ramping it up from 0 again would starve the balance of
            # acceleration at every gap (the extrapolation's own jump is the controller's)
            cart = self.cart
            for _ in range(n):
                cart.x += cart.v * dt
                self.obs.predict(0.0)
            self._t += n * dt
            # the extrapolation left the rail's curve along its tangent: the commands carry that offset on, and fade
            # it, so that the next command's second difference is the rail's own (no doubled curvature term)
            on_rail = self.rail.joints_list(cart.x)
            before = self.rail.joints_list(cart.x - cart.v * dt)
            self._off = [a - b for a, b in zip(q, on_rail)]
            self._off_prev = [a - b for a, b in zip(self._last2, before)]

    def _offset(self, q: Sequence[float]) -> tuple[float, ...]:
        """``q`` plus the off-rail offset of an extrapolation, decaying with a double pole at ``_FADE`` per cycle."""
        off, prev = self._off, self._off_prev
        nxt = [2.0 * _FADE * a - _FADE * _FADE * b for a, b in zip(off, prev)]
        self._off_prev, self._off = off, nxt
        if max(abs(v) for v in nxt) < 1e-15 and max(abs(v) for v in off) < 1e-15:
            self._off = None
        return tuple(a + b for a, b in zip(q, nxt))

    def _wait_for_readings(self) -> None:
        """Hold the start until the rod has hung still for 0.5 s of readings; then start the controller."""
        r = self.reader.latest if self.reader is not None else None
        self._waited += 1
        if r is not None and abs(r.theta) < _CALM and abs(r.omega) < _CALM_RATE:
            self._calm += 1
        else:
            self._calm = 0
        if self._calm * self._period >= 0.5:
            self._start_controller(r.theta)
        elif self._waited * self._period > self.wait_s:
            what = ("no reading arrived from the pendulum module" if r is None else
                    f"the rod did not hang still (last reading {math.degrees(r.theta):.1f}°, {r.omega:.2f} rad/s)")
            raise StopSession(f"{what} within {self.wait_s:g} s", completed=False)

    def _start_controller(self, phi: float) -> None:
        dt = self._period
        self.cart = Cart(self.rail.limits, dt, bounds=self.rail.local_bounds)
        self.ctl = UprightController(self.length, self.cart, self.options, self._gain)
        # the reading is the angle one delay ago; half the jitter of a radio link is in the delay the user gives
        self.obs = DelayedObserver(self.length, dt, self.sensor_delay_s, 1.0 / self.sensor_rate_hz, phi0=phi)
        self._reading = self.reader.latest

    def _control(self) -> Sequence[float]:
        obs, ctl, cart = self.obs, self.ctl, self.cart
        dt = self._period
        r = self.reader.latest
        if r is not self._reading:
            self._reading = r
            obs.correct(r.theta)
            self.readings += 1
        before = ctl.mode
        ctl.update(obs.phi, obs.omega)
        obs.predict(cart.a)
        self._t += dt
        if ctl.mode is Mode.BALANCE:
            if before is not Mode.BALANCE:
                self._run = 0.0
                if self.swing_up_s is None:
                    self.swing_up_s = self._t
            self._run += dt
            self.balanced_s += dt
            self.longest_balance_s = max(self.longest_balance_s, self._run)
            if self._run > 1.0:
                self.max_theta_balanced = max(self.max_theta_balanced, abs(wrap_angle(obs.phi - math.pi)))
            if self.swing_up_s is not None and self._t - self.swing_up_s >= self.hold_s:
                ctl.park()
                self.finished_reason = f"balanced upright, parked after {self.hold_s:g} s"
        elif ctl.mode is Mode.SWING_UP and self.swing_up_s is None and self._t > self.swing_timeout_s:
            ctl.park()
            self.finished_reason = f"no catch upright within {self.swing_timeout_s:g} s"
        elif ctl.mode is Mode.PARK and ctl.at_rest:
            ok = self.swing_up_s is not None and self._t - self.swing_up_s >= self.hold_s
            raise StopSession(self.finished_reason or "parked", completed=ok)
        return self.rail.joints_list(cart.x)

    # -- log and figures -------------------------------------------------------------------------------------
    def log_values(self, mon=None) -> tuple[float, ...]:
        if self.ctl is None:
            return (-1.0, 0.0, 0.0, 0.0, 0.0, 0.0)  # mode −1: not started, nothing estimated yet
        c = self.cart
        return (float(self.ctl.mode), self.obs.phi, self.obs.omega, c.x, c.v, c.a)

    def figures(self) -> dict:
        return {
            "swing_up_s": self.swing_up_s,
            "balanced_s": self.balanced_s,
            "longest_balance_s": self.longest_balance_s,
            "catches": self.ctl.catches if self.ctl else 0,
            "falls": self.ctl.falls if self.ctl else 0,
            "max_theta_balanced_deg": math.degrees(self.max_theta_balanced),
            "pendulum_readings": self.readings,
            "cart_trimmed_cycles": self.cart.trimmed if self.cart else 0,
            **cost_figures_us(self.cost_ns),
        }
