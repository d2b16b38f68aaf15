"""Plot of a cup-and-ball plan: side view of the ball's and the cup's paths with the phases, the paths over time, and
the joint rates against their limits."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import limits_phrase, save_figure

PHASE_STYLE = {0: ("taut", "tab:blue"), 1: ("slack (free flight)", "tab:orange"), 2: ("in the cup", "tab:green")}


def cup_outline(anchor: np.ndarray, cup) -> np.ndarray:
    """(m, 2) y–z outline [m] of the cup's cross-section (in its plane through the axis) for an upright cup."""
    ri, ro, rim, zb = cup.inner_radius, cup.outer_radius, cup.rim_height, cup.bottom_height
    pts = np.array(
        [(-ri, rim), (-ri, zb), (ri, zb), (ri, rim), (ro, rim), (ro, 0.0), (-ro, 0.0), (-ro, rim), (-ri, rim)]
    )
    return pts + anchor[None, :]


def plot_catch(result, path: str | Path) -> None:
    """One PNG for ``planners.catch_plan.CatchResult``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle

    run, r, rep = result.prediction, result.request, result.check
    m = r.model
    origin = run.pivot[0, 1:]
    ball = run.position[:, 1:] - origin
    anchor = run.pivot[:, 1:] - origin
    fig = plt.figure(figsize=(11, 12))
    grid = fig.add_gridspec(3, 1, height_ratios=[2.2, 1.0, 1.0])

    ax = fig.add_subplot(grid[0])
    for code, (label, color) in PHASE_STYLE.items():
        sel = np.where(run.phase == code, 1.0, np.nan)
        ax.plot(ball[:, 0] * sel, ball[:, 1] * sel, color=color, lw=1.6, label=f"ball: {label}")
    ax.plot(anchor[:, 0], anchor[:, 1], color="k", lw=1.0, label="string anchor (cup bottom)")
    ax.plot(anchor[:, 0], anchor[:, 1] + m.cup.rim_height, color="0.5", lw=0.8, ls="--", label="rim centre")
    n = result.nominal
    marks = [
        (n.t_release, "release"),
        (n.t_entry or n.t_crossing, "entry" if n.t_entry else "at the rim height"),
        (float(run.t[-1]), "end"),
    ]
    for t_mark, label in marks:
        if t_mark is None:
            continue
        k = min(int(np.searchsorted(run.t, t_mark)), len(run.t) - 1)
        ax.plot(*cup_outline(anchor[k], m.cup).T, color="0.2", lw=1.2)
        ax.add_patch(Circle(tuple(ball[k]), m.ball.radius, fill=False, color="tab:red", lw=1.0))
        ax.annotate(f"{label} {run.t[k]:.2f} s", ball[k], textcoords="offset points", xytext=(8, 8), fontsize=8)
    ax.set_aspect("equal")
    ax.set_xlabel("base y from the start pose [m]")
    ax.set_ylabel("base z from the start pose [m]")
    ax.legend(fontsize=8, loc="lower left")
    ax.grid(alpha=0.3)

    ax = fig.add_subplot(grid[1])
    for k, (name, ls) in enumerate((("y", "-"), ("z", "--"))):
        ax.plot(run.t, ball[:, k], color="tab:red", ls=ls, lw=1.0, label=f"ball {name}")
        ax.plot(run.t, anchor[:, k], color="k", ls=ls, lw=1.0, label=f"anchor {name}")
    for code, (label, color) in PHASE_STYLE.items():
        ax.fill_between(
            run.t, -1, 1, where=run.phase == code, color=color, alpha=0.12, transform=ax.get_xaxis_transform()
        )
    ax.set_ylabel("position [m]")
    ax.legend(fontsize=8, ncol=4, loc="upper left")

    ax = fig.add_subplot(grid[2])
    t = rep.series["t"]
    for qname, color in (("velocity", "tab:blue"), ("acceleration", "tab:orange"), ("jerk", "tab:green")):
        ratio = (np.abs(rep.series[qname]) / rep.limits[qname][None, :]).max(axis=1) * 100
        ax.plot(t, ratio, color=color, lw=0.9, label=f"{qname} (max joint)")
    ax.axhline(100, color="tab:red", lw=1.0)
    ax.set_ylabel("|joint rate| / limit [%]")
    ax.set_xlabel("t [s]")
    ax.legend(fontsize=8, loc="upper left")

    rb = result.band
    state = (
        f"caught: enters {n.t_entry:.2f} s, margin {1e3 * n.margin:.0f} mm, {n.relative_speed:.2f} m/s"
        if n.caught
        else f"NOT caught: {n.failure}"
    )
    fig.suptitle(
        f"cup-and-ball: l = {m.length:g} m, cup r = {1e3 * m.cup.inner_radius:.0f} mm, ball r = "
        f"{1e3 * m.ball.radius:.0f} mm — {state}\nband (l ±{100 * r.length_tol:g} %, m ±{100 * r.mass_tol:g} %"
        f"{', timing ±1 period' if r.timing else ''}): {100 * rb.success:.0f} % caught; joints: {limits_phrase(rep)}",
        fontsize=10,
    )
    fig.tight_layout()
    save_figure(fig, path, dpi=100)
