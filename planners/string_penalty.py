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
    from scipy.interpolate import CubicSpline

    k = len(models)
    if len({m.cup for m in models}) != 1:
        raise ValueError("the cases of one penalty run must share the cup")
    spline = CubicSpline(t, positions, axis=0, bc_type="clamped")
    n = int(math.ceil((t_end - t[0]) / dt))
    fine = t[0] + np.arange(n + 1) * dt
    inside_path = fine <= t[-1]
    path_p = spline(np.minimum(fine, t[-1]))
    path_v = np.where(inside_path[:, None], spline.derivative()(np.minimum(fine, t[-1])), 0.0)
    path_ax = axes[np.clip(np.searchsorted(t, fine), 0, len(t) - 1)]
    length = np.array([m.length for m in models])
    drag = np.array([m.drag for m in models])
    radius = np.array([m.ball.radius for m in models])
    e = np.array([m.restitution for m in models])
    mu = np.array([m.friction for m in models])
    zeta_c = -np.log(np.maximum(e, 1e-6)) / np.sqrt(math.pi**2 + np.log(np.maximum(e, 1e-6)) ** 2)
    w_s, w_c = 2 * math.pi * STRING_HZ, 2 * math.pi * CONTACT_HZ
    lag = np.round((np.zeros(k) if shifts is None else np.asarray(shifts, float)) / dt).astype(int)
    p0 = path_p[0]
    b = np.tile(p0, (k, 1)) - np.outer(length, (0.0, 0.0, 1.0))
    b[:, 2] -= G / w_s**2  # hanging at rest: the spring stretched by its static load
    v = np.zeros((k, 3)) if v0 is None else np.array(v0, dtype=float).reshape(k, 3)
    slack_seen = np.zeros(k, bool)
    t_slack = np.full(k, np.nan)
    t_inside = np.full(k, np.nan)
    t_cross = np.full(k, np.nan)
    rho_cross = np.full(k, np.nan)
    speed_cross = np.full(k, np.nan)
    prev_height = None
    every = max(1, int(round(sample_every / dt)))
    out_t, out_b = [], []
    eps = 1e-6
    cup = models[0].cup is not None
    for i in range(n):
        tt = fine[i]
        ia = np.clip(np.where(slack_seen, i - lag, i), 0, n)
        p, vp = path_p[ia], path_v[ia]
        rel = b - p
        d = np.linalg.norm(rel, axis=1)
        s = rel / d[:, None]
        vrel = v - vp
        stretch = d - length
        ddot = np.einsum("ij,ij->i", vrel, s)
        tension = np.where(stretch > 0, np.maximum(w_s**2 * stretch + 2 * STRING_DAMPING * w_s * ddot, 0.0), 0.0)
        newly = ~slack_seen & (stretch < -1e-3)
        t_slack[newly] = tt
        slack_seen |= newly
        acc = -tension[:, None] * s - (drag * np.linalg.norm(v, axis=1))[:, None] * v
        acc[:, 2] -= G
        if cup:
            axis = path_ax[ia]
            sdf = cup_sdf(rel, axis, models[0])
            pen = radius - sdf
            touching = pen > 0
            if touching.any():
                j = np.flatnonzero(touching)
                grad = np.zeros((len(j), 3))
                for c in range(3):
                    dp = np.zeros((len(j), 3))
                    dp[:, c] = eps
                    grad[:, c] = (
                        cup_sdf(rel[j] + dp, axis[j], models[0]) - cup_sdf(rel[j] - dp, axis[j], models[0])
                    ) / (2 * eps)
                nrm = grad / np.maximum(np.linalg.norm(grad, axis=1), 1e-12)[:, None]
                vn = np.einsum("ij,ij->i", vrel[j], nrm)
                fn = np.maximum(w_c**2 * pen[j] - 2 * zeta_c[j] * w_c * vn, 0.0)
                vt = vrel[j] - vn[:, None] * nrm
                st = np.linalg.norm(vt, axis=1)
                ft = -(mu[j] * fn * np.minimum(st / SLIP_SPEED, 1.0) / np.maximum(st, 1e-12))[:, None] * vt
                acc[j] += fn[:, None] * nrm + ft
            height = np.einsum("ij,ij->i", rel, axis) - models[0].cup.rim_height
            rho = np.linalg.norm(rel - (height + models[0].cup.rim_height)[:, None] * axis, axis=1)
            if prev_height is not None:
                down = np.isnan(t_cross) & (prev_height > 0) & (height <= 0) & slack_seen
                t_cross[down] = tt
                rho_cross[down] = rho[down]
                speed_cross[down] = np.linalg.norm(vrel[down], axis=1)
            prev_height = height
            inside = (
                (height < 0)
                & (height > models[0].cup.bottom_height - models[0].cup.rim_height)
                & (rho < models[0].cup.inner_radius)
            )
            t_inside[np.isnan(t_inside) & inside] = tt
        v = v + dt * acc
        b = b + dt * v
        if i % every == 0:
            out_t.append(tt)
            out_b.append(b.copy())
    caught = np.zeros(k, bool)
    if cup:
        axis = path_ax[np.full(k, n)]
        rel = b - path_p[n]
        z = np.einsum("ij,ij->i", rel, axis)
        c = models[0].cup
        rho = np.linalg.norm(rel - z[:, None] * axis, axis=1)
        slow = np.linalg.norm(v - path_v[n], axis=1) < 0.05
        caught = (z > c.bottom_height) & (z < c.rim_height) & (rho < c.inner_radius) & slow
    return PenaltyRun(caught, t_inside, t_cross, rho_cross, speed_cross, t_slack, np.array(out_t), np.array(out_b))
