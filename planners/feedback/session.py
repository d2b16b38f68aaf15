"""The whole upright experiment as one state machine, the same for the FRI client and the fast simulation: wait for
the rod to hang still, identify it (:mod:`.identify`), swing it up, balance it for the hold, bring it down gently
and park — with bounded time in every phase, so that it always ends, and an honest verdict.

Phases: ``WAIT`` (the last 0.5 s of readings within ``calm_range``: encoder noise of a few counts does not block it),
``IDENTIFY`` (at rest, the excitation, the free swing; the readings and the cart's accelerations recorded),
``FIT`` (the cart holds while ``fitter`` — a worker process in the FRI client — identifies the rod and computes the
balance gain for it), ``SWING`` / ``BALANCE`` (:class:`~.upright.UprightController` on the delay-compensating observer
of the identified rod; after a fall the rod must be caught again within ``recatch_s``), ``LOWER`` (the reverse of the
swing-up), ``PARK`` (the cart to the rail's centre, at rest), ``DONE``. ``succeeded`` only when the rod stayed
balanced for ``hold_s`` in one run without a fall. Readings arrive as raw encoder angles [rad]; the identified sign
and offset turn them into the controller's angle (a sign that disagrees with ``encoder_sign`` is an error: detected,
not guessed).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from ..rigid_pendulum import wrap_angle
from .cart import Cart
from .identify import DECAY_S, QUIET_S, IdentificationError, RodIdentification, excitation, identify
from .observer import DelayedObserver
from .upright import Mode, UprightController, UprightOptions, balance_gain, catch_reach, damping_limit

WAIT, IDENTIFY, FIT, SWING, BALANCE, LOWER, PARK, DONE = (
    "wait", "identify", "fit", "swing", "balance", "lower", "park", "done")  # fmt: skip


@dataclass(frozen=True)
class SessionOptions:
    """Times [s], thresholds and the identification's settings of an upright session."""

    hold_s: float = 60.0  # balanced in one run without a fall: the goal
    swing_timeout_s: float = 30.0  # from the swing-up's start to the first catch
    recatch_s: float = 20.0  # after a fall, to the next catch
    wait_s: float = 10.0  # for the rod to hang still
    calm_range: float = math.radians(2.0)  # [rad] the readings' range over CALM_S while hanging still
    identify: bool = True  # identify the rod before the swing-up (else: the nominal model)
    # [m] the cart's excursion of the excitation (out 2× this and back); None: a swing of ``excite_swing`` [rad] at
    # resonance for the nominal rod (amplitude = swing·l/π), within 40 % of the rail's travel — bearing friction eats
    # into it, and the fit needs a few half-periods of free swing
    excite_amplitude: float | None = None
    excite_swing: float = 0.8
    fit_timeout_s: float = 30.0
    fit_wait_s: float = 0.0  # the fit's result is taken no earlier than this after the free swing: in a lock-step
    # simulation the same simulated instant however fast the computer fits (0: as soon as it is ready)
    lower_ramp_s: float = 6.0  # the energy ramp of the gentle lowering
    lower_timeout_s: float = 20.0  # the lowering and the park together
    encoder_sign: int = 1  # the sign the module's encoder is expected to have
    sensor_delay_s: float = 0.006  # assumed without identification
    actuation_cycles: int = 2  # cycles between a command and the pivot's motion (the controller's interpolation)


CALM_S = 0.5  # [s]


@dataclass(frozen=True)
class FitResult:
    """What the fitter hands back: the rod, and the balance gain for it (both computed outside the FRI cycle)."""

    rod: RodIdentification
    gain: tuple[float, ...]
    reach: np.ndarray | None = None  # the balance's catch prediction (upright.catch_reach)
    damping_limit: float = math.inf  # [1/s] the rod damping the balance tolerates (upright.damping_limit)


def fit_rod(t_readings: np.ndarray, readings: np.ndarray, accel: np.ndarray, dt: float, nominal_length: float,
            t0: float, options: UprightOptions) -> FitResult:  # fmt: skip
    """Identify the rod and compute its balance gain (picklable: runs in a worker process)."""
    rod = identify(t_readings, readings, accel, dt, nominal_length, t0)
    length = rod.equivalent_length
    gain = balance_gain(length, options)
    return FitResult(rod, gain, catch_reach(length, gain, options.catch_horizon), damping_limit(length, gain))


class UprightSession:
    """One upright experiment on ``cart`` (stepped every ``cart.dt``) for a rod of nominal equivalent length
    ``length`` [m]. Call :meth:`reading` when the encoder's angle [rad] arrives, then :meth:`step` once per cycle.
    ``fitter(args) -> handle``: starts :func:`fit_rod` (``handle.done()``, ``handle.result()``); None runs it here."""

    def __init__(self, length: float, cart: Cart, reading_interval: float, options: SessionOptions = SessionOptions(),
                 controller: UprightOptions = UprightOptions(), fitter: Callable[[tuple], Any] | None = None,
                 nominal_gain: tuple[float, ...] | None = None) -> None:  # fmt: skip
        self.length, self.cart, self.o, self.co = length, cart, options, controller
        self.dt = cart.dt
        self.reading_interval = reading_interval
        self.fitter = fitter
        self._nominal_gain = nominal_gain
        self._nominal_reach = (catch_reach(length, nominal_gain, controller.catch_horizon)
                               if nominal_gain is not None and any(nominal_gain) else None)  # fmt: skip
        self.phase = WAIT
        self.t = 0.0  # [s] since the session started
        self._phase_t = 0.0  # [s] since the phase started
        self._recent: list[tuple[float, float]] = []  # (t, raw) of the last CALM_S of readings
        self._rec_t: list[float] = []
        self._rec_y: list[float] = []
        self._rec_a: list[float] = []
        self._fit: Any = None
        self.rod: RodIdentification | None = None
        self.sign, self.offset = options.encoder_sign, 0.0
        self.obs: DelayedObserver | None = None
        self.ctl: UprightController | None = None
        self.error: str | None = None  # why it failed (set with DONE when it did)
        self.succeeded = False
        self.verdict = ""
        # figures
        self.swing_up_s: float | None = None  # [s] from the swing-up's start to the first catch
        self.balanced_s = 0.0
        self.longest_balance_s = 0.0
        self._run = 0.0
        self._fell_at: float | None = None
        self.max_theta_balanced = 0.0  # [rad] from upright, after 1 s of a run
        self.readings = 0
        self._pending: float | None = None

    # -- inputs -----------------------------------------------------------------------------------------------
    def reading(self, raw: float) -> None:
        """The encoder's angle [rad] arrived this cycle."""
        self._pending = raw
        self.readings += 1

    def _enter(self, phase: str) -> None:
        self.phase = phase
        self._phase_t = 0.0

    def _fail(self, text: str) -> None:
        """Stop what it does: lower the rod if it is up, else park; the session fails with ``text``."""
        self.error = self.error or text
        self.verdict = text
        self._leave()

    def _leave(self) -> None:
        if self.ctl is not None and self.phase in (SWING, BALANCE):
            self.ctl.lower(self.o.lower_ramp_s)
            self._enter(LOWER)
        else:
            self._enter(PARK)

    # -- one cycle --------------------------------------------------------------------------------------------
    def step(self) -> None:
        """One cycle: the phase's logic, then the cart one step."""
        dt, o = self.dt, self.o
        self.t += dt
        self._phase_t += dt
        raw, self._pending = self._pending, None
        phase = self.phase
        if phase == WAIT:
            self._wait(raw)
        elif phase == IDENTIFY:
            self._identify(raw)
        elif phase == FIT:
            self._hold()
            self._collect_fit()
        elif phase in (SWING, BALANCE, LOWER):
            self._control(raw)
        elif phase == PARK:
            if self.ctl is None:
                self.ctl = UprightController(self.length, self.cart, self.co, self._nominal_gain or (0.0,) * 5)
            if self.ctl.mode is not Mode.PARK:
                self.ctl.park()
            self.ctl.update(0.0, 0.0)
            if self.ctl.at_rest or self._phase_t > o.lower_timeout_s:
                self._enter(DONE)
        else:
            self._hold()

    def _hold(self) -> None:
        """The cart brought to rest where it is."""
        c = self.cart
        c.track(-3.0 * c.v, self.co.accel_lag)

    def _wait(self, raw: float | None) -> None:
        self._hold()
        if raw is not None:
            rec = self._recent
            rec.append((self.t, raw))
            while rec and rec[0][0] < self.t - CALM_S:
                rec.pop(0)
            span = rec[-1][0] - rec[0][0]
            values = [v for _, v in rec]
            if span >= CALM_S * 0.9 and max(values) - min(values) <= self.o.calm_range:
                self.offset = float(np.median(values))  # until the identification says better
                if self.o.identify:
                    self._enter(IDENTIFY)
                else:
                    self._start_control(
                        self.length, self._nominal_gain, self.o.sensor_delay_s, 0.0, 0.0, self._nominal_reach
                    )
                return
        if self._phase_t > self.o.wait_s:
            rec = self._recent
            what = ("no reading arrived from the pendulum module" if not rec else
                    f"the rod did not hang still (its readings spanned {math.degrees(max(v for _, v in rec) - min(v for _, v in rec)):.1f}° "
                    f"over the last {CALM_S:g} s)")  # fmt: skip
            self._fail(f"{what} within {self.o.wait_s:g} s")

    def _identify(self, raw: float | None) -> None:
        o = self.o
        period = 2 * math.pi * math.sqrt(self.length / 9.81)
        t = self._phase_t
        amplitude = o.excite_amplitude
        if amplitude is None:
            amplitude = min(max(o.excite_swing * self.length / math.pi, 0.02), 0.4 * self.cart.limits.travel)
        if t < QUIET_S + period:
            self.cart.track(excitation(t - QUIET_S, period, amplitude), self.dt)
        else:  # (after lost messages the controller held the cart's velocity, not its acceleration: the push may
            self._hold()  # end moving; brought to rest, not left drifting to the rail's end)  # the governor keeps the rail's bounds; the record has what it did
        self._rec_a.append(self.cart.a)
        if raw is not None:
            self._rec_t.append(t)
            self._rec_y.append(raw)
        if t >= QUIET_S + period + DECAY_S:
            args = (np.array(self._rec_t), np.array(self._rec_y), np.array(self._rec_a), self.dt, self.length,
                    self.dt, self.co)  # fmt: skip
            self._fit = self.fitter(args) if self.fitter is not None else _Done(lambda: fit_rod(*args))
            self._enter(FIT)

    def _collect_fit(self) -> None:
        h = self._fit
        if not h.done() or self._phase_t < self.o.fit_wait_s:
            if self._phase_t > self.o.fit_timeout_s:
                self._fail(f"the identification did not finish within {self.o.fit_timeout_s:g} s")
            return
        try:
            res: FitResult = h.result()
        except IdentificationError as exc:
            self._fail(f"identification: {exc}")
            return
        except Exception as exc:  # noqa: BLE001 - a worker that died: say so, end safely
            self._fail(f"identification failed: {type(exc).__name__}: {exc}")
            return
        rod = res.rod
        self.rod = rod
        if rod.sign != self.o.encoder_sign:
            self._fail(f"the pendulum module's encoder reads the rod reversed (the arm's push swung it the other way "
                       f"than the model says, {rod.gain:.2f}× the model's swing): give SessionOptions.encoder_sign "
                       f"{-self.o.encoder_sign} or swap the encoder's direction")  # fmt: skip
            return
        self.offset = rod.offset
        sensor_delay = max(0.0, rod.delay - self.o.actuation_cycles * self.dt)
        self._start_control(
            rod.equivalent_length, res.gain, sensor_delay, rod.damping, rod.coulomb, res.reach, res.damping_limit
        )

    def _start_control(
        self,
        length: float,
        gain,
        sensor_delay: float,
        damping: float,
        coulomb: float,
        reach: np.ndarray | None = None,
        limit: float = math.inf,
    ) -> None:
        phi0 = 0.0
        if self._rec_y:
            phi0 = self.sign * (self._rec_y[-1] - self.offset)
        self.obs = DelayedObserver(length, self.dt, sensor_delay, self.reading_interval, friction=damping,
                                   actuation_delay=self.o.actuation_cycles, phi0=phi0, coulomb=coulomb)  # fmt: skip
        self.ctl = UprightController(length, self.cart, self.co, gain, friction=coulomb, reach=reach, limit=limit)
        self._swing_t0 = self.t
        self._enter(SWING)

    def _control(self, raw: float | None) -> None:
        obs, ctl, o = self.obs, self.ctl, self.o
        if raw is not None:
            obs.correct(wrap_angle(self.sign * (raw - self.offset)))  # type: ignore[union-attr]
        before = ctl.mode  # type: ignore[union-attr]
        ctl.update(obs.phi, obs.omega)  # type: ignore[union-attr]
        obs.predict(self.cart.a)  # type: ignore[union-attr]
        dt = self.dt
        if self.phase == LOWER:
            amplitude_ok = abs(wrap_angle(obs.phi)) < math.radians(10) and abs(obs.omega) < 0.5  # type: ignore[union-attr]
            if (self._phase_t > o.lower_ramp_s and amplitude_ok) or self._phase_t > o.lower_timeout_s:
                self._enter(PARK)
            return
        if ctl.mode is Mode.BALANCE:  # type: ignore[union-attr]
            if before is not Mode.BALANCE:
                self._run = 0.0
                self._fell_at = None
                if self.swing_up_s is None:
                    self.swing_up_s = self.t - self._swing_t0
            self.phase = BALANCE
            self._run += dt
            self.balanced_s += dt
            self.longest_balance_s = max(self.longest_balance_s, self._run)
            if self._run > 1.0:
                self.max_theta_balanced = max(self.max_theta_balanced, abs(wrap_angle(obs.phi - math.pi)))  # type: ignore[union-attr]
            if self._run >= o.hold_s:
                self.succeeded = True
                self.verdict = f"balanced upright for {o.hold_s:g} s" + (
                    f" (after {ctl.falls} fall{'s' if ctl.falls != 1 else ''} and re-catches)" if ctl.falls else ""
                )  # type: ignore[union-attr]
                ctl.lower(o.lower_ramp_s)  # type: ignore[union-attr]
                self._enter(LOWER)
            return
        self.phase = SWING
        if before is Mode.BALANCE:
            self._fell_at = self.t
        if self.swing_up_s is None and self.t - self._swing_t0 > o.swing_timeout_s:
            self._fail(f"no catch upright within {o.swing_timeout_s:g} s of swinging")
        elif self._fell_at is not None and self.t - self._fell_at > o.recatch_s:
            self._fail(f"the rod fell {self._fell_at - self._swing_t0:.1f} s into the swing-up and was not caught "
                       f"again within {o.recatch_s:g} s")  # fmt: skip

    # -- results ----------------------------------------------------------------------------------------------
    @property
    def done(self) -> bool:
        return self.phase == DONE

    @property
    def falls(self) -> int:
        return self.ctl.falls if self.ctl is not None else 0

    @property
    def catches(self) -> int:
        return self.ctl.catches if self.ctl is not None else 0

    def figures(self) -> dict:
        f = {"succeeded": self.succeeded, "verdict": self.verdict or self.error, "swing_up_s": self.swing_up_s,
             "balanced_s": self.balanced_s, "longest_balance_s": self.longest_balance_s, "catches": self.catches,
             "falls": self.falls, "max_theta_balanced_deg": math.degrees(self.max_theta_balanced),
             "pendulum_readings": self.readings}  # fmt: skip
        if self.rod is not None:
            f.update(self.rod.to_dict())
        return f


class _Done:
    """A fit run in place (no worker): the handle the session polls."""

    def __init__(self, fn: Callable[[], Any]) -> None:
        try:
            self._value, self._error = fn(), None
        except Exception as exc:  # noqa: BLE001 - handed to the session as the worker's would be
            self._value, self._error = None, exc

    def done(self) -> bool:
        return True

    def result(self) -> Any:
        if self._error is not None:
            raise self._error
        return self._value
