"""The ball on its string hanging from the TCP of the robot's measured pose — the project's string model
(``planners.string_model``: one-sided string, slack flight, re-tension jerk, and the cup on the flange when given).

Reported as analog inputs: ball_theta (tilt of the anchor→ball direction from hanging), ball_phi (its azimuth),
ball_theta_x and ball_theta_y (the planar angles atan2(d_x, −d_z), atan2(d_y, −d_z) of that direction d) [rad] —
the string angles while it is taut; ball_x, ball_y, ball_z, the ball centre in the base frame [m]; ball_phase
(0 taut, 1 slack, 2 in the cup). The value in the message of cycle k is the ball at cycle k−1: the TCP acceleration
at a sample is the second difference of the TCP positions around it (as ``planners.pendulum.SampledAcceleration``),
and the stepper (``planners.string_stepper``) advances the ball over the interval with it. ``io_delay_ms`` delays the
reported values further (a camera or encoder link), in whole cycles.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

from trajectories.errors import SettingError

from .tcp_acceleration import TcpAcceleration

BALL_IO_NAMES = ("ball_theta", "ball_phi", "ball_theta_x", "ball_theta_y", "ball_x", "ball_y", "ball_z", "ball_phase")
"""The simulated ball's analog inputs (and log columns): angles [rad], position [m] in the base frame, phase (taut,
slack, in the cup)."""
MAX_INTERVAL_S = 0.005  # [s] the stepper's longest interval (a longer controller period is split)
STRING_LENGTH_M = (0.01, 5.0)  # [m] the string lengths (anchor to ball centre) a ball may have: the one rule of the
# simulated ball's and the damper's string length options (0 where a command takes it for "no ball")


def string_length_problem(length: float) -> str | None:
    """Why ``length`` [m] cannot be a ball's string (outside :data:`STRING_LENGTH_M`), or None."""
    low, high = STRING_LENGTH_M
    if math.isfinite(length) and low <= length <= high:
        return None
    return f"the string length must be in [{low:g}, {high:g}] m, got {length:g}"


@dataclass(frozen=True)
class BallSpec:
    """A ball on a string of ``length`` [m] with viscous ``damping`` [1/s]; ``model`` (a
    ``planners.string_model.StringModel`` of that length) for another ball or the cup; picklable."""

    length: float
    damping: float = 0.0
    io_delay_ms: float = 0.0  # [ms] the IO values show the ball this much later (rounded to whole cycles)
    model: object = None  # planners.string_model.StringModel; None: the default ball, no cup

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        """SettingError naming the field (``BallSpec.length`` …) that is out of range."""
        problem = string_length_problem(self.length)
        if problem:
            raise SettingError(BallSpec, "length", problem)
        if not (math.isfinite(self.damping) and self.damping >= 0):
            raise SettingError(BallSpec, "damping", f"must be >= 0 1/s, got {self.damping:g}")
        if not (math.isfinite(self.io_delay_ms) and 0 <= self.io_delay_ms <= 1000):
            raise SettingError(BallSpec, "io_delay_ms", f"must be 0..1000 ms, got {self.io_delay_ms:g}")
        try:
            self.string_model().validate()
        except ValueError as exc:
            raise SettingError(BallSpec, "model", str(exc)) from None

    def string_model(self):
        """The string model this ball follows (length and damping from the spec)."""
        from dataclasses import replace

        from planners.string_model import StringModel

        base = self.model if self.model is not None else StringModel(self.length, cup=None)
        return replace(base, length=self.length, damping=self.damping)

    def build(self, context) -> "Ball":  # (checked when it was made)
        pose = context.robot.fk(context.q0)
        return Ball(self, context.period_s, pose.translation.tolist(), pose.rotation)


class Ball:
    """The ball's stepper and what it reports."""

    name = "ball"
    inputs = BALL_IO_NAMES
    uses_rotation = True  # the cup turns with the flange

    def __init__(self, spec: BallSpec, period_s: float, tcp0: Sequence[float], rotation0) -> None:
        from planners.string_stepper import StringStepper

        self.model = spec.string_model()
        self.length, self.damping, self.h = self.model.length, self.model.damping, period_s
        self._sub = max(1, math.ceil(period_s / MAX_INTERVAL_S - 1e-9))
        self._axis_f = self.model.axis_flange
        p0 = tuple(float(x) for x in tcp0)
        self.stepper = StringStepper(self.model, p0, self._axis(rotation0))
        self.stepper.t = (
            -2.0 * period_s
        )  # the first cycle advances the ball over [−2h, −h]: event times on the TCP's clock
        self._tcp_acc = TcpAcceleration(period_s, tcp0)
        self._acc_prev = (0.0, 0.0, 0.0)  # TCP acceleration at the sample before [m/s²]
        self._p_prev = p0  # TCP position at the sample before [m]
        self._v_prev = (0.0, 0.0, 0.0)  # its velocity, integrated from the accelerations [m/s]
        self._axis_prev = self._axis(rotation0)
        self.values = [0.0, 0.0, 0.0, 0.0, *self.stepper.b, 0.0]  # BALL_IO_NAMES, now
        self.max_theta = 0.0  # [rad]
        self.cycles = 0
        lag = int(round(spec.io_delay_ms * 1e-3 / period_s))
        self._late = [list(self.values) for _ in range(lag + 1)] if lag else None  # ring of the last lag + 1
        self._late_at = 0

    def _axis(self, rotation) -> tuple[float, float, float]:
        a = self._axis_f
        r = rotation
        return (
            r[0][0] * a[0] + r[0][1] * a[1] + r[0][2] * a[2],
            r[1][0] * a[0] + r[1][1] * a[1] + r[1][2] * a[2],
            r[2][0] * a[0] + r[2][1] * a[1] + r[2][2] * a[2],
        )

    def step(self, t: float, tcp: Sequence[float], rotation=None) -> list[float]:
        acc = self._tcp_acc.push(tcp)  # at the previous sample [m/s²]
        a0, p0, v0 = self._acc_prev, self._p_prev, self._v_prev
        st = self.stepper
        if self._sub == 1:
            st.advance(self.h, p0, v0, a0, acc, self._axis_prev)
        else:  # split a long period; the acceleration is linear across it
            from planners.string_stepper import Interval

            whole = Interval(p0, v0, a0, acc, self.h)
            hs = self.h / self._sub
            for i in range(self._sub):
                pi, vi, ai = whole.at(i * hs)
                st.advance(hs, pi, vi, ai, whole.at((i + 1) * hs)[2], self._axis_prev)
        self._v_prev = tuple(v0[k] + 0.5 * self.h * (a0[k] + acc[k]) for k in range(3))
        self._acc_prev = acc
        self._p_prev = self._tcp_acc.previous
        if rotation is not None:
            self._axis_prev = self._axis(rotation)
        dx, dy, dz = st.direction()
        theta = math.acos(max(-1.0, min(1.0, -dz)))
        v = self.values
        v[0], v[1], v[2], v[3] = theta, math.atan2(dy, dx), math.atan2(dx, -dz), math.atan2(dy, -dz)
        v[4], v[5], v[6] = st.b
        v[7] = float(st.phase_code)
        self.cycles += 1
        if theta > self.max_theta:
            self.max_theta = theta
        late = self._late
        if late is None:
            return v
        i = self._late_at
        late[i][:] = v
        self._late_at = i = (i + 1) % len(late)
        return late[i]  # the oldest: lag cycles ago

    def plane_angle_rate(self) -> tuple[float, float]:
        """θy = atan2(d_y, −d_z) [rad] and its rate [rad/s] (what an encoder on a y–z plane pendulum reads)."""
        _, sy, sz = self.stepper.direction()
        _, vy, vz = self.stepper.direction_rate()
        return self.values[3], (sy * vz - sz * vy) / (sy * sy + sz * sz)

    def info(self) -> dict:
        return {}

    def figures(self) -> dict:
        out = {"max_ball_theta": self.max_theta}
        if self.model.cup is not None:
            from planners.catch_outcome import outcome

            o = outcome(self.stepper.events, self.stepper.resting, self.stepper.inside)
            out["cup"] = {
                "caught": o.caught,
                "entered_s": o.t_entry,
                "rest_s": o.t_rest,
                "released_s": o.t_release,
                "entry_margin_m": o.margin,
                "relative_entry_speed_m_s": o.relative_speed,
                "failure": o.failure,
                "in_cup_at_end": self.stepper.inside,
            }
        return out

    def close(self) -> None:
        pass
