"""Plot of joint position, velocity, acceleration and jerk against the limits (thesis Fig. 5.3, plus jerk)."""

from __future__ import annotations

from . import limits_phrase, save_figure

from pathlib import Path

import numpy as np

QUANTITIES = (("position", "rad"), ("velocity", "rad/s"), ("acceleration", "rad/s²"), ("jerk", "rad/s³"))


def plot_check(report, path: str | Path, title: str = "") -> None:
    """Every joint's position, velocity, acceleration and jerk with the ± limit lines (× (1 − margin)); samples
    over a limit in red (over the jerk limit in orange when jerk is not enforced). The title states what was
    checked and the peaks."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = report.series["t"]
    series = report.series
    fig, axes = plt.subplots(7, len(QUANTITIES), figsize=(16, 12), sharex=True)
    peaks = report.ratios()
    for col, (qname, unit) in enumerate(QUANTITIES):
        data = series.get(qname)
        enforced = qname != "jerk" or report.jerk_enforced
        for j in range(7):
            ax = axes[j, col]
            lim = report.limits[qname][j]
            if data is not None:
                ax.plot(t, data[:, j], lw=1.0, color="tab:blue", zorder=2)
                over = np.abs(data[:, j]) > lim
                if over.any():
                    ax.plot(
                        t[over], data[over, j], ".", ms=2.5, color="tab:red" if enforced else "tab:orange", zorder=3
                    )
            ax.axhline(lim, ls="--", lw=0.8, color="k", zorder=1)
            ax.axhline(-lim, ls="--", lw=0.8, color="k", zorder=1)
            ax.set_ylabel(f"A{j + 1} [{unit}]", fontsize=8)
            ax.tick_params(labelsize=7)
            ax.grid(alpha=0.3)
            ax.text(
                0.99,
                0.95,
                f"{100 * peaks[qname][j]:.0f} %",
                transform=ax.transAxes,
                ha="right",
                va="top",
                fontsize=7,
                color="tab:red" if peaks[qname][j] > 1 and enforced else "0.3",
            )
            if j == 0:
                note = "" if enforced else " — reported, not checked (jerk not enforced)"
                ax.set_title(f"joint {qname}{note}", fontsize=9)
        axes[-1, col].set_xlabel("t [s]")
    status = limits_phrase(report)
    fig.suptitle(f"{title} — {status}" if title else status, fontsize=10)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
