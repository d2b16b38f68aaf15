"""Plot of an anti-sway plan: top view of the pivot path, pivot acceleration and predicted sway against time."""

from __future__ import annotations

from . import limits_phrase, save_figure, unwrap_deg

from pathlib import Path

import numpy as np


def plot_antisway(result, path: str | Path) -> None:
    """One PNG with three panels; the title names the shaper, residual sway and the peak joint-jerk ratio."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plan = result.plan
    figs = result.figures()
    fig = plt.figure(figsize=(12, 7.5))
    grid = fig.add_gridspec(2, 2, width_ratios=(1, 1.6))
    _top_view(fig.add_subplot(grid[:, 0]), result)
    acc_ax = fig.add_subplot(grid[0, 1])
    _acceleration_panel(acc_ax, result, figs)
    _sway_panel(fig.add_subplot(grid[1, 1], sharex=acc_ax), result, figs)
    fig.suptitle(
        f"anti-sway plan: moving {figs['motion_s']:.2f} s (thesis baseline {figs['baseline_motion_s']:.2f} s), "
        f"a_max {plan.a_max:g} m/s²\njoints: {limits_phrase(result.report)}",
        fontsize=11,
    )
    fig.tight_layout()
    save_figure(fig, path, dpi=110)


def _top_view(top, result) -> None:
    """The pivot path, the ball's paths across the length band, the obstacles and the turning points, from above."""
    import matplotlib
    from matplotlib.patches import Rectangle

    plan, band = result.plan, result.band
    top.plot(plan.position[:, 0], plan.position[:, 1], lw=1.5, color="tab:blue", label="pivot path")
    if band is not None:
        colours = matplotlib.colormaps["viridis"](np.linspace(0.0, 0.85, len(band.lengths)))
        for ln, ball, col in zip(band.lengths, band.ball_paths, colours):
            top.plot(ball[:, 0], ball[:, 1], lw=0.8, color=col, alpha=0.9, label=f"ball, string {ln:.3f} m")
    for ob in result.obstacles:
        w, h = ob.upper[0] - ob.lower[0], ob.upper[1] - ob.lower[1]
        top.add_patch(Rectangle(ob.lower[:2], w, h, color="tab:red", alpha=0.35))
        top.annotate(
            f"{ob.name} (z {ob.lower[2]:.2f}–{ob.upper[2]:.2f} m)",
            (ob.lower[0], ob.upper[1]),
            fontsize=8,
            color="tab:red",
        )
    if result.obstacles:
        c = band.clearance
        top.plot(
            [c.position[0]],
            [c.position[1]],
            "x",
            color="tab:red",
            ms=8,
            label=f"least clearance {c.clearance * 1000:.0f} mm ({c.obstacle})",
        )
    top.legend(fontsize=7, loc="best")
    ends = np.array([plan.segments[0].start] + [s.end for s in plan.segments])
    top.plot(ends[:, 0], ends[:, 1], "o", color="k", ms=5)
    for k, (x, y) in enumerate(ends):
        top.annotate(str(k), (x, y), textcoords="offset points", xytext=(5, 5), fontsize=9)
    top.set_xlabel("x [m]")
    top.set_ylabel("y [m]")
    top.set_aspect("equal", adjustable="datalim")
    top.grid(alpha=0.3)
    top.set_title("top view (base frame), turning points in order", fontsize=10)


def _acceleration_panel(ax, result, figs: dict) -> None:
    """The pivot's acceleration [m/s²] against time, with ±a_max."""
    plan = result.plan
    acc = plan.acceleration()
    ax.plot(plan.t, acc[:, 0], lw=1.0, label="ẍ")
    ax.plot(plan.t, acc[:, 1], lw=1.0, label="ÿ")
    ax.axhline(plan.a_max, ls="--", lw=0.8, color="k")
    ax.axhline(-plan.a_max, ls="--", lw=0.8, color="k", label="±a_max")
    ax.set_ylabel("pivot acceleration [m/s²]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper right")
    ax.set_title(
        f"shaper {plan.shaper}; peak joint jerk {figs['jerk_ratio'] * 100:.0f} % of the limit"
        + (" (acceleration steps: jerk unbounded)" if plan.shaper == "accel" else ""),
        fontsize=10,
    )


def _sway_panel(ax, result, figs: dict) -> None:
    """The predicted sway [deg] against time: tilt, its components, the worst across the band, the limit."""
    plan, run, band = result.plan, result.run, result.band
    ax.plot(run.t, np.degrees(run.theta), lw=2.2, color="0.75", label="tilt θ", zorder=1)
    ax.plot(run.t, unwrap_deg(run.theta_x), lw=1.0, color="tab:blue", label="θx (toward +x)", zorder=2)
    ax.plot(run.t, unwrap_deg(run.theta_y), lw=1.0, ls="--", color="tab:orange", label="θy (toward +y)", zorder=3)
    if band is not None and len(band.lengths) > 1:
        env = np.max([np.degrees(r.theta) for r in band.runs], axis=0)
        ax.plot(
            band.runs[0].t,
            env,
            lw=0.8,
            ls="--",
            color="tab:purple",
            label=f"worst tilt, string ±{plan.options.length_tolerance * 100:g} %",
        )
    if result.max_sway is not None:
        ax.axhline(np.degrees(result.max_sway), ls="-.", lw=0.8, color="tab:red", label="max sway")
    ax.axvline(result.stop_time, ls=":", color="tab:red", lw=1.0, label="last stop")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("predicted sway [deg]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper right")
    ax.set_title(
        f"nonlinear spherical pendulum, l = {plan.string_length:.3f} m: peak {figs['peak_sway_deg']:.2f}°, "
        f"residual {figs['residual_sway_deg']:.3f}°",
        fontsize=10,
    )
