"""Closed loop: damp the simulated ball's sway from its measured angle (the ``ball_theta_y`` IO value).

The pivot moves along base y by turning A1 (radius r); a pivot velocity v = k·θy makes its acceleration k·θ̇y,
which damps the pendulum θ̈ = −(g/l)·θ − a/l. The first 2 s swing the ball up a little with a (1 − cos) on A1.

    python examples/damp_ball.py [--gain 0.9] [--length 0.25]
"""

from __future__ import annotations

import math

from _connect import arguments, run

from lbrcli.fri import LBRClient


class BallDamper(LBRClient):
    def __init__(self, gain: float, radius: float, excite_s: float = 2.0, accel: float = 2.0):
        self.gain, self.radius = gain, radius  # [m/s/rad], [m]
        self.excite_s, self.accel = excite_s, accel  # [s], [rad/s²]
        self.t = self.omega = 0.0  # [s], A1 velocity [rad/s]
        self.q: list[float] | None = None
        self.sway: list[tuple[float, float]] = []  # (t [s], θy [rad])

    def command(self, state):
        dt = state.sample_time
        if self.q is None:
            self.q = list(state.ipo_joint_position)
            self.q1_0 = self.q[0]
        theta = state.analog_io("ball_theta_y")
        if self.t < self.excite_s:  # one period of the pendulum per second: 0.02·(1 − cos 2πt)
            self.q[0] = self.q1_0 + 0.02 * (1 - math.cos(2 * math.pi * self.t))
        else:
            want = self.gain * theta / self.radius
            self.omega += max(-self.accel * dt, min(self.accel * dt, want - self.omega))
            self.q[0] += self.omega * dt
        self.t += dt
        self.sway.append((self.t, theta))
        return self.q


def main(argv=None):
    p = arguments(__doc__.splitlines()[0], duration_s=8.0)
    p.add_argument("--gain", type=float, default=0.9, help="pivot speed per ball angle [m/s/rad] (0: open loop)")
    p.add_argument("--length", type=float, default=0.25, help="simulated string length [m]")
    args = p.parse_args(argv)
    from lbrcli.plants import default_plants

    client = BallDamper(args.gain, radius=0.576)
    result = run(client, args, plants=default_plants(args.length))
    late = [abs(th) for t, th in client.sway if t > client.t - 1.5]  # its last 1.5 s of commanding
    print(f"{result.outcome.value}: {result.detail}; sway in the last 1.5 s ≤ {math.degrees(max(late or [0])):.3f}°")
    return result, client


if __name__ == "__main__":
    main()
