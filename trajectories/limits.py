"""Joint limit tables of the iiwa 7 R800, loaded from one TOML data file (a user's TOML file of the same layout may replace it)."""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, replace
from importlib import resources
from pathlib import Path

import numpy as np

from .errors import InputError
from .trajectory import N_JOINTS

DEFAULT_LIMITS_FILE = "iiwa7_limits.toml"

# key in the file -> (field, factor to SI)
_KEYS = {
    "position_deg": ("position", math.pi / 180),
    "position_rad": ("position", 1.0),
    "velocity_deg_s": ("velocity", math.pi / 180),
    "velocity_rad_s": ("velocity", 1.0),
    "acceleration_deg_s2": ("acceleration", math.pi / 180),
    "acceleration_rad_s2": ("acceleration", 1.0),
    "jerk_deg_s3": ("jerk", math.pi / 180),
    "jerk_rad_s3": ("jerk", 1.0),
    "torque_nm": ("torque", 1.0),
}


@dataclass(frozen=True)
class JointLimits:
    """Symmetric per-joint limits in SI units (arrays of 7)."""

    position: np.ndarray  # [rad], |q| <= position
    velocity: np.ndarray  # [rad/s]
    acceleration: np.ndarray  # [rad/s^2]
    jerk: np.ndarray  # [rad/s^3]
    torque: np.ndarray  # [Nm]
    t1_cartesian_speed: float = 0.25  # [m/s]

    def scaled(self, factor: float) -> "JointLimits":
        """Limits scaled by ``factor`` (e.g. 1 − margin); position limits shrink the same way."""
        return replace(
            self,
            position=self.position * factor,
            velocity=self.velocity * factor,
            acceleration=self.acceleration * factor,
            jerk=self.jerk * factor,
            torque=self.torque * factor,
        )


# Plausible ranges of each table [SI units]: a limit outside them is a typo (deg for rad, a missing exponent) or a
# hostile file, and would make planners and re-timing work for hours or overflow.
_RANGES = {
    "position": (1e-3, 2 * math.pi),  # [rad]
    "velocity": (1e-3, 100.0),  # [rad/s]
    "acceleration": (1e-2, 1e4),  # [rad/s²]
    "jerk": (1e-1, 1e7),  # [rad/s³]
    "torque": (1e-2, 1e4),  # [Nm]
}
_T1_RANGE = (1e-3, 10.0)  # [m/s]
_MAX_NESTING = 100  # TOML arrays/tables nested deeper are refused before parsing (tomllib recurses)


def _number(value: object) -> float | None:
    """A TOML number as float (None for booleans, text, arrays, numbers beyond float)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    try:
        return float(value)
    except OverflowError:
        return None


def _unit(key: str) -> str:
    """'velocity_deg_s' → 'deg/s', 'jerk_rad_s3' → 'rad/s³', 'torque_nm' → 'Nm'."""
    parts = key.split("_")[1:]
    text = "/".join(parts).replace("s2", "s²").replace("s3", "s³")
    return "Nm" if text == "nm" else text


def _in_range(key: str, value: float, low: float, high: float, factor: float, where: str, source: str) -> None:
    if not (math.isfinite(value) and low <= value * factor <= high):
        unit = _unit(key)
        raise InputError(
            f"'{key}'{where} = {value:g} is outside the plausible range {low / factor:.4g}..{high / factor:.4g} {unit}",
            file=source,
        )


def _parse(data: dict, source: str, base: JointLimits | None) -> JointLimits:
    fields: dict[str, object] = {}
    if base is not None:
        fields = {
            "position": base.position,
            "velocity": base.velocity,
            "acceleration": base.acceleration,
            "jerk": base.jerk,
            "torque": base.torque,
            "t1_cartesian_speed": base.t1_cartesian_speed,
        }
    for key, value in data.items():
        if key == "t1_cartesian_speed_m_s":
            v = _number(value)
            if v is None:
                raise InputError(f"'{key}' must be a number [m/s]", file=source)
            _in_range(key, v, *_T1_RANGE, 1.0, "", source)
            fields["t1_cartesian_speed"] = v
            continue
        if key not in _KEYS:
            raise InputError(f"unknown limit table '{key}' (known: {', '.join(sorted(_KEYS))})", file=source)
        name, factor = _KEYS[key]
        values = [_number(v) for v in value] if isinstance(value, list) else []
        if len(values) != N_JOINTS or any(v is None for v in values):
            raise InputError(f"'{key}' must be a list of {N_JOINTS} numbers, one per joint A1..A7", file=source)
        for j, v in enumerate(values):
            _in_range(key, v, *_RANGES[name], factor, f" (A{j + 1})", source)
        fields[name] = np.array(values, dtype=float) * factor
    missing = [f for f in ("position", "velocity", "acceleration", "jerk", "torque") if f not in fields]
    if missing:
        raise InputError(f"missing limit tables: {', '.join(missing)}", file=source)
    return JointLimits(**fields)  # type: ignore[arg-type]


def default_limits() -> JointLimits:
    """The iiwa 7 R800 limits shipped with lbr."""
    text = resources.files("trajectories").joinpath("data", DEFAULT_LIMITS_FILE).read_text()
    return _parse(tomllib.loads(text), DEFAULT_LIMITS_FILE, None)


def _nesting(text: str) -> int:
    """Deepest run of '[' / '{' not closed (an upper bound of the TOML nesting; strings may inflate it)."""
    depth = deepest = 0
    for ch in text:
        if ch in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif ch in "]}":
            depth = max(0, depth - 1)
    return deepest


def load_limits(path: str | Path | None = None) -> JointLimits:
    """Default limits, with any tables in ``path`` (TOML, same keys) replacing the defaults. InputError (exit 2)
    naming the file for anything else: not UTF-8, not TOML, nested deeper than any limits file, unknown keys,
    values that are not numbers or outside the plausible range of their table."""
    from .inputs import MAX_SMALL_BYTES, read_text_input

    base = default_limits()
    if path is None:
        return base
    text = read_text_input(path, MAX_SMALL_BYTES, what="limits file")
    if _nesting(text) > _MAX_NESTING:
        raise InputError(f"not a limits file: nested deeper than {_MAX_NESTING} levels", file=path)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"not a valid TOML limits file ({exc})", file=path) from None
    except RecursionError:
        raise InputError("not a limits file: nested too deeply", file=path) from None
    return _parse(data, str(path), base)
