"""Parsing of command-line values: angles with deg/rad suffixes, joint vectors, point lists."""

from __future__ import annotations

import math

import numpy as np

from trajectories.errors import OptionError
from trajectories.trajectory import N_JOINTS


def parse_angle(text: str, option: str) -> float:
    """'115deg' → 2.007 rad, '2rad' or '2' → 2.0 rad."""
    s = str(text).strip().lower()
    factor = 1.0
    for suffix, f in (("deg", math.pi / 180), ("°", math.pi / 180), ("rad", 1.0)):
        if s.endswith(suffix):
            s, factor = s[: -len(suffix)].strip(), f
            break
    try:
        value = float(s)
    except ValueError:
        raise OptionError(f"{option}: not an angle: {text!r} (a number, optionally with deg or rad)") from None
    if not math.isfinite(value):
        raise OptionError(f"{option}: not a finite angle: {text!r}")
    return value * factor


def parse_joint_vector(text: str, option: str) -> np.ndarray:
    """Seven comma-separated angles, each optionally suffixed with deg/rad → (7,) [rad]."""
    parts = [p for p in str(text).replace(";", ",").split(",")]
    if len(parts) != N_JOINTS:
        raise OptionError(f"{option}: expected {N_JOINTS} comma-separated joint angles, got {len(parts)}")
    return np.array([parse_angle(p, option) for p in parts])


def parse_floats(text: str, option: str, count: int | None = None) -> np.ndarray:
    """Comma-separated finite numbers."""
    try:
        vals = np.array([float(p) for p in str(text).split(",")])
    except ValueError:
        raise OptionError(f"{option}: expected comma-separated numbers, got {text!r}") from None
    if count is not None and len(vals) != count:
        raise OptionError(f"{option}: expected {count} numbers, got {len(vals)}")
    if not np.all(np.isfinite(vals)):
        raise OptionError(f"{option}: numbers must be finite, got {text!r}")
    return vals


def parse_points(text: str, option: str, dims: int = 2) -> np.ndarray:
    """'x0,y0;x1,y1;...' → (n, dims) [m]."""
    pts = [p for p in str(text).split(";") if p.strip()]
    if not pts:
        raise OptionError(f"{option}: expected points 'x0,y0;x1,y1;...'")
    return np.array([parse_floats(p, option, dims) for p in pts])
