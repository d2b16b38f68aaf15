"""Plot of a swing-up plan: ball angle, pivot motion, tension margin, joint rates against the limits."""

from __future__ import annotations

from . import limits_phrase, save_figure, unwrap_deg

import math
from pathlib import Path

import numpy as np


def plot_swingup(result, path: str | Path) -> None:
    """One PNG: θ(t) verified and planned with θ_d; pivot x(t) and u(t); tension/mass; joint velocity,
    acceleration (and jerk) as a fraction of their limits."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    r, plan, ver, rep = result.request, result.plan, result.verification, result.check
    fig, axes = plt.subplots(5, 1, figsize=(10, 13), sharex=True)

    ax = axes[0]
    ax.plot(
        ver.t,
        unwrap_deg(ver.theta),
        lw=2.2,
        color="tab:blue",
        alpha=0.6,
        zorder=2,
        label="verified (ball simulated under the joint path)",
    )
    ax.plot(plan.t, unwrap_deg(plan.theta), lw=1.0, ls="--", color="k", zorder=3, label="planned (planar model)")
    for sign in (1, -1):
        ax.axhline(sign * math.degrees(r.theta_d), color="k", ls=":", lw=0.8)
    if result.t_reach is not None:
        ax.axvline(result.t_reach, color="tab:green", lw=0.8, label=f"θ_d reached {result.t_reach:.2f} s")
    ax.set_ylabel("θ [deg]")
    ax.legend(fontsize=8, loc="upper left")

    ax = axes[1]
    ax.plot(plan.t, plan.x, color="tab:blue", lw=1.0)
    ax.set_ylabel("pivot x along base y [m]", color="tab:blue")
    ax.axvline(plan.t_rest, color="k", lw=0.6, ls=":")
    twin = ax.twinx()
    twin.plot(plan.t, plan.u, color="tab:orange", lw=0.8)
    twin.set_ylabel("u = ẍ [m/s²]", color="tab:orange")

    ax = axes[2]
    ax.plot(ver.t, ver.tension, lw=2.2, color="tab:blue", alpha=0.6, zorder=2, label="verified")
    ax.plot(plan.t, plan.tension, lw=1.0, ls="--", color="k", zorder=3, label="planned")
    ax.axhline(0.0, color="k", lw=0.8)
    slack = ver.tension <= 0
    if slack.any():
        ax.fill_between(ver.t, ver.tension.min(), 0, where=slack, color="tab:red", alpha=0.2, label="slack")
    ax.set_ylabel("tension / mass [m/s²]")
    ax.legend(fontsize=8, loc="upper left")

    t = rep.series["t"]
    for ax, qname in ((axes[3], "velocity"), (axes[4], "acceleration")):
        ratio = np.abs(rep.series[qname]) / rep.limits[qname][None, :] * 100
        for j in range(7):
            ax.plot(t, ratio[:, j], lw=0.8, label=f"A{j + 1}")
        if qname == "acceleration":
            jr = (np.abs(rep.series["jerk"]) / rep.limits["jerk"][None, :]).max(axis=1) * 100
            ax.plot(
                t,
                jr,
                color="k",
                lw=0.6,
                ls="--",
                label="jerk (max joint)" + ("" if rep.jerk_enforced else ", not checked"),
            )
        ax.axhline(100, color="tab:red", lw=1.0)
        ax.set_ylabel(f"|joint {qname}| / limit [%]")
        ax.legend(fontsize=7, ncol=8, loc="upper left")
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(
        f"swing-up ({plan.method}): l = {r.length:g} m, θ_d = {math.degrees(r.theta_d):.0f}°, "
        f"max {math.degrees(ver.max_theta):.1f}°, {'taut' if ver.tension.min() > 0 else 'slack'}\n"
        f"joints: {limits_phrase(rep)}",
        fontsize=11,
    )
    fig.tight_layout()
    save_figure(fig, path, dpi=100)
