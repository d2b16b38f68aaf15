"""Plots of a study: a figure (or the share of runs that succeeded) over one or two varied options.

On a grid the cells are heat-map squares (mean over the samples of a cell; the run count in each when it is more
than one); with random parameters every run is a dot coloured by its value. Success maps colour the share of runs
that exited 0 from red (none) to green (all).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Sequence

from . import save_figure

MAX_CATEGORIES = 40  # distinct values an axis may have to be drawn as heat-map cells


def _number(v) -> float | None:
    if isinstance(v, bool):
        return float(v)
    if isinstance(v, (int, float)) and math.isfinite(v):
        return float(v)
    return None


def numeric(rows: Sequence[dict], name: str) -> bool:
    """True when every run has a finite number (or bool) for ``name``."""
    return bool(rows) and all(_number(r.get(name)) is not None for r in rows)


def plot_study(rows: Sequence[dict], x: str, y: str | None, value: str, path: str | Path, title: str) -> None:
    """One PNG of ``value`` (a column, or ``ok``: exit code 0) over ``x`` (and ``y``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    success = value == "ok"
    label = "share of runs that exited 0" if success else value
    vals = [1.0 if r["exit_code"] == 0 else 0.0 for r in rows] if success else [_number(r.get(value)) for r in rows]
    keep = [i for i, v in enumerate(vals) if v is not None]
    xs = [rows[i][x] for i in keep]
    ys = [rows[i][y] for i in keep] if y else None
    vs = np.array([vals[i] for i in keep], dtype=float)
    cmap = "RdYlGn" if success else "viridis"
    fig, ax = plt.subplots(figsize=(7.5, 5.5))
    if not keep:
        ax.text(0.5, 0.5, f"no run reported {value}", ha="center", va="center", transform=ax.transAxes)
    elif y is None:
        xv = np.array([_number(v) for v in xs], dtype=float) if all(_number(v) is not None for v in xs) else None
        if xv is None:
            cats = sorted(set(map(str, xs)))
            xv = np.array([cats.index(str(v)) for v in xs], dtype=float)
            ax.set_xticks(range(len(cats)), cats, rotation=30, ha="right")
        ax.plot(xv, vs, ".", alpha=0.5, label="runs")
        ux = np.unique(xv)
        if len(ux) < len(xv):
            ax.plot(ux, [vs[xv == u].mean() for u in ux], "-", lw=2, label="mean")
            ax.legend()
        ax.set_ylabel(label)
    else:
        cx, cy = sorted(set(xs), key=_sortable), sorted(set(ys), key=_sortable)
        if len(cx) <= MAX_CATEGORIES and len(cy) <= MAX_CATEGORIES and len(cx) * len(cy) < len(xs) + 1:
            grid = np.full((len(cy), len(cx)), np.nan)
            count = np.zeros_like(grid)
            for xv_, yv_, v in zip(xs, ys, vs):
                i, j = cy.index(yv_), cx.index(xv_)
                grid[i, j] = v if count[i, j] == 0 else grid[i, j] + v
                count[i, j] += 1
            grid = np.where(count > 0, grid / np.maximum(count, 1), np.nan)
            im = ax.imshow(grid, origin="lower", aspect="auto", cmap=cmap,
                           vmin=0 if success else None, vmax=1 if success else None)  # fmt: skip
            ax.set_xticks(range(len(cx)), [_fmt(v) for v in cx], rotation=30, ha="right")
            ax.set_yticks(range(len(cy)), [_fmt(v) for v in cy])
            if grid.size <= 144:
                for i in range(len(cy)):
                    for j in range(len(cx)):
                        if count[i, j]:
                            n = f"\n(n={int(count[i, j])})" if count.max() > 1 else ""
                            ax.text(j, i, f"{grid[i, j]:.3g}{n}", ha="center", va="center", fontsize=7)
        else:
            im = ax.scatter([_number(v) for v in xs], [_number(v) for v in ys], c=vs, cmap=cmap, s=18,
                            vmin=0 if success else None, vmax=1 if success else None)  # fmt: skip
        fig.colorbar(im, ax=ax, label=label)
        ax.set_ylabel(y)
    ax.set_xlabel(x)
    ax.set_title(title, fontsize=10)
    fig.tight_layout()
    save_figure(fig, path)


def _sortable(v):
    n = _number(v)
    return (0, n, "") if n is not None else (1, 0.0, str(v))


def _fmt(v) -> str:
    n = _number(v)
    return f"{n:.4g}" if n is not None and not isinstance(v, bool) else str(v)
