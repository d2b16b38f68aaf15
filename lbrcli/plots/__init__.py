"""Plots of the commands (matplotlib, Agg). Every figure is written through :func:`save_figure`."""

from __future__ import annotations

from pathlib import Path


def save_figure(fig, path: str | Path, dpi: int = 110) -> None:
    """Write ``fig`` to ``path`` (format from the file name) and close it; an unsupported format is bad input."""
    import matplotlib.pyplot as plt

    from trajectories.errors import OptionError

    try:
        fig.savefig(path, dpi=dpi)
    except ValueError as exc:
        if "is not supported" not in str(exc):
            raise
        raise OptionError(f"--plot {path}: not an image format matplotlib writes (use .png, .pdf or .svg)") from None
    finally:
        plt.close(fig)
