"""KUKA's LBRJointSineOverlay on lbrcli.fri: command = ipo + A·sin(2π·f·t) on one joint, low-pass filtered.

    python examples/joint_sine_overlay.py [--robot 192.170.10.2] [--duration 10]
"""

from __future__ import annotations

import math

from _connect import arguments, run

from lbrcli.fri import LBRClient, SessionState


class JointSineOverlay(LBRClient):
    def __init__(self, joint: int = 3, freq_hz: float = 0.25, amplitude: float = 0.04, filter_coeff: float = 0.99):
        self.joint, self.freq_hz, self.amplitude, self.filter_coeff = joint, freq_hz, amplitude, filter_coeff
        self.offset = self.phi = self.step = 0.0  # [rad], [rad], [rad per cycle]
        self.history: list[tuple[tuple[float, ...], tuple[float, ...]]] = []  # (measured, commanded) per cycle

    def on_state_change(self, old: SessionState, new: SessionState) -> None:
        if new is SessionState.MONITORING_READY:
            self.offset = self.phi = 0.0
            self.step = 2 * math.pi * self.freq_hz * self.robot_state.sample_time

    def command(self, state):
        self.offset = self.offset * self.filter_coeff + self.amplitude * math.sin(self.phi) * (1 - self.filter_coeff)
        self.phi = (self.phi + self.step) % (2 * math.pi)
        q = list(state.ipo_joint_position)
        q[self.joint] += self.offset
        self.history.append((state.measured_joint_position, tuple(q)))
        return q


def main(argv=None):
    args = arguments(__doc__.splitlines()[0], duration_s=10.0).parse_args(argv)
    client = JointSineOverlay(freq_hz=1.0)
    result = run(client, args)
    print(f"{result.outcome.value}: {result.detail}; {len(client.history)} commands")
    return result, client


if __name__ == "__main__":
    main()
