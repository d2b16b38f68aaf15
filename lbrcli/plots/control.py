"""Plots of feedback-control runs (`lbr control`), drawn from the execution log."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import save_figure


def plot_upright(log_path: str | Path, path: str | Path) -> None:
    """Two panels: the rod's angle from upright [deg] (simulated truth if logged, the observer's estimate) with the
    controller's mode shaded, and the cart position [m] and acceleration [m/s²]."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from trajectories.csvio import read_table

    from ..fri.log import LOG_COLUMNS, NAN_COLUMNS

    tab = read_table(log_path, LOG_COLUMNS, time="increasing", nan_columns=NAN_COLUMNS + ("est_phi", "est_omega"))
    t = tab.column("t")
    fig, axes = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
    ax = axes[0]

    def from_upright(phi):
        return np.degrees(np.angle(np.exp(1j * (phi - np.pi))))

    if tab.has("pendulum_phi"):
        ax.plot(t, from_upright(tab.column("pendulum_phi")), color="0.6", lw=2.0, label="simulated rod (truth)")
    if tab.has("est_phi"):
        est = tab.column("est_phi")
        if tab.has("mode"):
            est = np.where(tab.column("mode") >= 0, est, np.nan)  # mode −1: the controller had not started
        ax.plot(t, from_upright(est), color="tab:blue", lw=0.8, label="observer estimate")
    if tab.has("mode"):
        mode = tab.column("mode")
        bal = mode == 1
        if bal.any():
            edges = np.flatnonzero(np.diff(np.concatenate([[0], bal.astype(np.int8), [0]])))
            for k, (a, b) in enumerate(zip(edges[::2], edges[1::2])):
                ax.axvspan(t[a], t[b - 1], color="tab:green", alpha=0.12, label="balancing" if k == 0 else None)
    ax.set_ylabel("rod angle from upright [deg]")
    ax.set_ylim(-185, 185)
    ax.legend(fontsize=8, loc="upper right")
    ax.grid(alpha=0.3)
    ax = axes[1]
    if tab.has("cart_x"):
        ax.plot(t, tab.column("cart_x"), color="tab:orange", lw=1.0, label="cart position [m]")
        ax.set_ylabel("cart position along base y [m]", color="tab:orange")
        ax2 = ax.twinx()
        ax2.plot(t, tab.column("cart_a"), color="tab:purple", lw=0.6, alpha=0.7)
        ax2.set_ylabel("cart acceleration [m/s²]", color="tab:purple")
    ax.grid(alpha=0.3)
    axes[-1].set_xlabel("t [s] (controller time)")
    fig.suptitle(f"pendulum module upright: {Path(log_path).name}")
    save_figure(fig, path)
