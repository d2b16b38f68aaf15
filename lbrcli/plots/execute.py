"""Plot of an execution log: commanded vs measured joints, tracking, and the (simulated) ball sway."""

from __future__ import annotations

from . import save_figure, unwrap_deg

from pathlib import Path

import numpy as np


def mask_degenerate(
    planar: np.ndarray, theta: np.ndarray, phi: np.ndarray, axis: str, min_projection: float = 0.2
) -> np.ndarray:
    """NaN where the planar swing angle θx (axis 'x') or θy ('y') is undefined: the string's projection onto that
    vertical plane is shorter than ``min_projection`` of its length (the string nearly perpendicular to the
    plane, e.g. θx while the ball swings over the top in the y–z plane). θ tilt, φ azimuth [rad]."""
    horizontal = np.sin(theta) * (np.cos(phi) if axis == "x" else np.sin(phi))
    projection = np.hypot(horizontal, np.cos(theta))
    return np.where(projection >= min_projection, planar, np.nan)


def plot_execution(log_path: str | Path, path: str | Path, title: str = "") -> None:
    """Three panels from the log: joint positions (commanded dashed, measured solid) [rad], tracking performance
    and max |measured − commanded| [mrad] in COMMANDING_ACTIVE, ball tilt ``ball_theta`` [deg] if logged."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from trajectories.csvio import read_table

    from ..fri.log import LOG_COLUMNS, NAN_COLUMNS

    tab = read_table(log_path, LOG_COLUMNS, time="increasing", nan_columns=NAN_COLUMNS)
    t = tab.column("t")
    cmd = np.column_stack([tab.column(f"cmd_q{j}") for j in range(1, 8)])
    msr = np.column_stack([tab.column(f"msr_q{j}") for j in range(1, 8)])
    active = tab.column("state") == 4
    has_ball = tab.has("ball_theta")
    fig, axes = plt.subplots(3 if has_ball else 2, 1, figsize=(10, 9 if has_ball else 6.5), sharex=True)
    ax = axes[0]
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for j in range(7):
        c = colors[j % len(colors)]
        ax.plot(t, msr[:, j], lw=1.0, color=c, label=f"A{j + 1}")
        ax.plot(t, cmd[:, j], lw=1.0, ls="--", color=c)
    ax.set_ylabel("joint position [rad]")
    ax.set_title("measured (solid) and commanded (dashed)", fontsize=9)
    ax.legend(ncol=7, fontsize=7, loc="upper center")
    ax.grid(alpha=0.3)

    ax = axes[1]
    tracking = np.where(active, tab.column("tracking"), np.nan)
    ax.plot(t, tracking, color="tab:blue", lw=1.0)
    ax.set_ylabel("tracking performance [0..1]", color="tab:blue")
    ax.set_ylim(-0.05, 1.05)
    ax.grid(alpha=0.3)
    ax2 = ax.twinx()
    err = np.where(active, np.max(np.abs(msr - cmd), axis=1), np.nan) * 1e3
    ax2.plot(t, err, color="tab:red", lw=0.8)
    ax2.set_ylabel("max |measured − commanded| [mrad]", color="tab:red")
    if has_ball:
        ax = axes[2]
        theta = tab.column("ball_theta")
        ax.plot(t, np.degrees(theta), color="0.7", lw=2.4, label="tilt θ", zorder=1)
        for name, style, color in (("ball_theta_x", "-", "tab:blue"), ("ball_theta_y", "--", "tab:orange")):
            if tab.has(name):
                planar = tab.column(name)
                if tab.has("ball_phi"):
                    planar = mask_degenerate(planar, theta, tab.column("ball_phi"), axis=name[-1])
                ax.plot(
                    t,
                    unwrap_deg(planar),
                    lw=1.0,
                    ls=style,
                    color=color,
                    zorder=2,
                    label=name.replace("ball_", "") + " (unwrapped)",
                )
        ax.set_ylabel("ball sway [deg]")
        ax.legend(fontsize=7, title="θx, θy blank where the string is perpendicular to their plane", title_fontsize=7)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("t [s] (controller time)")
    if active.any():
        for a in axes:
            a.axvspan(t[active][0], t[active][-1], color="0.9", zorder=-1)
    fig.suptitle(title or str(log_path))
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
