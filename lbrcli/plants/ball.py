"""The ball on its string, hanging from the TCP of the robot's measured pose (planners.pendulum model).

Reported as analog inputs [rad]: ball_theta (tilt from the vertical), ball_phi (azimuth), ball_theta_x and
ball_theta_y (the planar angles atan2(s_x, −s_z), atan2(s_y, −s_z) of the string direction s). The value in the
message of cycle k is the ball at cycle k−1: the TCP acceleration at a sample is the second difference of the
TCP positions around it (as ``planners.pendulum.SampledAcceleration``), integrated with one RK4 step per cycle.
``io_delay_ms`` delays the reported angles further (a camera or encoder link), in whole cycles.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

from trajectories.errors import OptionError

from .tcp_acceleration import TcpAcceleration

BALL_IO_NAMES = ("ball_theta", "ball_phi", "ball_theta_x", "ball_theta_y")  # [rad], analog inputs


@dataclass(frozen=True)
class BallSpec:
    """A ball on a string of ``length`` [m] with viscous ``damping`` [1/s]; picklable."""

    length: float
    damping: float = 0.0
    io_delay_ms: float = 0.0  # [ms] the IO values show the ball this much later (rounded to whole cycles)

    def validate(self) -> None:
        if not (math.isfinite(self.length) and self.length > 0):
            raise OptionError(f"--length: string length must be > 0 m, got {self.length:g}")
        if not (math.isfinite(self.damping) and self.damping >= 0):
            raise OptionError(f"--damping: must be >= 0 1/s, got {self.damping:g}")
        if not (math.isfinite(self.io_delay_ms) and 0 <= self.io_delay_ms <= 1000):
            raise OptionError(f"--sim-delay: must be 0..1000 ms, got {self.io_delay_ms:g}")

    def build(self, context) -> "Ball":
        self.validate()
        return Ball(self, context.period_s, context.robot.fk(context.q0).translation.tolist())


class Ball:
    """The ball's state: string direction s (unit vector) and its rate ṡ [1/s]."""

    name = "ball"
    inputs = BALL_IO_NAMES

    def __init__(self, spec: BallSpec, period_s: float, tcp0: Sequence[float]) -> None:
        from planners.pendulum import rk4_step_floats

        self._rk4 = rk4_step_floats
        self.length, self.damping, self.h = spec.length, spec.damping, period_s
        self._tcp_acc = TcpAcceleration(period_s, tcp0)
        self._acc_prev = (0.0, 0.0, 0.0)  # TCP acceleration at the sample before [m/s²]
        self.s = (0.0, 0.0, -1.0)  # string direction (hanging)
        self.sdot = (0.0, 0.0, 0.0)  # [1/s]
        self.angles = [0.0, 0.0, 0.0, 0.0]  # BALL_IO_NAMES [rad], now
        self.max_theta = 0.0  # [rad]
        lag = int(round(spec.io_delay_ms * 1e-3 / period_s))
        self._late = [[0.0, 0.0, 0.0, 0.0] for _ in range(lag + 1)] if lag else None  # ring of the last lag + 1
        self._late_at = 0

    def step(self, t: float, tcp: Sequence[float]) -> list[float]:
        acc = self._tcp_acc.push(tcp)  # at the previous sample [m/s²]
        self.s, self.sdot = self._rk4(self.s, self.sdot, self._acc_prev, acc, self.h, self.length, self.damping)
        self._acc_prev = acc
        sx, sy, sz = self.s
        theta = math.acos(max(-1.0, min(1.0, -sz)))
        a = self.angles
        a[0], a[1], a[2], a[3] = theta, math.atan2(sy, sx), math.atan2(sx, -sz), math.atan2(sy, -sz)
        if theta > self.max_theta:
            self.max_theta = theta
        late = self._late
        if late is None:
            return a
        i = self._late_at
        late[i][:] = a
        self._late_at = i = (i + 1) % len(late)
        return late[i]  # the oldest: lag cycles ago

    def plane_angle_rate(self) -> tuple[float, float]:
        """θy = atan2(s_y, −s_z) [rad] and its rate [rad/s] (what an encoder on a y–z plane pendulum reads)."""
        sx, sy, sz = self.s
        vx, vy, vz = self.sdot
        return self.angles[3], (sy * vz - sz * vy) / (sy * sy + sz * sz)

    def info(self) -> dict:
        return {}

    def figures(self) -> dict:
        return {"max_ball_theta": self.max_theta}

    def close(self) -> None:
        pass
