"""FRI 2.7 transformation requests of the simulated controller: the frames the robot application asks the client for.

A Sunrise application that configures frames to be provided over FRI makes the controller list them in every
monitoring message (``requestedTransformations``: their names); the client answers each message with the values
(``commandData.commandedTransformations``: name, (tx, ty, tz [mm], qw, qx, qy, qz), the timestamp of the data). The
bank keeps, per requested frame, how many values arrived, the last one (in metres) and its timestamp; values for a
frame that was not requested, or that are malformed, are counted as refused and ignored.
"""

from __future__ import annotations

import math
from typing import Any

from ..cartesian import wire_to_pose

__all__ = ["TransformationBank"]


class TransformationBank:
    """Requested frames ``names`` in monitoring message ``mon`` and what the client sent for them."""

    def __init__(self, mon: Any, names: tuple[str, ...]) -> None:
        self.names = tuple(names)
        for name in self.names:
            mon.requestedTransformations.add().name = name
        self.received = {name: 0 for name in self.names}
        self.last: dict[str, list[float]] = {}  # name -> x, y, z [m], qw, qx, qy, qz
        self.stamp: dict[str, float] = {}  # name -> timestamp of the last value [s]
        self.refused = 0

    def apply(self, transformations: Any) -> None:
        """Take one command message's ``commandedTransformations``."""
        for tr in transformations:
            if tr.name not in self.received:
                self.refused += 1
                continue
            try:
                wire_to_pose(tr.element)  # validates: 7 finite values, a non-zero quaternion
            except ValueError:
                self.refused += 1
                continue
            e = tr.element
            self.received[tr.name] += 1
            self.last[tr.name] = [e[0] * 1e-3, e[1] * 1e-3, e[2] * 1e-3, e[3], e[4], e[5], e[6]]
            if tr.HasField("timestamp"):
                self.stamp[tr.name] = tr.timestamp.sec + tr.timestamp.nanosec * 1e-9

    def figures(self) -> dict:
        """Per requested frame: values received, the last value (x, y, z [m], qw, qx, qy, qz), its timestamp [s]."""
        return {name: {"received": self.received[name], "last": self.last.get(name),
                       "timestamp_s": self.stamp.get(name, math.nan) if name in self.stamp else None}
                for name in self.names}  # fmt: skip
