"""Identify the rod on the flange from a short excitation before the swing-up: its equivalent length, damping, the
encoder's zero offset and sign, and the sensor delay.

Protocol (run by the controller, the arm on its rail): ``QUIET_S`` at rest (the offset and the noise), one period of
a sine of the cart acceleration at the rod's nominal period (:func:`excitation`, a few degrees of swing), then
``DECAY_S`` of free swing. Model (small swings about hanging, the controller's convention)::

    θ̈ = −ω0²·θ − c·θ̇ − μ·sgn θ̇ − (ω0²/g)·a(t)   (l_eq = g/ω0², a the cart acceleration [m/s²])
    reading(t) = s·θ(t − τ) + φ0

:func:`identify` fits ω0, c, μ (dry friction) and τ by least squares over the whole record (the response to the known input computed
by an exact discretisation and ``scipy.signal.lfilter``; for each candidate the gain k and the offset φ0 are a
linear fit), then reads the sign off the gain: k ≈ +1 in the controller's convention, ≈ −1 for a reversed encoder
(detected from the response to a known push, not guessed). Pure numpy/scipy on arrays; ≈ 50 ms for a 5 s record —
run it outside the FRI cycle (a worker process).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..pendulum import G

QUIET_S = 0.5  # [s] at rest before the excitation
DECAY_S = 3.0  # [s] free swing after it
MIN_SWING = math.radians(1.0)  # [rad] a response smaller than this is no rod (or no encoder)
GAIN_BAND = (0.6, 1.6)  # |k|: the response to the known push, relative to the model's, for a rigid rod


class IdentificationError(ValueError):
    """The record does not show a rod that swings as a pendulum (the text says what was seen)."""


@dataclass(frozen=True)
class RodIdentification:
    """What the excitation showed about the rod and its sensor."""

    equivalent_length: float  # [m] g/ω0²
    damping: float  # c [1/s] (viscous equivalent of the bearing's friction)
    offset: float  # φ0 [rad] the encoder's reading of the hanging rod
    sign: int  # +1: the encoder reads in the controller's convention, −1: reversed
    delay: float  # τ [s] from the rod's motion to the reading's arrival (with the actuation lag)
    gain: float  # |k|: the response's size against the model's (≈ 1)
    noise: float  # [rad] RMS of the readings about the hanging rod at rest
    rms: float  # [rad] fit residual
    amplitude: float  # [rad] largest swing in the record
    coulomb: float = 0.0  # μ [rad/s²] the bearing's dry friction torque per inertia

    @property
    def period(self) -> float:
        """Small-swing period [s]."""
        return 2 * math.pi * math.sqrt(self.equivalent_length / G)

    def to_dict(self) -> dict:
        return {"identified_length_m": self.equivalent_length, "identified_period_s": self.period,
                "identified_damping_1_s": self.damping, "encoder_offset_deg": math.degrees(self.offset),
                "encoder_sign": self.sign, "identified_delay_ms": self.delay * 1e3, "identified_gain": self.gain,
                "encoder_noise_deg": math.degrees(self.noise), "fit_rms_deg": math.degrees(self.rms),
                "identified_coulomb_share": self.coulomb * self.equivalent_length / G}  # fmt: skip


def excitation(t: float, period: float, amplitude: float) -> float:
    """The cart acceleration [m/s²] of the excitation at ``t`` [s] after its start: one period ``period`` [s] of
    x(t) = amplitude·(1 − cos ωt) — out by up to 2·``amplitude`` [m] and back, starting and ending at rest on the
    spot it left, at the rod's resonance (a swing of ≈ π·amplitude·ω²/g rad); 0 outside."""
    if t < 0.0 or t >= period:
        return 0.0
    w = 2 * math.pi / period
    return amplitude * w * w * math.cos(w * t)


def _simulate(a: np.ndarray, dt: float, w0: float, c: float, mu: float) -> np.ndarray:
    """θ on the grid of the nonlinear model (sin θ, cos θ, viscous c and dry μ friction, smoothed by tanh as the
    bearing's) driven by ``a`` from rest: semi-implicit Euler at ``dt`` (one pass, ≈ 5 ms for 5 s)."""
    out = np.empty(len(a))
    th = om = 0.0
    w2, k = w0 * w0, w0 * w0 / G
    sin, cos, tanh = math.sin, math.cos, math.tanh
    for i, u in enumerate(a.tolist()):
        om += (-w2 * sin(th) - k * u * cos(th) - c * om - mu * tanh(om / 0.05)) * dt
        th += om * dt
        out[i] = th
    return out


def _extrema(t: np.ndarray, y: np.ndarray, centre: float, floor: float) -> list[tuple[float, float]]:
    """(time, value) of the swing's turning points: the extreme of each run between crossings of ``centre``, if it
    is more than ``floor`` [rad] away from it."""
    out = []
    side = np.sign(y - centre)
    start = None  # runs cut by the record's ends are no turning points: only those between two crossings count
    for i in range(1, len(y)):
        if side[i] != side[i - 1] and side[i] != 0:
            if start is not None:
                seg = y[start:i] - centre
                j = int(np.argmax(np.abs(seg)))
                if abs(seg[j]) > floor:
                    out.append((float(t[start + j]), float(y[start + j])))
            start = i
    return out


def identify(t_readings: np.ndarray, readings: np.ndarray, accel: np.ndarray, dt: float, nominal_length: float,
             t0: float = 0.0, max_delay: float = 0.06) -> RodIdentification:  # fmt: skip
    """Identify the rod from readings [rad] that arrived at ``t_readings`` [s] while the cart was driven by ``accel``
    (n,) [m/s²] sampled every ``dt`` [s] from ``t0`` [s] (the excitation ends before the free swing):

    1. the free swing's turning points give the equilibrium (midpoints of successive extremes: dry friction shifts
       them alternately), the period (between turning points on the same side), and the decay (peak amplitudes
       A_{n+1} = e^{−σT/2}·A_n − 2μ/ω0²: viscous σ = c/2 and dry μ by a linear fit) — :func:`_free_swing`;
    2. the model's response to the known input, shifted over delays 0..``max_delay``, against the whole record: the
       delay, the gain k (its sign the encoder's) and the fit's residual — :func:`_fit_response`.

    ``nominal_length`` [m] bounds the search (the period within ±40 % of its). :class:`IdentificationError` when the
    record shows no rod, or none that swings as a pendulum."""
    t_r = np.asarray(t_readings, dtype=float)
    y = np.asarray(readings, dtype=float)
    a = np.asarray(accel, dtype=float)
    if len(y) < 50 or len(a) < 100:
        raise IdentificationError(f"too short a record ({len(y)} readings)")
    rest = _at_rest(t_r, y, t0)
    noise = float(np.std(rest))
    swing = float(np.max(np.abs(y - np.median(rest))))
    if swing < MIN_SWING:
        raise IdentificationError(f"the rod barely moved ({math.degrees(swing):.2f}° at most) when the arm pushed it: "
                                  "is it attached, and the encoder read?")  # fmt: skip
    w_nom = math.sqrt(G / nominal_length)
    seed = _free_swing(t_r, y, a, dt, t0, rest, noise, swing, w_nom)
    w0, c, mu, (rms, tau, k, off) = _fit_response(t_r, y, a, dt, t0, seed, w_nom, max_delay)
    if not GAIN_BAND[0] <= abs(k) <= GAIN_BAND[1] or rms > 0.25 * swing:
        raise IdentificationError(f"the rod's swing does not fit a pendulum on the arm (response {abs(k):.2f}× the "
                                  f"model's, residual {math.degrees(rms):.2f}° of a {math.degrees(swing):.1f}° "
                                  "swing): is it a rigid rod on a free bearing, and the encoder's axis the rail's?")  # fmt: skip
    return RodIdentification(G / (w0 * w0), c, off, 1 if k > 0 else -1, tau, abs(k), noise, rms, swing, mu)


def _at_rest(t_r: np.ndarray, y: np.ndarray, t0: float) -> np.ndarray:
    """The readings [rad] of the hanging rod before the excitation (its offset and noise)."""
    quiet = t_r < t0 + QUIET_S * 0.9
    return y[quiet] if quiet.sum() >= 5 else y[: max(5, len(y) // 20)]


def _free_swing(t_r: np.ndarray, y: np.ndarray, a: np.ndarray, dt: float, t0: float, rest: np.ndarray, noise: float,
                swing: float, w_nom: float) -> tuple[float, float, float]:  # fmt: skip
    """Step 1: (ω0 [rad/s], c [1/s], μ [rad/s²]) read off the free swing after the excitation — the period between
    crossings of the equilibrium, the decay of the turning points (the seed of :func:`_fit_response`)."""
    moving = np.flatnonzero(np.abs(a) > 1e-9)
    t_free = t0 + (moving[-1] + 1) * dt + 0.05 if len(moving) else t0
    # (at the latest one period after the push began, as planned: after lost messages the controller held the
    # cart's velocity, not its acceleration, and the cart is still being brought to rest — the fit has that motion)
    t_free = min(t_free, t0 + QUIET_S + 2 * math.pi / w_nom + 0.05)
    free = t_r >= t_free
    tf, yf = t_r[free], y[free]
    floor = max(4.0 * noise, math.radians(0.3))
    centre, ext = _turning_points(tf, yf, float(np.median(yf)) if len(yf) else float(np.median(rest)), floor)
    if len(ext) < 2:
        raise IdentificationError(f"the rod stopped swinging within {len(ext)} half-periods of the push (swing "
                                  f"{math.degrees(swing):.1f}°): too much friction in its bearing, or a push too weak")  # fmt: skip
    cross = _crossings(tf, yf, centre, ext[-1][0], floor)
    if len(cross) < 2:
        raise IdentificationError("the rod's free swing crossed its equilibrium less than twice: push too weak")
    period = float(np.mean(np.diff(cross[::2])) if len(cross) >= 3 else 2 * np.mean(np.diff(cross)))
    # a large swing takes longer than a small one: T = T0·(1 + θ²/16 + 11θ⁴/3072 + …) at amplitude θ
    amps = np.abs(np.array([p[1] for p in ext]) - centre)
    amp = float(np.mean(amps))
    period /= 1.0 + amp * amp / 16.0 + 11.0 * amp**4 / 3072.0
    w0 = 2 * math.pi / period
    if not 0.6 * w_nom <= w0 <= 1.4 * w_nom:
        raise IdentificationError(f"the rod swings with a period of {period:.3f} s, the model's is "
                                  f"{2 * math.pi / w_nom:.3f} s: check identify.nominal_length")  # fmt: skip
    c0, mu0 = _decay(amps, period, w0, floor)
    return w0, c0, mu0


def _turning_points(tf: np.ndarray, yf: np.ndarray, centre: float, floor: float) -> tuple[float, list]:
    """The swing's equilibrium [rad] (midpoints of successive extremes: dry friction shifts them alternately) and its
    turning points about it (:func:`_extrema`)."""
    ext = _extrema(tf, yf, centre, floor)
    if len(ext) >= 2:
        mids = [(p[1] + q[1]) / 2 for p, q in zip(ext, ext[1:])]
        centre = float(np.mean(mids[: max(1, 2 * (len(mids) // 2))]))
        ext = _extrema(tf, yf, centre, floor)
    return centre, ext


def _decay(amps: np.ndarray, period: float, w0: float, floor: float) -> tuple[float, float]:
    """(c [1/s], μ [rad/s²]) from the turning points' amplitudes [rad]: per half period A_{n+1} = r·A_n − d with
    r = e^{−cT/4} (viscous) and d = 2μ/ω0² (dry); whichever of the two decays fits better (a rod without either keeps
    its amplitude: both 0)."""
    if len(amps) < 3 or np.ptp(amps) <= 2.0 * floor:
        return 0.0, 0.0
    n = np.arange(len(amps), dtype=float)
    slope_log, icpt_log = np.polyfit(n, np.log(amps), 1)
    slope_lin, icpt_lin = np.polyfit(n, amps, 1)
    res_log = float(np.sum((amps - np.exp(icpt_log + slope_log * n)) ** 2))
    res_lin = float(np.sum((amps - (icpt_lin + slope_lin * n)) ** 2))
    if res_log <= res_lin:
        return max(0.0, -4.0 * slope_log / period), 0.0
    return 0.0, max(0.0, -slope_lin * w0 * w0 / 2.0)


_Fit = tuple[float, float, float, float]  # (rms [rad], τ [s], k, offset [rad]) of the model's response


def _fit_response(t_r: np.ndarray, y: np.ndarray, a: np.ndarray, dt: float, t0: float, seed: tuple[float, float, float],
                  w_nom: float, max_delay: float) -> tuple[float, float, float, _Fit]:  # fmt: skip
    """Step 2: (ω0, c, μ) refined from ``seed`` (Nelder–Mead) so that the nonlinear model's response to the known
    input fits the whole record, and that fit (:func:`_response_fit`)."""
    from scipy.optimize import minimize

    grid = t0 + np.arange(len(a)) * dt

    def cost(p: np.ndarray) -> float:
        w, c, mu = p
        if not (0.6 * w_nom <= w <= 1.4 * w_nom and 0.0 <= c <= 5.0 and 0.0 <= mu <= 5.0 * w_nom * w_nom):
            return 1e3
        return _response_fit(_simulate(a, dt, w, c, mu), t_r, y, grid, max_delay)[0]

    w0, c0, mu0 = seed
    simplex = np.array(seed) + np.array(
        [[0, 0, 0], [0.004 * w0, 0, 0], [0, 0.05 + 0.2 * c0, 0], [0, 0, 0.005 * w0 * w0 + 0.2 * mu0]]
    )
    res = minimize(cost, np.array(seed), method="Nelder-Mead", options={"xatol": 1e-5, "fatol": 1e-9, "maxiter": 60,
                                                                        "initial_simplex": simplex})  # fmt: skip
    w0, c, mu = (float(v) for v in res.x)
    return w0, c, mu, _response_fit(_simulate(a, dt, w0, c, mu), t_r, y, grid, max_delay)


def _response_fit(theta: np.ndarray, t_r: np.ndarray, y: np.ndarray, grid: np.ndarray, max_delay: float) -> _Fit:
    """The model's response ``theta`` on ``grid`` against the readings: the delay scanned over 0..``max_delay`` in
    2 ms steps, then refined to 0.25 ms about the best."""
    best = _scan(theta, np.arange(0.0, max_delay + 1e-9, 0.002), t_r, y, grid, max_delay)
    return _scan(theta, best[1] + np.arange(-0.002, 0.00201, 0.00025), t_r, y, grid, max_delay, best)


def _scan(theta: np.ndarray, taus: np.ndarray, t_r: np.ndarray, y: np.ndarray, grid: np.ndarray, max_delay: float,
          best: _Fit = (math.inf, 0.0, 0.0, 0.0)) -> _Fit:  # fmt: skip
    """The best of ``best`` and the fits at the delays ``taus`` [s]: for each, the gain k and the offset are the
    linear least-squares fit of the readings to the response shifted by τ."""
    sy = float(y.sum())
    for tau in taus:
        if not 0.0 <= tau <= max_delay:
            continue
        x = np.interp(t_r - tau, grid, theta, left=0.0, right=theta[-1])
        sx, sxx = float(x.sum()), float(x @ x)
        n = len(x)
        det = n * sxx - sx * sx
        if det <= 0.0:
            continue
        sxy = float(x @ y)
        k = (n * sxy - sx * sy) / det
        off = (sy - k * sx) / n
        res = y - k * x - off
        rms = math.sqrt(float(res @ res) / n)
        if rms < best[0]:
            best = (rms, float(tau), k, off)
    return best


def _crossings(t: np.ndarray, y: np.ndarray, centre: float, until: float, floor: float) -> np.ndarray:
    """Times [s] where the swing crosses ``centre`` up to ``until``, each crossing once: where the readings pass from
    beyond ``floor`` [rad] on one side to beyond it on the other (the noise of a slow crossing flips the sign about
    the centre several times: the midpoint of the first and last flip, each interpolated linearly)."""
    z = y - centre
    far = np.flatnonzero(np.abs(z) > floor)
    out = []
    for f in np.flatnonzero((z[far[1:]] > 0) != (z[far[:-1]] > 0)):
        i0 = far[f]
        flips = i0 + np.flatnonzero((z[i0 : far[f + 1]] < 0) != (z[i0 + 1 : far[f + 1] + 1] < 0))
        tc = t[flips] - z[flips] * (t[flips + 1] - t[flips]) / (z[flips + 1] - z[flips])
        out.append(0.5 * (tc[0] + tc[-1]))
    cross = np.array(out)
    return cross[cross <= until]
