"""Finite-difference derivatives of sampled trajectories (thesis eq. 5.7, applied repeatedly)."""

from __future__ import annotations

import numpy as np


def central_difference(x: np.ndarray, h: float) -> np.ndarray:
    """Derivative of samples x (n, ...) one step h [s] apart: (x[k+1] − x[k−1]) / 2h inside, one-sided at the ends."""
    x = np.asarray(x, dtype=float)
    if x.shape[0] < 2:
        return np.zeros_like(x)
    return np.gradient(x, h, axis=0, edge_order=1)


def derivatives(x: np.ndarray, h: float, order: int = 3) -> list[np.ndarray]:
    """[ẋ, ẍ, x⃛, ...] up to ``order`` by applying the central difference repeatedly (thesis §5.3.2)."""
    out = []
    d = np.asarray(x, dtype=float)
    for _ in range(order):
        d = central_difference(d, h)
        out.append(d)
    return out
