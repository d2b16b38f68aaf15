"""Colour classes as bands in OpenCV's HSV space (H 0–179, S and V 0–255).

Red wraps around H = 0, so it is two bands (≈ 0–10 and 170–179). A colour is given by name (red, green,
blue, yellow, orange, magenta, cyan) or as a hue range ``H1-H2`` in OpenCV units (``170-10`` wraps).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trajectories.errors import SettingError

_MIN_S = 100  # minimum saturation of a coloured marker (grey, white, skin and wood stay below)
_MIN_V = 50  # minimum value (brightness) — darker pixels have unreliable hue


@dataclass(frozen=True)
class HsvBand:
    """One inclusive box in HSV: lower and upper (h, s, v)."""

    lower: tuple[int, int, int]
    upper: tuple[int, int, int]


@dataclass(frozen=True)
class ColorSpec:
    """A named colour: the union of its HSV bands."""

    name: str
    bands: tuple[HsvBand, ...]


def _hue_bands(h1: int, h2: int, s: int = _MIN_S, v: int = _MIN_V) -> tuple[HsvBand, ...]:
    if h1 <= h2:
        return (HsvBand((h1, s, v), (h2, 255, 255)),)
    return (HsvBand((0, s, v), (h2, 255, 255)), HsvBand((h1, s, v), (179, 255, 255)))


COLORS: dict[str, ColorSpec] = {
    "red": ColorSpec("red", _hue_bands(170, 10)),
    "orange": ColorSpec("orange", _hue_bands(11, 22)),
    "yellow": ColorSpec("yellow", _hue_bands(23, 35)),
    "green": ColorSpec("green", _hue_bands(40, 85, s=80)),
    "cyan": ColorSpec("cyan", _hue_bands(86, 99, s=80)),
    "blue": ColorSpec("blue", _hue_bands(100, 130, s=80)),
    "magenta": ColorSpec("magenta", _hue_bands(140, 169)),
}


def color_spec(text: str, setting: str = "ColorSpec.name") -> ColorSpec:
    """A colour by name (see COLORS) or as an OpenCV hue range 'H1-H2' (0–179; H1 > H2 wraps through 0). An unknown
    one is a SettingError naming ``setting`` ("Class.field" of what the text was given for; the CLI names its option).
    """
    key = str(text).strip().lower()
    if key in COLORS:
        return COLORS[key]
    parts = key.split("-")
    if len(parts) == 2:
        try:
            h1, h2 = int(parts[0]), int(parts[1])
        except ValueError:
            h1 = h2 = -1
        if 0 <= h1 <= 179 and 0 <= h2 <= 179:
            return ColorSpec(key, _hue_bands(h1, h2))
    names = ", ".join(COLORS)
    owner, _, name = setting.rpartition(".")
    raise SettingError(owner, name, f"unknown colour {text!r} (one of {names}, or a hue range H1-H2 in 0–179)")


def color_mask(hsv: np.ndarray, spec: ColorSpec) -> np.ndarray:
    """uint8 mask (255 where the pixel is of the colour) of an HSV image."""
    import cv2

    mask = None
    for band in spec.bands:
        m = cv2.inRange(hsv, band.lower, band.upper)
        mask = m if mask is None else cv2.bitwise_or(mask, m)
    return mask


def with_min_saturation(spec: ColorSpec, min_s: int, min_v: int | None = None) -> ColorSpec:
    """The same hue bands with another minimum saturation (and value): for a ball smeared by motion blur,
    whose colour is mixed with the background's and so less saturated."""
    bands = tuple(
        HsvBand((b.lower[0], int(min_s), int(b.lower[2] if min_v is None else min_v)), b.upper) for b in spec.bands
    )
    return ColorSpec(f"{spec.name}@S{int(min_s)}", bands)
