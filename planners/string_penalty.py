"""An independent judge of the string-and-cup model: penalty forces, fixed small steps, its own geometry.

Deliberately different from ``string_sim`` / ``string_stepper`` (which switch between constrained phases at located
events and apply impulses): here the ball is a free point mass at every instant, in Cartesian coordinates, and
  - the string is a stiff tension-only spring–damper (stiffness ω_s², damping 2ζ_s·ω_s per unit mass; it pushes
    never), so "taut", "slack" and the re-tension jerk are not states but what the spring does;
  - the cup is the union of two solid cylinders (bottom slab, wall tube) whose signed distance comes from the
    rectangle distance of its (ρ, z) section, the contact normal from a finite-difference gradient of it;
  - contact is a Kelvin–Voigt spring–dashpot whose damping ratio gives the restitution e = exp(−ζπ/√(1 − ζ²)),
    friction a regularised Coulomb force;
  - the anchor follows a cubic spline through the sampled TCP positions (not the second-difference realisation);
  - the integrator is semi-implicit (symplectic) Euler at 10–20 µs, all cases of a band at once (numpy).
What it shares with the model: the physical parameters (``StringModel``) and gravity.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .pendulum import G
from .string_model import StringModel

STRING_HZ = 200.0  # [Hz] radial frequency of the taut string spring (stretch ≈ 20 µm under 30 m/s²)
CONTACT_HZ = 800.0  # [Hz] contact spring frequency (contact lasts ≈ 0.6 ms, 0.4 mm deep at 2 m/s)
STRING_DAMPING = 1.2  # damping ratio of the string spring (> 1: the jerk is inelastic, as retension = 0)
SLIP_SPEED = 0.01  # [m/s] the regularised friction reaches μ·N at this sliding speed


@dataclass(frozen=True)
class PenaltyRun:
    """Per case (k,): caught (at rest in the cup at the end), when the ball was first inside the cup [s] (NaN never),
    the first downward crossing of the rim plane: time [s], lateral distance from the axis [m], and relative speed
    [m/s]; the first time the string went slack [s]; and the sampled ball positions (m, k, 3) [m] at ``t`` (m,)."""

    caught: np.ndarray
    t_inside: np.ndarray
    t_crossing: np.ndarray
    rho_crossing: np.ndarray
    speed_crossing: np.ndarray
    t_slack: np.ndarray
    t: np.ndarray
    position: np.ndarray


def _rect_sdf(rho: np.ndarray, z: np.ndarray, r0: float, r1: float, z0: float, z1: float) -> np.ndarray:
    """Signed distance [m] from (ρ, z) to the rectangle [r0, r1] × [z0, z1] of the half-plane (negative inside)."""
    dx = np.maximum(np.maximum(r0 - rho, rho - r1), 0.0)
    dz = np.maximum(np.maximum(z0 - z, z - z1), 0.0)
    outside = np.hypot(dx, dz)
    inside = np.minimum(np.maximum(np.maximum(r0 - rho, rho - r1), np.maximum(z0 - z, z - z1)), 0.0)
    return outside + inside


def cup_sdf(rel: np.ndarray, axis: np.ndarray, model: StringModel) -> np.ndarray:
    """Signed distance [m] from points rel (k, 3) (relative to the anchor) to the cup's solid, axis (k, 3) unit."""
    c = model.cup
    z = np.einsum("ij,ij->i", rel, axis)
    rho = np.linalg.norm(rel - z[:, None] * axis, axis=1)
    bottom = _rect_sdf(rho, z, -c.outer_radius, c.outer_radius, 0.0, c.bottom_height)
    wall = _rect_sdf(rho, z, c.inner_radius, c.outer_radius, 0.0, c.rim_height)
    return np.minimum(bottom, wall)


def _anchor_path(t: np.ndarray, positions: np.ndarray, axes: np.ndarray, t_end: float, dt: float):
    """The anchor at every fine step from t[0] to t_end [s]: times (n + 1,), positions, velocities (clamped cubic
    spline through the samples; held, at rest, past the last) and cup axes (the sample's, n + 1, 3)."""
    from scipy.interpolate import CubicSpline

    spline = CubicSpline(t, positions, axis=0, bc_type="clamped")
    n = int(math.ceil((t_end - t[0]) / dt))
    fine = t[0] + np.arange(n + 1) * dt
    inside_path = fine <= t[-1]
    path_p = spline(np.minimum(fine, t[-1]))
    path_v = np.where(inside_path[:, None], spline.derivative()(np.minimum(fine, t[-1])), 0.0)
    path_ax = axes[np.clip(np.searchsorted(t, fine), 0, len(t) - 1)]
    return fine, path_p, path_v, path_ax


@dataclass(frozen=True)
class _Cases:
    """Per case (k,): string length [m], drag [1/m], ball radius [m], contact damping ratio (from the restitution)
    and friction coefficient."""

    length: np.ndarray
    drag: np.ndarray
    radius: np.ndarray
    zeta: np.ndarray
    mu: np.ndarray

    @classmethod
    def of(cls, models: list[StringModel]) -> "_Cases":
        e = np.array([m.restitution for m in models])
        zeta_c = -np.log(np.maximum(e, 1e-6)) / np.sqrt(math.pi**2 + np.log(np.maximum(e, 1e-6)) ** 2)
        return cls(
            length=np.array([m.length for m in models]),
            drag=np.array([m.drag for m in models]),
            radius=np.array([m.ball.radius for m in models]),
            zeta=zeta_c,
            mu=np.array([m.friction for m in models]),
        )


def _string_and_air(b, v, p, vp, cases: _Cases):
    """The ball relative to the anchor (position, velocity), the string's stretch [m] and the acceleration [m/s²]
    from the string spring (tension only), the air drag and gravity."""
    w_s = 2 * math.pi * STRING_HZ
    rel = b - p
    d = np.linalg.norm(rel, axis=1)
    s = rel / d[:, None]
    vrel = v - vp
    stretch = d - cases.length
    ddot = np.einsum("ij,ij->i", vrel, s)
    tension = np.where(stretch > 0, np.maximum(w_s**2 * stretch + 2 * STRING_DAMPING * w_s * ddot, 0.0), 0.0)
    acc = -tension[:, None] * s - (cases.drag * np.linalg.norm(v, axis=1))[:, None] * v
    acc[:, 2] -= G
    return rel, vrel, stretch, acc


def _add_contact(acc, rel, vrel, axis, model: StringModel, cases: _Cases, eps: float = 1e-6) -> None:
    """Add the cup's contact force per unit mass to ``acc`` (in place) for the cases whose ball penetrates the cup:
    a Kelvin–Voigt normal force along the signed distance's finite-difference gradient, regularised friction."""
    w_c = 2 * math.pi * CONTACT_HZ
    pen = cases.radius - cup_sdf(rel, axis, model)
    touching = pen > 0
    if not touching.any():
        return
    j = np.flatnonzero(touching)
    grad = np.zeros((len(j), 3))
    for c in range(3):
        dp = np.zeros((len(j), 3))
        dp[:, c] = eps
        grad[:, c] = (cup_sdf(rel[j] + dp, axis[j], model) - cup_sdf(rel[j] - dp, axis[j], model)) / (2 * eps)
    nrm = grad / np.maximum(np.linalg.norm(grad, axis=1), 1e-12)[:, None]
    vn = np.einsum("ij,ij->i", vrel[j], nrm)
    fn = np.maximum(w_c**2 * pen[j] - 2 * cases.zeta[j] * w_c * vn, 0.0)
    vt = vrel[j] - vn[:, None] * nrm
    st = np.linalg.norm(vt, axis=1)
    ft = -(cases.mu[j] * fn * np.minimum(st / SLIP_SPEED, 1.0) / np.maximum(st, 1e-12))[:, None] * vt
    acc[j] += fn[:, None] * nrm + ft


class _RimWatch:
    """Per case: the first time the ball was inside the cup and its first downward crossing of the rim plane once
    slack (time, distance from the axis, relative speed)."""

    def __init__(self, k: int) -> None:
        self.t_inside = np.full(k, np.nan)
        self.t_cross = np.full(k, np.nan)
        self.rho_cross = np.full(k, np.nan)
        self.speed_cross = np.full(k, np.nan)
        self.prev_height = None

    def update(self, tt: float, rel, vrel, axis, slack_seen, model: StringModel) -> None:
        cup = model.cup
        height = np.einsum("ij,ij->i", rel, axis) - cup.rim_height
        rho = np.linalg.norm(rel - (height + cup.rim_height)[:, None] * axis, axis=1)
        if self.prev_height is not None:
            down = np.isnan(self.t_cross) & (self.prev_height > 0) & (height <= 0) & slack_seen
            self.t_cross[down] = tt
            self.rho_cross[down] = rho[down]
            self.speed_cross[down] = np.linalg.norm(vrel[down], axis=1)
        self.prev_height = height
        inside = (height < 0) & (height > cup.bottom_height - cup.rim_height) & (rho < cup.inner_radius)
        self.t_inside[np.isnan(self.t_inside) & inside] = tt


def _resting_in_cup(b, v, p, vp, axis, model: StringModel) -> np.ndarray:
    """Per case: the ball's centre inside the cup and slower than 5 cm/s relative to it."""
    rel = b - p
    z = np.einsum("ij,ij->i", rel, axis)
    c = model.cup
    rho = np.linalg.norm(rel - z[:, None] * axis, axis=1)
    slow = np.linalg.norm(v - vp, axis=1) < 0.05
    return (z > c.bottom_height) & (z < c.rim_height) & (rho < c.inner_radius) & slow


def judge(
    models: list[StringModel],
    t: np.ndarray,
    positions: np.ndarray,
    axes: np.ndarray,
    t_end: float,
    dt: float = 4e-5,
    shifts: np.ndarray | None = None,
    sample_every: float = 0.005,
    v0: np.ndarray | None = None,
) -> PenaltyRun:
    """Simulate each case (a model: length, ball, cup, coefficients) from the ball hanging under the anchor (at rest,
    or with velocity ``v0`` (k, 3) [m/s]) along the anchor path sampled at times t (n,) [s] with positions (n, 3) [m]
    and cup axes (n, 3) (base frame), to t_end [s]. ``shifts`` (k,) [s]: once a case's string first goes slack its
    anchor runs that much late (negative: early)."""
    k = len(models)
    if len({m.cup for m in models}) != 1:
        raise ValueError("the cases of one penalty run must share the cup")
    fine, path_p, path_v, path_ax = _anchor_path(t, positions, axes, t_end, dt)
    n = len(fine) - 1
    cases = _Cases.of(models)
    lag = np.round((np.zeros(k) if shifts is None else np.asarray(shifts, float)) / dt).astype(int)
    b = np.tile(path_p[0], (k, 1)) - np.outer(cases.length, (0.0, 0.0, 1.0))
    b[:, 2] -= G / (2 * math.pi * STRING_HZ) ** 2  # hanging at rest: the spring stretched by its static load
    v = np.zeros((k, 3)) if v0 is None else np.array(v0, dtype=float).reshape(k, 3)
    slack_seen = np.zeros(k, bool)
    t_slack = np.full(k, np.nan)
    watch = _RimWatch(k)
    every = max(1, int(round(sample_every / dt)))
    out_t, out_b = [], []
    cup = models[0].cup is not None
    for i in range(n):
        tt = fine[i]
        ia = np.clip(np.where(slack_seen, i - lag, i), 0, n)
        rel, vrel, stretch, acc = _string_and_air(b, v, path_p[ia], path_v[ia], cases)
        newly = ~slack_seen & (stretch < -1e-3)
        t_slack[newly] = tt
        slack_seen |= newly
        if cup:
            _add_contact(acc, rel, vrel, path_ax[ia], models[0], cases)
            watch.update(tt, rel, vrel, path_ax[ia], slack_seen, models[0])
        v = v + dt * acc
        b = b + dt * v
        if i % every == 0:
            out_t.append(tt)
            out_b.append(b.copy())
    caught = np.zeros(k, bool)
    if cup:
        caught = _resting_in_cup(b, v, path_p[n], path_v[n], path_ax[np.full(k, n)], models[0])
    return PenaltyRun(
        caught,
        watch.t_inside,
        watch.t_cross,
        watch.rho_cross,
        watch.speed_cross,
        t_slack,
        np.array(out_t),
        np.array(out_b),
    )
