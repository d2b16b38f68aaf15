"""Plots of the commands (matplotlib, Agg). Every figure is written through :func:`save_figure`."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np


def save_figure(fig, path: str | Path, dpi: int = 110) -> None:
    """Write ``fig`` to ``path`` (format from the file name; atomically: a temporary name renamed when complete) and
    close it; an unsupported format is bad input."""
    import matplotlib.pyplot as plt

    from trajectories.errors import SettingError

    from trajectories.atomic import atomic_path

    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=dpi, format=Path(path).suffix.lstrip(".").lower() or "png")
    except ValueError as exc:
        if "is not supported" not in str(exc):
            raise
        raise SettingError(
            "Plot", "path", f"{path}: not an image format matplotlib writes (use .png, .pdf or .svg)"
        ) from None
    finally:
        plt.close(fig)


def unwrap_deg(angle_rad) -> "np.ndarray":
    """Angles [rad] → degrees with the ±180° wraps removed inside every run of finite samples; NaN samples stay
    gaps, and a run after a gap starts from its own value (no offset is carried across what was not measured)."""
    import numpy as np

    a = np.asarray(angle_rad, dtype=float)
    out = np.full(a.shape, np.nan)
    ok = np.isfinite(a)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], ok.astype(np.int8), [0]])))
    for start, stop in zip(edges[::2], edges[1::2]):
        out[start:stop] = np.degrees(np.unwrap(a[start:stop]))
    return out


def limits_phrase(report) -> str:
    """What a CheckReport checked and found, for a title: the quantities checked, the peaks [% of the limits],
    and jerk as reported-only when it is not enforced (never "within limits" while jerk is above its table)."""
    peak = {k: 100.0 * float(v.max()) for k, v in report.ratios().items()}
    checked = "position, velocity, acceleration" + (", jerk" if report.jerk_enforced else "")
    scaled = f" × {1 - report.margin:.2f}" if report.margin else ""
    status = "within the limits" if report.ok else f"{len(report.failing)} limit violations"
    peaks = "/".join(f"{peak[k]:.0f}" for k in ("position", "velocity", "acceleration"))
    text = f"{checked}{scaled}: {status} (peaks {peaks} %"
    text += f", jerk {peak['jerk']:.0f} %)" if report.jerk_enforced else ")"
    if not report.jerk_enforced:
        text += f"; jerk {peak['jerk']:.0f} % of its limit" + (
            " — NOT checked" if peak["jerk"] > 100 else ", not checked"
        )
    return text
