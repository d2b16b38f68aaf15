"""Parsing of command-line values: angles with deg/rad suffixes, joint vectors.

Numbers follow :mod:`trajectories.numbers` (plain ASCII decimals: no '1_0', 'nan' or 'inf'). The option parsers
of :mod:`lbrcli.options` call these at parse time; they also accept values parsed already (idempotent), so code
that receives an option's value may pass it on unchanged.
"""

from __future__ import annotations

import math

import numpy as np

from trajectories.errors import OptionError
from trajectories.numbers import NotANumber, plain_float
from trajectories.trajectory import N_JOINTS


def _where(option: str) -> str:
    return f"{option}: " if option else ""


def parse_angle(text: str | float, option: str) -> float:
    """'115deg' → 2.007 rad, '2rad' or '2' → 2.0 rad (a float is taken as radians)."""
    if isinstance(text, (int, float, np.floating)) and not isinstance(text, bool):
        value, factor = float(text), 1.0
    else:
        s = str(text).strip().lower()
        factor = 1.0
        for suffix, f in (("deg", math.pi / 180), ("°", math.pi / 180), ("rad", 1.0)):
            if s.endswith(suffix):
                s, factor = s[: -len(suffix)].strip(), f
                break
        try:
            value = plain_float(s)
        except NotANumber:
            raise OptionError(
                f"{_where(option)}not an angle: {text!r} (a plain number, optionally with deg or rad)"
            ) from None
    if not math.isfinite(value):
        raise OptionError(f"{_where(option)}not a finite angle: {text!r}")
    return value * factor


def parse_joint_vector(text: str | np.ndarray, option: str) -> np.ndarray:
    """Seven comma-separated angles, each optionally suffixed with deg/rad → (7,) [rad]; an array of 7 finite
    values is returned as it is."""
    if not isinstance(text, str):
        q = np.asarray(text, dtype=float).ravel()
        if q.shape != (N_JOINTS,) or not np.all(np.isfinite(q)):
            raise OptionError(f"{_where(option)}expected {N_JOINTS} finite joint angles")
        return q
    parts = text.replace(";", ",").split(",")
    if len(parts) != N_JOINTS:
        raise OptionError(f"{_where(option)}expected {N_JOINTS} comma-separated joint angles, got {len(parts)}")
    return np.array([parse_angle(p, option) for p in parts])
