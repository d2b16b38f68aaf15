"""Swing a rigid pendulum up from hanging and balance it upright with a cart (the arm on its rail).

Modes: ``SWING_UP`` pumps energy (Åström–Furuta): the cart acceleration a = −sat(k_E·(E_top − E)·φ̇·cos φ) − k_x·x
− k_v·v, so Ė = −a·φ̇·cos φ raises the swing energy E toward the upright's; ``BALANCE`` once the rod is within
``catch_angle`` of upright with less than ``catch_rate`` and the balance can catch it from there on the rail — LQR
state feedback on (x, v, a, φ − π, φ̇) with the jerk as input, whose linear closed loop from the state at the catch
(:func:`catch_reach`) must keep the cart within ``catch_travel`` of the rail's travel (a rod caught near an end, or
falling toward one, is let swing on and caught on a later pass); while it balances calmly the cart dithers
(:func:`dither_amplitude`) so that the bearing's dry friction cannot make the rod stick and slip; back to
``SWING_UP`` if it falls beyond ``drop_angle``. ``PARK`` (after :meth:`park`) stops balancing and
brings the cart back to the rail's centre and to rest. ``LOWER`` (after :meth:`lower`) brings a balanced rod down as
the swing-up brought it up, in reverse: the energy follows a target ramped from the upright's to the hanging rod's
over ``ramp_s``, so the rod swings down in ever smaller swings instead of falling. Every mode drives the
:class:`~.cart.Cart`, whose governor keeps the rail's bounds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from ..rigid_pendulum import swing_energy, wrap_angle
from ..pendulum import G
from .cart import Cart
from .lqr import lqr_gain


class Mode(IntEnum):
    """What the upright controller is doing (the log's `mode` column): swinging up, balancing, parking the cart."""

    SWING_UP = 0
    BALANCE = 1
    PARK = 2
    LOWER = 3


@dataclass(frozen=True)
class UprightOptions:
    """Gains of the swing-up and the balance."""

    swing_accel: float = 0.7  # share of the cart's acceleration bound the pumping may use [-]
    energy_gain: float = 8.0  # k_E [s²/m²·…]: pumping saturates once (E_top − E)·|φ̇| is above swing accel / k_E
    centre_gain: float = 4.0  # k_x [1/s²] keeps the swing near the rail's centre
    centre_damping: float = 3.0  # k_v [1/s]
    start_rate: float = 0.3  # [rad/s] below this (hanging half) the swing is started by a kick
    accel_lag: float = 0.03  # [s] how fast the cart follows the swing-up's acceleration
    catch_angle: float = 0.35  # [rad] from upright
    catch_rate: float = 3.0  # [rad/s]
    # share of the rail's travel the balance may use after a catch (predicted) [-]: the linear prediction leaves out
    # the rail's acceleration bound, which shrinks with the speed and toward the ends — on the ±0.4 m rail a catch
    # predicted to 0.95 of it ran to the end and fell; 0.7 of it catches where 0.95 of a ±0.3 m rail did
    catch_travel: float = 0.7
    catch_horizon: float = 3.0  # [s] of the closed loop predicted at a catch
    drop_angle: float = 0.7  # [rad] from upright
    weights: tuple[float, float, float, float, float] = (30.0, 10.0, 0.1, 200.0, 5.0)  # (x, v, a, θ, θ̇)
    jerk_weight: float = 1e-3
    # dither while balancing: a sine of the cart's acceleration (see :func:`dither_amplitude`) so that the rod never
    # sticks in its bearing — averaged over the dither, the dry friction acts as a damper the balance tolerates
    # instead of a stick-slip limit cycle
    dither_gain: float = 2.0  # [-] the amplitude over the least that keeps the averaged friction tolerable
    dither_hz: float = 3.0  # [Hz]
    dither_cap: float = 0.5  # [-] share of the cart's acceleration bound the dither may use at most
    dither_calm: float = 0.1  # [rad] from upright: beyond this (a knock, the catch) no dither …
    dither_on_s: float = 1.0  # [s] … and its amplitude's ramp up once within


def balance_gain(length: float, options: UprightOptions = UprightOptions()) -> tuple[float, ...]:
    """The balance's LQR gain K (5,) for a rod of equivalent ``length`` [m] (scipy; compute it before a session)."""
    return tuple(float(k) for k in lqr_gain(length, True, options.weights, options.jerk_weight))


def damping_limit(length: float, gain: tuple[float, ...], top: float = 1e3) -> float:
    """The largest viscous damping c [1/s] of the rod's bearing (θ̈ −= c·θ̇) under which the balance's linear closed
    loop (gain K, rod of equivalent ``length`` [m]) stays stable (bisection on its eigenvalues; inf above ``top``).
    It is finite for every balance: a rod held stiffly by its bearing leaves the cart's own loop, unstable by design.
    """
    from .lqr import cart_pendulum

    a, b = cart_pendulum(length, True)
    closed = a - b @ np.asarray(gain, dtype=float).reshape(1, 5)

    def stable(c: float) -> bool:
        m = closed.copy()
        m[4, 4] -= c
        return bool(np.linalg.eigvals(m).real.max() < 0.0)

    if not stable(0.0):
        return 0.0
    if stable(top):
        return math.inf
    lo, hi = 0.0, top
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return lo


def dither_amplitude(length: float, friction: float, limit: float, options: UprightOptions = UprightOptions()) -> float:
    """The dither's cart acceleration amplitude A [m/s²] for a rod of equivalent ``length`` [m] with dry friction μ =
    ``friction`` [rad/s²] under a balance that tolerates rod damping up to ``limit`` [1/s] (:func:`damping_limit`).

    A sine of the cart's acceleration A·sin Ωt swings the rod against its bearing at the rate amplitude
    ω_d = A·Ω/(l·Ω² + g) (the linear model). Averaged over a period, the dry friction μ·sgn(θ̇ + ω_d·sin Ωt) acts on
    the slow motion as (2μ/π)·asin(θ̇/ω_d): a damper of slope at most μ/ω_d where the rod moves slower than ω_d,
    instead of a stick. ``dither_gain`` × the A for which μ/ω_d equals ``limit``:
    A = dither_gain · μ·(l·Ω² + g)/(Ω·limit)."""
    if not (friction > 0.0 and limit > 0.0) or math.isinf(limit):
        return 0.0
    w = 2.0 * math.pi * options.dither_hz
    return options.dither_gain * friction * (length * w * w + G) / (w * limit)


def catch_reach(length: float, gain: tuple[float, ...], horizon: float = 3.0, step: float = 0.01) -> np.ndarray:
    """(3, n, 5): row [i, k] maps the state z = (x, v, a, θ, θ̇) at a catch to the cart's x [m], v [m/s], a [m/s²]
    (i = 0, 1, 2) after (k + 1)·``step`` [s] under the balance's linear closed loop (gain K, rod of equivalent
    ``length`` [m]) over ``horizon`` [s]."""
    from scipy.linalg import expm

    from .lqr import cart_pendulum

    a, b = cart_pendulum(length, True)
    phi = expm((a - b @ np.asarray(gain, dtype=float).reshape(1, 5)) * step)
    n = max(1, int(round(horizon / step)))
    out = np.empty((n, 5, 5))
    p = np.eye(5)
    for k in range(n):
        p = phi @ p
        out[k] = p
    return np.ascontiguousarray(out[:, :3, :].transpose(1, 0, 2))


class UprightController:
    """Drives ``cart`` from the estimate (φ, φ̇) of a pendulum of equivalent length ``length`` [m]."""

    def __init__(self, length: float, cart: Cart, options: UprightOptions = UprightOptions(),
                 gain: tuple[float, ...] | None = None, friction: float = 0.0, reach: np.ndarray | None = None,
                 limit: float | None = None) -> None:  # fmt: skip
        self.length = length
        self.friction = friction  # μ [rad/s²] the bearing's dry friction per inertia (identified): pumped for
        self.cart = cart
        self.o = options
        self.gain = gain if gain is not None else balance_gain(length, options)
        # the catch's prediction (pass it in to keep the matrix exponential out of a real-time cycle)
        self._reach = (
            reach if reach is not None or not any(self.gain) else catch_reach(length, self.gain, options.catch_horizon)
        )
        if limit is None:  # (pass it in, computed with the gain, to keep its eigenvalues out of a real-time cycle)
            limit = damping_limit(length, self.gain) if friction > 0.0 and any(self.gain) else math.inf
        self.dither_amplitude = dither_amplitude(length, friction, limit, options)  # [m/s²] (before the cap)
        self._z = np.zeros(5)
        self._av = 0.0  # [m/s²] the balance's own share of the cart's acceleration (the dither's apart)
        self._bal_t = 0.0  # [s] since the catch
        self._dither_share = 0.0  # [-] of the dither's full amplitude
        self.dither = 0.0  # [m/s²] the dither's acceleration now
        self.mode = Mode.SWING_UP
        self.catches = 0
        self.falls = 0

    def park(self) -> None:
        """Stop balancing: bring the cart to the centre and to rest."""
        self.mode = Mode.PARK

    def lower(self, ramp_s: float = 6.0) -> None:
        """Bring the rod down gently: its energy follows a target ramped to the hanging rod's over ``ramp_s`` [s]."""
        self.mode = Mode.LOWER
        self._lower_t = 0.0
        self._lower_ramp = max(ramp_s, 1e-3)

    def update(self, phi: float, omega: float) -> None:
        """One cycle with the estimate φ [rad] (0 hanging, π upright), φ̇ [rad/s]: step the cart."""
        o, cart = self.o, self.cart
        theta = wrap_angle(phi - math.pi)
        if (
            self.mode is Mode.SWING_UP
            and abs(theta) < o.catch_angle
            and abs(omega) < o.catch_rate
            and self._catchable(theta, omega)
        ):
            self.mode = Mode.BALANCE
            self.catches += 1
            self._av = cart.a
            self._bal_t = 0.0
            self._dither_share = 0.0
        elif self.mode is Mode.BALANCE and abs(theta) > o.drop_angle:
            self.mode = Mode.SWING_UP
            self.falls += 1
        if self.mode is Mode.BALANCE:
            self._balance(theta, omega)
        elif self.mode is Mode.SWING_UP:
            # dry friction takes ≈ μ·l·π/2 of energy over the last quarter swing to the top: pump that much more
            e_top = G + 0.5 * math.pi * self.friction * self.length
            e = swing_energy(phi, omega, self.length)
            cap = o.swing_accel * cart.acceleration_bound
            if abs(omega) < o.start_rate and math.cos(phi) > 0.0:  # (nearly) at rest below: kick it outward
                pump = cap if phi >= 0.0 else -cap
            else:
                pump = o.energy_gain * (e_top - e) * omega * math.cos(phi)
            a = -max(-cap, min(cap, pump)) - o.centre_gain * cart.x - o.centre_damping * cart.v
            cart.track(a, o.accel_lag)
        elif self.mode is Mode.LOWER:
            self._lower_t += cart.dt
            share = min(1.0, self._lower_t / self._lower_ramp)
            target = G * (1.0 - 2.0 * share)  # from the upright's energy to the hanging rod's
            e = swing_energy(phi, omega, self.length)
            cap = o.swing_accel * cart.acceleration_bound
            take = o.energy_gain * (e - target) * omega * math.cos(phi)  # Ė = −a·φ̇·cos φ: a of this sign takes energy
            a = max(-cap, min(cap, take)) - o.centre_gain * cart.x - o.centre_damping * cart.v
            cart.track(a, o.accel_lag)
        else:
            cart.track(-o.centre_gain * cart.x - o.centre_damping * cart.v, o.accel_lag)

    def _balance(self, theta: float, omega: float) -> None:
        """One cycle of the balance: the LQR's jerk on the state without the dither's own motion, the dither on top."""
        o, cart, k = self.o, self.cart, self.gain
        dt = cart.dt
        self._bal_t += dt
        self._dither_share = min(1.0, self._dither_share + dt / o.dither_on_s) if abs(theta) < o.dither_calm else 0.0
        amp = self._dither_share * min(self.dither_amplitude, o.dither_cap * cart.acceleration_bound)
        w = 2.0 * math.pi * o.dither_hz
        s, c = math.sin(w * self._bal_t), math.cos(w * self._bal_t)
        # the dither's periodic response in the linear model (cart and rod) is taken out of the state the balance
        # sees: it does not fight the dither
        rod = -amp / (self.length * w * w + G)
        z = self._z
        z[0], z[1], z[2] = cart.x + amp * s / (w * w), cart.v + amp * c / w, self._av
        z[3], z[4] = theta - rod * s, omega - rod * w * c
        jerk = -(k[0] * z[0] + k[1] * z[1] + k[2] * z[2] + k[3] * z[3] + k[4] * z[4])
        av = self._av + jerk * dt
        d = amp * s
        cart.step((av + d - cart.a) / dt)
        self._av = cart.a - d  # what the governor let through, less the dither
        self.dither = d

    def _catchable(self, theta: float, omega: float) -> bool:
        """The balance, started now, keeps the cart inside ``catch_travel`` of the rail (the linear closed loop's
        prediction; its speed and acceleration are the governor's to trim)."""
        if self._reach is None:
            return False
        c, z = self.cart, self._z
        z[0], z[1], z[2], z[3], z[4] = c.x, c.v, c.a, theta, omega
        r = self._reach @ z  # (3, n)
        return bool(np.abs(r[0]).max() < self.o.catch_travel * c.limits.travel)

    @property
    def at_rest(self) -> bool:
        """The cart is back at the centre and still (after :meth:`park`)."""
        c = self.cart
        return abs(c.x) < 1e-3 and abs(c.v) < 1e-3 and abs(c.a) < 1e-2
