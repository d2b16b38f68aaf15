"""Model vs experiment: θ over time overlaid (as the thesis's Figs. 4.5 and 5.6) and the error."""

from __future__ import annotations

from . import save_figure, unwrap_deg

from pathlib import Path

import numpy as np


def plot_compare(
    cmp,
    t_model: np.ndarray,
    theta_model: np.ndarray,
    path: str | Path,
    title: str = "",
    t_meas: np.ndarray | None = None,
    theta_meas: np.ndarray | None = None,
) -> None:
    """Overlay on the model's time axis: the prediction (blue) and the measurement shifted by the lag (orange).

    t_meas, theta_meas [s, rad]: the whole track (as compared, i.e. already negated with --flip), drawn
    faintly outside the overlap.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, ax_err) = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    # the experiment wide and light underneath, the model thin and dashed on top: both stay visible where they agree
    if t_meas is not None and theta_meas is not None:
        ax.plot(
            np.asarray(t_meas) - cmp.lag_s,
            unwrap_deg(theta_meas),
            color="tab:orange",
            lw=1.0,
            alpha=0.35,
            zorder=1,
            label="experiment outside the overlap",
        )
    ax.plot(
        cmp.t - cmp.lag_s,
        unwrap_deg(cmp.measured),
        color="tab:orange",
        lw=3.0,
        alpha=0.75,
        zorder=2,
        label="experiment (track)",
    )
    ax.plot(t_model, unwrap_deg(theta_model), color="tab:blue", lw=1.3, ls="--", zorder=3, label="model (prediction)")
    ax.set_ylabel("θ [deg]")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper right", fontsize=9)
    ax_err.plot(cmp.t - cmp.lag_s, np.degrees(cmp.measured - cmp.model), color="tab:red", lw=1.0)
    ax_err.axhline(0.0, color="k", lw=0.6)
    ax_err.set_ylabel("exp. − model [deg]")
    ax_err.set_xlabel("t [s] (model time; track shifted by the lag)")
    ax_err.grid(alpha=0.3)
    figures = f"lag {cmp.lag_s:.3f} s, RMS {cmp.rms_deg:.2f}°, max {cmp.max_deg:.2f}° over {cmp.overlap_s:.2f} s"
    fig.suptitle(f"{title}\n{figures}" if title else figures, fontsize=10)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
