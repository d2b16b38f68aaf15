"""Plot of an anti-sway plan: top view of the pivot path, pivot acceleration and predicted sway against time."""

from __future__ import annotations

from . import save_figure

from pathlib import Path

import numpy as np


def plot_antisway(result, path: str | Path) -> None:
    """One PNG with three panels; the title names the shaper, residual sway and the peak joint-jerk ratio."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plan, run = result.plan, result.run
    figs = result.figures()
    fig = plt.figure(figsize=(12, 7.5))
    grid = fig.add_gridspec(2, 2, width_ratios=(1, 1.6))
    top = fig.add_subplot(grid[:, 0])
    top.plot(plan.position[:, 0], plan.position[:, 1], lw=1.5, color="tab:blue", label="pivot path")
    ends = np.array([plan.segments[0].start] + [s.end for s in plan.segments])
    top.plot(ends[:, 0], ends[:, 1], "o", color="k", ms=5)
    for k, (x, y) in enumerate(ends):
        top.annotate(str(k), (x, y), textcoords="offset points", xytext=(5, 5), fontsize=9)
    top.set_xlabel("x [m]")
    top.set_ylabel("y [m]")
    top.set_aspect("equal", adjustable="datalim")
    top.grid(alpha=0.3)
    top.set_title("top view (base frame), turning points in order", fontsize=10)

    acc_ax = fig.add_subplot(grid[0, 1])
    acc = plan.acceleration()
    acc_ax.plot(plan.t, acc[:, 0], lw=1.0, label="ẍ")
    acc_ax.plot(plan.t, acc[:, 1], lw=1.0, label="ÿ")
    acc_ax.axhline(plan.a_max, ls="--", lw=0.8, color="k")
    acc_ax.axhline(-plan.a_max, ls="--", lw=0.8, color="k", label="±a_max")
    acc_ax.set_ylabel("pivot acceleration [m/s²]")
    acc_ax.grid(alpha=0.3)
    acc_ax.legend(fontsize=8, loc="upper right")
    acc_ax.set_title(
        f"shaper {plan.shaper}; peak joint jerk {figs['jerk_ratio'] * 100:.0f} % of the limit"
        + (" (acceleration steps: jerk unbounded)" if plan.shaper == "accel" else ""),
        fontsize=10,
    )

    sway = fig.add_subplot(grid[1, 1], sharex=acc_ax)
    sway.plot(run.t, np.degrees(run.theta_x), lw=1.0, label="θx (toward +x)")
    sway.plot(run.t, np.degrees(run.theta_y), lw=1.0, label="θy (toward +y)")
    sway.plot(run.t, np.degrees(run.theta), lw=0.8, color="k", alpha=0.5, label="tilt θ")
    sway.axvline(result.stop_time, ls=":", color="tab:red", lw=1.0, label="last stop")
    sway.set_xlabel("t [s]")
    sway.set_ylabel("predicted sway [deg]")
    sway.grid(alpha=0.3)
    sway.legend(fontsize=8, loc="upper right")
    sway.set_title(
        f"nonlinear spherical pendulum, l = {plan.string_length:.3f} m: peak {figs['peak_sway_deg']:.2f}°, "
        f"residual {figs['residual_sway_deg']:.3f}°",
        fontsize=10,
    )
    status = "within joint limits" if figs["limits_ok"] else "LIMITS VIOLATED"
    fig.suptitle(
        f"anti-sway plan: moving {figs['motion_s']:.2f} s (thesis baseline {figs['baseline_motion_s']:.2f} s), "
        f"a_max {plan.a_max:g} m/s², {status}"
    )
    fig.tight_layout()
    save_figure(fig, path, dpi=110)

