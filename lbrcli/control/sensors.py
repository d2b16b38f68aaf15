"""Where the damper's sway readings come from, one class per kind of sensor a lab has: the controller's analog inputs
(:class:`IoSensor`, e.g. the simulator's ball or an external tracker wired to the controller), the pendulum module's
encoder on its serial port (:class:`ModuleSensor`, one axis), and a camera tracked live (:class:`CameraSensor`).
Each answers ``poll(state)`` once per FRI cycle with the readings that arrived since: (axis, angle [rad]) pairs, axis
0 the sway about base y (θx, the ball displaced along base x), 1 about base x (θy) — or (axis, angle, age [s]) from a
sensor that knows each reading's age."""

from __future__ import annotations

import time
from typing import Any, Iterator

import numpy as np


class IoSensor:
    """Both tilt angles [rad] from two analog inputs of every monitoring message."""

    axes = (0, 1)

    def __init__(self, names: tuple[str, str] = ("ball_theta_x", "ball_theta_y")) -> None:
        self.names = names
        self.interval_s: float | None = None  # every message

    def describe(self, axis: int) -> str:
        return f"the analog input {self.names[axis]}"

    def poll(self, state: Any) -> Iterator[tuple[int, float]]:
        yield 0, state.analog_io(self.names[0])
        yield 1, state.analog_io(self.names[1])


class ModuleSensor:
    """One tilt angle [rad] from the pendulum module's encoder (``reader``: a PendulumReader, set when the module is
    attached); the module's rod swings about its bearing axis, so it measures the sway about that axis only."""

    def __init__(self, axis: int = 1, rate_hz: float = 200.0) -> None:
        self.axes = (axis,)
        self.axis = axis
        self.reader: Any = None
        self.interval_s = 1.0 / rate_hz
        self._last: Any = None

    def describe(self, axis: int) -> str:
        return "the pendulum module's encoder"

    def poll(self, state: Any) -> Iterator[tuple[int, float]]:
        r = self.reader.latest if self.reader is not None else None
        if r is not None and r is not self._last:
            self._last = r
            yield self.axis, r.theta


class CameraSensor:
    """Tilt angles [rad] of the ball tracked live in a camera's frames (``tracker``: an object with ``latest()`` —
    the newest result or None — whose results carry ``theta_x`` / ``theta_y`` [rad] for the axes the camera sees; a
    NaN component is one this view does not give).

    Results that carry ``moment`` (the time the frame shows, ``time.monotonic()``) are handed on with their age
    (axis, angle, age [s]): a camera's frames come late by varying amounts (tracking time, transfer, a busy PC), and
    the damper's observer compares each with its estimate for that very moment; one older than ``max_age_s`` is
    dropped (counted ``late``). A tracker with ``observe(t, q)`` is given the robot's measured joint positions of
    every message (its pivot), one with ``freeze()`` is told when the rows start, one with ``failure(now)`` is asked
    every cycle whether it can still be trusted."""

    def __init__(self, tracker: Any, axes: tuple[int, ...], fps: float, max_age_s: float = 0.25) -> None:
        self.tracker = tracker
        self.axes = axes
        self.interval_s = 1.0 / fps
        self.max_age_s = max_age_s  # [s] the observer keeps its history this far back
        self._last: Any = None
        self._started = False
        self.ages: list[float] = []  # [s] age of each reading when handed on
        self.late = 0

    def describe(self, axis: int) -> str:
        return "the camera"

    def observe(self, state: Any) -> None:
        observe = getattr(self.tracker, "observe", None)
        if observe is not None:
            observe(time.monotonic(), state.measured_joint_position)

    def failure(self) -> str | None:
        check = getattr(self.tracker, "failure", None)
        return check(time.monotonic()) if check is not None else None

    def poll(self, state: Any) -> Iterator[tuple]:
        if not self._started:
            self._started = True
            freeze = getattr(self.tracker, "freeze", None)
            if freeze is not None:
                freeze()
        r = self.tracker.latest()
        if r is None or r is self._last or not getattr(r, "found", True):
            return
        self._last = r
        moment = getattr(r, "moment", None)
        age = None
        if moment is not None:
            age = time.monotonic() - moment
            if age > self.max_age_s:
                self.late += 1
                return
            self.ages.append(age)
        for axis in self.axes:
            value = r.theta_x if axis == 0 else r.theta_y
            if value is not None and value == value:  # NaN: this view does not give that component
                yield (axis, value) if age is None else (axis, value, age)

    def figures(self) -> dict:
        a = np.array(self.ages) * 1e3
        return {
            "camera_age_ms_p50": float(np.percentile(a, 50)) if len(a) else None,
            "camera_age_ms_p95": float(np.percentile(a, 95)) if len(a) else None,
            "camera_late_readings": self.late,
        }
