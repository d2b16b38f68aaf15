"""Where the damper's sway readings come from, one class per kind of sensor a lab has: the controller's analog inputs
(:class:`IoSensor`, e.g. the simulator's ball or an external tracker wired to the controller), the pendulum module's
encoder on its serial port (:class:`ModuleSensor`, one axis), and a camera tracked live (:class:`CameraSensor`).
Each answers ``poll(state)`` once per FRI cycle with the readings that arrived since: (axis, angle [rad]) pairs, axis
0 the sway about base y (θx, the ball displaced along base x), 1 about base x (θy)."""

from __future__ import annotations

from typing import Any, Iterator


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
    the newest result or None — whose results carry ``theta_x`` / ``theta_y`` [rad] for the axes the camera sees)."""

    def __init__(self, tracker: Any, axes: tuple[int, ...], fps: float) -> None:
        self.tracker = tracker
        self.axes = axes
        self.interval_s = 1.0 / fps
        self._last: Any = None

    def describe(self, axis: int) -> str:
        return "the camera"

    def poll(self, state: Any) -> Iterator[tuple[int, float]]:
        r = self.tracker.latest()
        if r is None or r is self._last or not getattr(r, "found", True):
            return
        self._last = r
        for axis in self.axes:
            value = r.theta_x if axis == 0 else r.theta_y
            if value is not None:
                yield axis, value
