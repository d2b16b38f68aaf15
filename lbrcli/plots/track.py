"""Plot of a ball track: θ over time (when a pivot is known) and the ball's image coordinates, lost frames marked."""

from __future__ import annotations

from . import save_figure, unwrap_deg

from pathlib import Path

import numpy as np


def plot_track(track, path: str | Path, title: str = "") -> None:
    """track: anything with t [s], uv (n, 2) [px], found (n,), theta (n,) [rad] or None."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    has_theta = track.theta is not None
    fig, axes = plt.subplots(3 if has_theta else 2, 1, figsize=(10, 7.5 if has_theta else 5.5), sharex=True)
    t = track.t
    lost = ~np.asarray(track.found, bool)
    ax_list = list(axes)
    if has_theta:
        ax = ax_list.pop(0)
        ax.plot(t, unwrap_deg(track.theta), lw=1.2, color="tab:orange", label="tracked θ")
        ax.set_ylabel("θ [deg]")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    for ax, j, name in zip(ax_list, (0, 1), ("u", "v")):
        ax.plot(t, track.uv[:, j], lw=1.0, color="tab:blue")
        ax.set_ylabel(f"{name} [px]")
        ax.grid(alpha=0.3)
        if lost.any():
            ymin, ymax = ax.get_ylim()
            ax.vlines(t[lost], ymin, ymax, colors="tab:red", lw=0.5, alpha=0.4, label="not found")
            ax.legend(loc="upper right", fontsize=8)
    if has_theta and lost.any():
        ymin, ymax = axes[0].get_ylim()
        axes[0].vlines(t[lost], ymin, ymax, colors="tab:red", lw=0.5, alpha=0.4)
    axes[-1].set_xlabel("t [s]")
    found_pct = 100.0 * (1.0 - lost.mean()) if len(lost) else 0.0
    fig.suptitle(
        f"{title} — ball found in {found_pct:.1f} % of {len(t)} frames" if title else f"found {found_pct:.1f} %"
    )
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
