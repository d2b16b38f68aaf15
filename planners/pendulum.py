"""Ball on a string hanging from a moving pivot: the spherical pendulum driven by the pivot acceleration.

The load r = p + l·s (|s| = 1) obeys m·r̈ = −T·s + m·g_vec (facts/physics.md), hence
    l·s̈ = (I − s sᵀ)(g_vec − p̈) − l·|ṡ|²·s        and        T/m = l·|ṡ|² + s·(g_vec − p̈).
The string is taut while T > 0. Planar motion is the special case of a pivot moving in one vertical plane.
Base frame: z up, gravity g_vec = (0, 0, −g).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

G = 9.81  # [m/s^2]
G_VEC = np.array([0.0, 0.0, -G])
HANGING = np.array([0.0, 0.0, -1.0])

AccelerationFn = Callable[[float], np.ndarray]


def natural_period(length: float, g: float = G) -> float:
    """Small-angle period T = 2π·√(l/g) [s] of a string of ``length`` [m]."""
    return 2.0 * math.pi * math.sqrt(length / g)


def direction_from_angles(theta_x: float = 0.0, theta_y: float = 0.0) -> np.ndarray:
    """Unit string direction tilted by the planar angles θx (toward +x) and θy (toward +y) from hanging."""
    s = np.array([math.tan(theta_x), math.tan(theta_y), -1.0])
    return s / np.linalg.norm(s)


def rhs(
    s: np.ndarray,
    sdot: np.ndarray,
    pivot_acc: np.ndarray,
    length: float,
    damping: float = 0.0,
    constraint_rate: float = 0.0,
) -> np.ndarray:
    """s̈ for string direction s, its rate ṡ [1/s] and pivot acceleration p̈ [m/s²]; ``damping`` [1/s] on ṡ.

    ``constraint_rate`` α [1/s] > 0 adds Baumgarte stabilisation of |s| = 1 (c = (|s|² − 1)/2 then obeys
    c̈ = −2αċ − α²c; identical on the sphere). Without it the drift of |s| grows exponentially whenever the
    tension is negative (slack string, rigid-rod model), which long runs past 90° need.
    """
    f = (G_VEC - pivot_acc) / length
    if constraint_rate == 0.0:
        return f - np.dot(s, f) * s - np.dot(sdot, sdot) * s - damping * sdot
    ss = np.dot(s, s)
    c, cdot = 0.5 * (ss - 1.0), np.dot(s, sdot)
    lam = (np.dot(s, f) + np.dot(sdot, sdot) + 2.0 * constraint_rate * cdot + constraint_rate**2 * c) / ss
    return f - lam * s - damping * sdot


def tension_per_mass(s: np.ndarray, sdot: np.ndarray, pivot_acc: np.ndarray, length: float) -> np.ndarray:
    """String tension divided by the ball mass [m/s²] (positive: taut). Works on (n, 3) arrays too."""
    s, sdot, pivot_acc = np.atleast_2d(s), np.atleast_2d(sdot), np.atleast_2d(pivot_acc)
    return length * np.einsum("ij,ij->i", sdot, sdot) + np.einsum("ij,ij->i", s, G_VEC - pivot_acc)


def rk4_step(
    s: np.ndarray, sdot: np.ndarray, acc0: np.ndarray, acc1: np.ndarray, h: float, length: float, damping: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """One RK4 step of length h [s] with the pivot acceleration going linearly from acc0 to acc1 [m/s²].

    For fixed-step use (``rk4_step_floats`` is the same step on float tuples, for the FRI simulator's
    per-cycle loop); the result is re-projected onto the sphere.
    """
    acc_mid = 0.5 * (acc0 + acc1)
    k1v = rhs(s, sdot, acc0, length, damping)
    k1x = sdot
    s2, v2 = s + 0.5 * h * k1x, sdot + 0.5 * h * k1v
    k2v = rhs(s2, v2, acc_mid, length, damping)
    s3, v3 = s + 0.5 * h * v2, sdot + 0.5 * h * k2v
    k3v = rhs(s3, v3, acc_mid, length, damping)
    s4, v4 = s + h * v3, sdot + h * k3v
    k4v = rhs(s4, v4, acc1, length, damping)
    s_new = s + h / 6.0 * (k1x + 2 * v2 + 2 * v3 + v4)
    v_new = sdot + h / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v)
    s_new /= np.linalg.norm(s_new)
    v_new -= np.dot(v_new, s_new) * s_new
    return s_new, v_new


Vec3 = tuple[float, float, float]


def _rhs_floats(s: Vec3, v: Vec3, a: Vec3, length: float, damping: float) -> Vec3:
    """``rhs`` on 3-tuples of floats (no Baumgarte term)."""
    fx, fy, fz = -a[0] / length, -a[1] / length, (-G - a[2]) / length
    lam = s[0] * fx + s[1] * fy + s[2] * fz + v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
    return (fx - lam * s[0] - damping * v[0], fy - lam * s[1] - damping * v[1], fz - lam * s[2] - damping * v[2])


def rk4_step_floats(
    s: Vec3, sdot: Vec3, acc0: Vec3, acc1: Vec3, h: float, length: float, damping: float = 0.0
) -> tuple[Vec3, Vec3]:
    """``rk4_step`` on plain 3-tuples of floats: the same scheme without numpy's per-call overhead (several
    times faster for a single step; used in the FRI simulator's 1 kHz loop). Returns (s, ṡ) as tuples."""
    am = (0.5 * (acc0[0] + acc1[0]), 0.5 * (acc0[1] + acc1[1]), 0.5 * (acc0[2] + acc1[2]))
    hh = 0.5 * h
    k1v = _rhs_floats(s, sdot, acc0, length, damping)
    s2 = (s[0] + hh * sdot[0], s[1] + hh * sdot[1], s[2] + hh * sdot[2])
    v2 = (sdot[0] + hh * k1v[0], sdot[1] + hh * k1v[1], sdot[2] + hh * k1v[2])
    k2v = _rhs_floats(s2, v2, am, length, damping)
    s3 = (s[0] + hh * v2[0], s[1] + hh * v2[1], s[2] + hh * v2[2])
    v3 = (sdot[0] + hh * k2v[0], sdot[1] + hh * k2v[1], sdot[2] + hh * k2v[2])
    k3v = _rhs_floats(s3, v3, am, length, damping)
    s4 = (s[0] + h * v3[0], s[1] + h * v3[1], s[2] + h * v3[2])
    v4 = (sdot[0] + h * k3v[0], sdot[1] + h * k3v[1], sdot[2] + h * k3v[2])
    k4v = _rhs_floats(s4, v4, acc1, length, damping)
    h6 = h / 6.0
    sn = [s[i] + h6 * (sdot[i] + 2.0 * v2[i] + 2.0 * v3[i] + v4[i]) for i in range(3)]
    vn = [sdot[i] + h6 * (k1v[i] + 2.0 * k2v[i] + 2.0 * k3v[i] + k4v[i]) for i in range(3)]
    norm = math.sqrt(sn[0] * sn[0] + sn[1] * sn[1] + sn[2] * sn[2])
    sn = [x / norm for x in sn]
    radial = vn[0] * sn[0] + vn[1] * sn[1] + vn[2] * sn[2]
    return (sn[0], sn[1], sn[2]), (vn[0] - radial * sn[0], vn[1] - radial * sn[1], vn[2] - radial * sn[2])


@dataclass(frozen=True)
class PendulumRun:
    """A simulated run: times (n,) [s], string directions s (n, 3), rates ṡ (n, 3) [1/s], tension/mass [m/s²]."""

    t: np.ndarray
    s: np.ndarray
    sdot: np.ndarray
    tension: np.ndarray
    length: float

    @property
    def theta(self) -> np.ndarray:
        """Polar angle from the hanging vertical [rad], 0..π."""
        return np.arccos(np.clip(-self.s[:, 2], -1.0, 1.0))

    @property
    def phi(self) -> np.ndarray:
        """Azimuth of the tilt in the base x–y plane [rad]."""
        return np.arctan2(self.s[:, 1], self.s[:, 0])

    @property
    def theta_x(self) -> np.ndarray:
        """Signed swing angle in the x–z plane, positive toward +x [rad]."""
        return np.arctan2(self.s[:, 0], -self.s[:, 2])

    @property
    def theta_y(self) -> np.ndarray:
        """Signed swing angle in the y–z plane, positive toward +y [rad]."""
        return np.arctan2(self.s[:, 1], -self.s[:, 2])

    def energy_per_mass(self) -> np.ndarray:
        """Swing energy relative to the pivot, per unit mass [J/kg]: ½ l² |ṡ|² − g l cos θ."""
        return 0.5 * self.length**2 * np.einsum("ij,ij->i", self.sdot, self.sdot) + G * self.length * self.s[:, 2]


def simulate(
    times: np.ndarray,
    pivot_acc: AccelerationFn,
    length: float,
    s0: np.ndarray = HANGING,
    sdot0: np.ndarray | None = None,
    *,
    damping: float = 0.0,
    rtol: float = 1e-9,
    atol: float = 1e-11,
    max_step: float = np.inf,
    constraint_rate: float = 0.0,
) -> PendulumRun:
    """Integrate the driven spherical pendulum (scipy solve_ivp, DOP853) and sample it at ``times`` [s].

    ``pivot_acc(t)`` returns the pivot acceleration [m/s²]; give ``max_step`` no larger than the shortest
    feature of the input (e.g. the sample step of a sampled path) so that no input change is stepped over.
    ``constraint_rate`` [1/s]: see ``rhs`` (use e.g. 20 for runs where the string may go slack).
    """
    from scipy.integrate import solve_ivp

    s0 = np.asarray(s0, dtype=float) / np.linalg.norm(s0)
    v0 = np.zeros(3) if sdot0 is None else np.asarray(sdot0, dtype=float)

    def f(t: float, y: np.ndarray) -> np.ndarray:
        s, v = y[:3], y[3:]
        return np.concatenate([v, rhs(s, v, pivot_acc(t), length, damping, constraint_rate)])

    times = np.asarray(times, dtype=float)
    sol = solve_ivp(
        f,
        (times[0], times[-1]),
        np.concatenate([s0, v0]),
        method="DOP853",
        t_eval=times,
        rtol=rtol,
        atol=atol,
        max_step=max_step,
    )
    if not sol.success:
        raise RuntimeError(f"pendulum integration failed: {sol.message}")
    s = sol.y[:3].T
    s = s / np.linalg.norm(s, axis=1, keepdims=True)
    v = sol.y[3:].T
    acc = np.array([pivot_acc(t) for t in times])
    return PendulumRun(t=times, s=s, sdot=v, tension=tension_per_mass(s, v, acc, length), length=length)


class SampledAcceleration:
    """Pivot acceleration of a path sampled every h [s], as a position-controlled robot realises it.

    The acceleration at sample k is the second difference (p[k+1] − 2p[k] + p[k−1])/h² (the path is held at
    rest before the first and after the last sample); between samples it is interpolated linearly.
    """

    def __init__(self, t: np.ndarray, positions: np.ndarray) -> None:
        p = np.asarray(positions, dtype=float)
        self.t0 = float(t[0])
        self.h = float(t[1] - t[0])
        padded = np.vstack([p[:1], p, p[-1:]])
        self.acc = (padded[2:] - 2.0 * padded[1:-1] + padded[:-2]) / self.h**2
        self.n = len(p)

    def __call__(self, t: float) -> np.ndarray:
        x = (t - self.t0) / self.h
        if x <= 0.0:
            return self.acc[0] if x == 0.0 else np.zeros(3)
        k = int(x)
        if k >= self.n - 1:
            return self.acc[-1] if k == self.n - 1 and x == k else np.zeros(3)
        w = x - k
        return (1.0 - w) * self.acc[k] + w * self.acc[k + 1]

    def samples(self) -> np.ndarray:
        """(n, 3) acceleration at the samples [m/s²]."""
        return self.acc.copy()
