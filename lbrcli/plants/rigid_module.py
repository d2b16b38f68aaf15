"""The thesis's pendulum module (ch. 6) simulated as what it is: a rigid rod on a bearing on the flange, its AS5600
encoder read at ``rate_hz`` and delivered over the radio link and USB serial after ``delay_ms`` (± ``jitter_ms``)
as the receiving Arduino's lines (``count,omega``) on a pseudo-terminal (``pendulum_path`` in the plant info).

Geometry: the bearing axis is ``axis`` in the TCP frame (the module is coaxial with the flange: its z axis); the
encoder's zero is the direction in which the rod hangs at the start pose. The rod's dynamics are those of
:class:`planners.rigid_pendulum.RigidPendulum` in the plane normal to the axis, driven by gravity and the TCP's
acceleration (second differences of the measured TCP positions, as for the ball). The housing's own rotation about
the axis is not modelled (the encoder reads the rod against the housing as if the flange kept its orientation;
the feedback controllers do keep it).

Analog inputs (ground truth for the log, not for controllers): ``pendulum_phi`` [rad] (the rod's angle from the
encoder zero, wrapped to (−π, π]) and ``pendulum_omega`` [rad/s]. ``pushes`` knock the rod: (t [s], Δφ [rad]).
"""

from __future__ import annotations

from lbrcli.lab.pendulum_serial import LOCKSTEP_SETTLE_S

import math
import random
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from lbrcli.lab.pendulum_serial import COUNTS_PER_TURN as COUNTS
from lbrcli.lab.pendulum_serial import format_line
from planners.rigid_pendulum import RigidPendulum, rk4_step, wrap_angle
from trajectories.errors import OptionError, SettingError

from .tcp_acceleration import TcpAcceleration

MODULE_IO_NAMES = ("pendulum_phi", "pendulum_omega")  # [rad], [rad/s]


@dataclass(frozen=True)
class RigidModuleSpec:
    """The simulated module: the rod, its encoder's line rate [Hz], the link's delay and jitter [ms]."""

    pendulum: RigidPendulum = field(default_factory=RigidPendulum)
    rate_hz: float = 200.0  # [Hz] readings per second on the serial line
    delay_ms: float = 5.0  # [ms] encoder sample → line on the serial port (radio + serial)
    jitter_ms: float = 1.0  # [ms] extra delay, uniform in [0, jitter]
    phi0: float = 0.0  # [rad] the rod's angle at the start (0: hanging)
    omega0: float = 0.0  # [rad/s]
    pushes: tuple[tuple[float, float], ...] = ()  # (t [s] after the start, Δφ [rad]): knocks of the rod
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)  # bearing axis in the TCP frame
    zero_count: int = 0  # encoder count of the hanging rod
    seed: int = 0  # of the jitter
    noise_counts: int = 0  # the encoder's reading is off by up to ± this many counts (uniform, per reading)
    sign: int = 1  # −1: the encoder counts the other way (mounted reversed)

    def validate(self) -> None:
        try:
            self.pendulum.validate()
        except ValueError as exc:
            raise SettingError(RigidModuleSpec, "pendulum", str(exc)) from None
        if not (math.isfinite(self.rate_hz) and 1.0 <= self.rate_hz <= 10000.0):
            raise SettingError(RigidModuleSpec, "rate_hz", f"must be 1..10000 Hz, got {self.rate_hz:g}")
        if not (math.isfinite(self.delay_ms) and 0 <= self.delay_ms <= 500):
            raise SettingError(RigidModuleSpec, "delay_ms", f"must be 0..500 ms, got {self.delay_ms:g}")
        if not (math.isfinite(self.jitter_ms) and 0 <= self.jitter_ms <= 500):
            raise SettingError(RigidModuleSpec, "jitter_ms", f"must be 0..500 ms, got {self.jitter_ms:g}")
        if not (math.isfinite(self.phi0) and math.isfinite(self.omega0)):
            raise SettingError(RigidModuleSpec, "phi0", "the pendulum's start angle and rate must be finite")
        for t, d in self.pushes:
            if not (math.isfinite(t) and t >= 0 and math.isfinite(d)):
                raise SettingError(
                    RigidModuleSpec, "pushes", f"need a time >= 0 s and a finite angle, got {t:g} s, {d:g} rad"
                )
        if not 0 <= self.noise_counts <= 100:
            raise SettingError(RigidModuleSpec, "noise_counts", f"must be 0..100 counts, got {self.noise_counts}")
        if self.sign not in (1, -1):
            raise SettingError(RigidModuleSpec, "sign", f"must be 1 or -1, got {self.sign}")
        if not 0 <= self.zero_count < COUNTS:
            raise SettingError(
                RigidModuleSpec, "zero_count", f"must be an encoder count 0..4095, got {self.zero_count}"
            )

    def build(self, context) -> "RigidModule":
        self.validate()
        start = context.robot.fk(np.asarray(context.q0, dtype=float))
        module = RigidModule(self, context.period_s, start.translation.tolist(), start.rotation)
        module._emu.settle_s = LOCKSTEP_SETTLE_S if context.lockstep else 0.0
        return module


class RigidModule:
    """The rod's state φ [rad] (from the encoder zero), φ̇ [rad/s], and the serial line it feeds."""

    name = "pendulum_module"
    inputs = MODULE_IO_NAMES
    uses_rotation = True  # step(t, tcp, rotation)

    def __init__(self, spec: RigidModuleSpec, period_s: float, tcp0: Sequence[float], rotation0: np.ndarray) -> None:
        from lbrcli.lab.pendulum_serial import PendulumEmulator

        self.spec, self.p, self.h = spec, spec.pendulum, period_s
        n = np.asarray(spec.axis, dtype=float)
        n /= np.linalg.norm(n)
        n_world = rotation0 @ n
        down = np.array([0.0, 0.0, -1.0])
        u = down - n_world * float(n_world @ down)
        if np.linalg.norm(u) < 0.2:  # the axis is within ≈ 11° of vertical: the rod would not hang
            raise OptionError(
                "the pendulum module's axis is (nearly) vertical at the start pose: the rod cannot swing; "
                "start with the flange horizontal (e.g. the thesis start pose)"
            )
        u /= np.linalg.norm(u)
        self._n = n.tolist()  # axis, TCP frame
        self._u = (rotation0.T @ u).tolist()  # encoder zero, TCP frame
        self.phi, self.omega = spec.phi0, spec.omega0
        self._tcp_acc = TcpAcceleration(period_s, tcp0)
        self._a_prev = (0.0, 0.0)  # (a_h, a_v) at the previous sample [m/s²]
        self._t = 0.0
        self._pushes = sorted(spec.pushes)
        self._emu = PendulumEmulator(rate_hz=spec.rate_hz, zero_count=spec.zero_count, delay_s=spec.delay_ms * 1e-3,
                                     jitter_s=spec.jitter_ms * 1e-3, seed=spec.seed)  # fmt: skip
        self._sample_every = 1.0 / spec.rate_hz
        self._rng = random.Random(spec.seed + 1)
        self._next_sample = 0.0
        self._last_count: int | None = None
        self._last_sample_t = 0.0
        self.values = [self.phi, self.omega]
        self.max_abs_phi = abs(self.phi)

    def _in_plane(self, acc: Sequence[float], rot: np.ndarray) -> tuple[float, float]:
        """(a_h, a_v) of the pendulum's equation from the TCP acceleration [m/s²] and the TCP rotation."""
        n, u = self._n, self._u
        r = rot.tolist() if isinstance(rot, np.ndarray) else rot
        nw = [r[i][0] * n[0] + r[i][1] * n[1] + r[i][2] * n[2] for i in range(3)]
        uw = [r[i][0] * u[0] + r[i][1] * u[1] + r[i][2] * u[2] for i in range(3)]
        ew = [nw[1] * uw[2] - nw[2] * uw[1], nw[2] * uw[0] - nw[0] * uw[2], nw[0] * uw[1] - nw[1] * uw[0]]
        g_eff = (-acc[0], -acc[1], -9.81 - acc[2])  # gravity minus the pivot's acceleration
        g_u = g_eff[0] * uw[0] + g_eff[1] * uw[1] + g_eff[2] * uw[2]
        g_e = g_eff[0] * ew[0] + g_eff[1] * ew[1] + g_eff[2] * ew[2]
        return -g_e, g_u - 9.81

    def step(self, t: float, tcp: Sequence[float], rotation: np.ndarray) -> list[float]:
        self._t += self.h
        a = self._in_plane(self._tcp_acc.push(tcp), rotation)
        self.phi, self.omega = rk4_step(self.p, self.phi, self.omega, self._a_prev, a, self.h)
        self._a_prev = a
        while self._pushes and self._pushes[0][0] <= self._t:
            self.phi += self._pushes.pop(0)[1]
        self.phi = wrap_angle(self.phi)
        self._sample()
        self._emu.deliver(self._t)
        if abs(self.phi) > self.max_abs_phi:
            self.max_abs_phi = abs(self.phi)
        v = self.values
        v[0], v[1] = self.phi, self.omega
        return v

    def _sample(self) -> None:
        """The encoder read by the module's Arduino: the 12-bit count and the library's speed (count difference over
        the time between reads); queued for delivery after the link's delay."""
        t = self._t
        if t + 1e-9 < self._next_sample:
            return
        self._next_sample += self._sample_every * max(1, math.floor((t - self._next_sample) / self._sample_every) + 1)
        count = int(round(self.phi / (2 * math.pi) * COUNTS)) % COUNTS
        if self._last_count is None:
            omega = 0.0
        else:
            d = (count - self._last_count + COUNTS // 2) % COUNTS - COUNTS // 2
            omega = d * 2 * math.pi / COUNTS / max(t - self._last_sample_t, 1e-9)
        self._last_count, self._last_sample_t = count, t
        spec = self.spec
        read = spec.sign * self.phi
        if spec.noise_counts:
            read += self._rng.randint(-spec.noise_counts, spec.noise_counts) * 2 * math.pi / COUNTS
        self._emu.queue(t, format_line(read, spec.sign * omega, spec.zero_count))

    def info(self) -> dict:
        return {"pendulum_path": self._emu.path}

    def figures(self) -> dict:
        return {
            "lines_sent": self._emu.sent,
            "lines_dropped": self._emu.dropped,
            "max_abs_phi_deg": math.degrees(self.max_abs_phi),
            "final_phi_deg": math.degrees(self.phi),
        }

    def close(self) -> None:
        self._emu.close()
