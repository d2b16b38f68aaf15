"""Plot of joint velocity and acceleration against the limits (thesis Fig. 5.3)."""

from __future__ import annotations

from . import save_figure

from pathlib import Path

import numpy as np


def plot_check(report, path: str | Path, title: str = "") -> None:
    """Velocity and acceleration of every joint with the ± limit lines; violations in red."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = report.series["t"]
    fig, axes = plt.subplots(7, 2, figsize=(11, 12), sharex=True)
    for col, (qname, unit) in enumerate((("velocity", "rad/s"), ("acceleration", "rad/s²"))):
        data = report.series[qname]
        for j in range(7):
            ax = axes[j, col]
            lim = report.limits[qname][j]
            ax.plot(t, data[:, j], lw=1.0, color="tab:blue")
            over = np.abs(data[:, j]) > lim
            if over.any():
                ax.plot(t[over], data[over, j], ".", ms=2, color="tab:red")
            ax.axhline(lim, ls="--", lw=0.8, color="k")
            ax.axhline(-lim, ls="--", lw=0.8, color="k")
            ax.set_ylabel(f"A{j + 1} [{unit}]", fontsize=8)
            ax.tick_params(labelsize=7)
            ax.grid(alpha=0.3)
            if j == 0:
                ax.set_title(f"joint {qname} (limits × {1 - report.margin:.2f})", fontsize=9)
        axes[-1, col].set_xlabel("t [s]")
    status = "within limits" if report.ok else f"{len(report.failing)} violations"
    fig.suptitle(f"{title} — {status}" if title else status)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
