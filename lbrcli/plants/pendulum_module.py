"""The thesis's pendulum module (ch. 6) emulated on a pseudo-terminal: the simulated ball's planar angle θy and
its rate as AS5600 lines at ``rate_hz``, ``delay_ms`` (+ up to ``jitter_ms``) after the sample; the device path is reported as ``pendulum_path`` (plant info). Needs a
ball plant before it in ``SimConfig.plants``."""

from __future__ import annotations

from lbrcli.lab.pendulum_serial import LOCKSTEP_SETTLE_S

import math
from dataclasses import dataclass
from typing import Sequence

from trajectories.errors import OptionError, SettingError


@dataclass(frozen=True)
class PendulumModuleSpec:
    """The emulated module reading the ball plant; ``rate_hz`` [Hz] readings per second on the serial line."""

    rate_hz: float = 200.0
    delay_ms: float = 0.0  # [ms] sample → line on the serial port (radio + USB)
    jitter_ms: float = 0.0  # [ms] extra delay, uniform in [0, jitter]

    def validate(self) -> None:
        if not (math.isfinite(self.rate_hz) and 1.0 <= self.rate_hz <= 10000.0):
            raise OptionError(f"pendulum rate must be 1..10000 Hz, got {self.rate_hz:g}")
        for name, v in (("delay", self.delay_ms), ("jitter", self.jitter_ms)):
            if not (math.isfinite(v) and 0 <= v <= 500):
                raise OptionError(f"pendulum module {name} must be 0..500 ms, got {v:g}")

    def build(self, context) -> "PendulumModule":
        from .ball import Ball

        self.validate()
        ball = next((p for p in context.plants if isinstance(p, Ball)), None)
        if ball is None:
            raise SettingError(
                PendulumModuleSpec, "ball", "the pendulum module emulation needs a simulated ball before it"
            )
        module = PendulumModule(self, ball, context.period_s)
        module._emu.settle_s = LOCKSTEP_SETTLE_S if context.lockstep else 0.0
        return module


class PendulumModule:
    """Feeds the ball's θy and rate to a PendulumEmulator every cycle (it throttles to its rate)."""

    name = "pendulum_module"
    inputs: tuple[str, ...] = ()

    def __init__(self, spec: PendulumModuleSpec, ball, period_s: float) -> None:
        from lbrcli.lab.pendulum_serial import PendulumEmulator

        self._ball = ball
        self._h = period_s
        self._t = 0.0  # [s] simulated time
        self._emu = PendulumEmulator(rate_hz=spec.rate_hz, delay_s=spec.delay_ms * 1e-3, jitter_s=spec.jitter_ms * 1e-3)

    def step(self, t: float, tcp: Sequence[float]) -> tuple[()]:
        self._t += self._h
        theta, omega = self._ball.plane_angle_rate()
        self._emu.feed(self._t, theta, omega)
        return ()

    def info(self) -> dict:
        return {"pendulum_path": self._emu.path}

    def figures(self) -> dict:
        return {"lines_sent": self._emu.sent}

    def close(self) -> None:
        self._emu.close()
