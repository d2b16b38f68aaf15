"""Test support for the lab's camera path: a free spherical pendulum as the scene a simulated camera films (the
camera-stream tests and ``benchmarks/bench_live.py`` judge the live tracker against it)."""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from planners.pendulum import PendulumRun, direction_from_angles, simulate

Scene = Callable[[float], tuple[np.ndarray, np.ndarray]]  # t [s] → (ball, pivot) [m]


def free_pendulum_scene(pivot_m: np.ndarray, string_m: float, seconds: float) -> tuple[PendulumRun, Scene]:
    """A free spherical pendulum on a still pivot ``pivot_m`` [m], string ``string_m`` [m], started at 14° / −6° of
    tilt with 0.7 m/s sideways (an elliptical orbit: both tilt components move), simulated for ``seconds`` [s] on a
    1 ms grid by :func:`planners.pendulum.simulate`; the run and the scene (linear between grid points)."""
    grid = np.arange(0.0, seconds, 0.001)
    run = simulate(grid, lambda t: np.zeros(3), string_m, s0=direction_from_angles(math.radians(14), math.radians(-6)),
                   sdot0=np.array([0.0, 0.7, 0.0]))  # fmt: skip

    def scene(t: float) -> tuple[np.ndarray, np.ndarray]:
        k = min(max(t, 0.0), grid[-1] - 2e-3) / 1e-3
        i = int(k)
        return pivot_m + string_m * ((1 - (k - i)) * run.s[i] + (k - i) * run.s[i + 1]), pivot_m

    return run, scene
