"""Joint limit tables of the iiwa 7 R800, loaded from one TOML data file (overridable with --limits)."""

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
            if not isinstance(value, (int, float)) or value <= 0:
                raise InputError(f"'{key}' must be a positive number", file=source)
            fields["t1_cartesian_speed"] = float(value)
            continue
        if key not in _KEYS:
            raise InputError(f"unknown limit table '{key}' (known: {', '.join(sorted(_KEYS))})", file=source)
        name, factor = _KEYS[key]
        if (
            not isinstance(value, list)
            or len(value) != N_JOINTS
            or not all(isinstance(v, (int, float)) and math.isfinite(v) and v > 0 for v in value)
        ):
            raise InputError(f"'{key}' must be a list of {N_JOINTS} positive numbers", file=source)
        fields[name] = np.array(value, dtype=float) * factor
    missing = [f for f in ("position", "velocity", "acceleration", "jerk", "torque") if f not in fields]
    if missing:
        raise InputError(f"missing limit tables: {', '.join(missing)}", file=source)
    return JointLimits(**fields)  # type: ignore[arg-type]


def default_limits() -> JointLimits:
    """The iiwa 7 R800 limits shipped with lbr."""
    text = resources.files("trajectories").joinpath("data", DEFAULT_LIMITS_FILE).read_text()
    return _parse(tomllib.loads(text), DEFAULT_LIMITS_FILE, None)


def load_limits(path: str | Path | None = None) -> JointLimits:
    """Default limits, with any tables in ``path`` (TOML, same keys) replacing the defaults."""
    base = default_limits()
    if path is None:
        return base
    try:
        data = tomllib.loads(Path(path).read_text())
    except FileNotFoundError:
        raise InputError("limits file not found", file=path) from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"not a valid TOML limits file ({exc})", file=path) from None
    return _parse(data, str(path), base)
