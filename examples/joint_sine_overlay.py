"""KUKA's LBRJointSineOverlay on lbrcli.fri: command = ipo + A·sin(2π·f·t) on the masked joints, low-pass filtered.

    python examples/joint_sine_overlay.py [--robot 192.170.10.2] [--duration 10] [--freq 0.25] [--amplitude 0.04]

Defaults are KUKA's: joint mask 0x8 (A4), 0.25 Hz, 0.04 rad, filter coefficient 0.99. Unlike KUKA's client, which
answers until IDLE, the run ends when the session leaves COMMANDING_ACTIVE (lbrcli.fri's robot-side end).
"""

from __future__ import annotations

import math

from _connect import arguments, run

from lbrcli.fri import LBRClient, SessionState


class JointSineOverlay(LBRClient):
    def __init__(self, joint_mask: int = 0x8, freq_hz: float = 0.25, amplitude: float = 0.04, filter_coeff=0.99):
        self.mask, self.freq_hz, self.amplitude = joint_mask, freq_hz, amplitude  # bit j = A(j+1), [Hz], [rad]
        self.filter_coeff = filter_coeff  # 0 (off) to 1
        self.offset = self.phi = self.step = 0.0  # [rad], [rad], [rad per cycle]
        self.next_q: list[float] | None = None  # prepared after the last reply
        self.history: list[tuple[tuple[float, ...], tuple[float, ...]]] = []  # (measured, commanded) per cycle

    def on_state_change(self, old: SessionState, new: SessionState) -> None:
        if new is SessionState.MONITORING_READY:
            self.offset, self.phi, self.next_q = 0.0, 0.0, None
            self.step = 2 * math.pi * self.freq_hz * self.robot_state.sample_time

    def _sine(self, ipo) -> list[float]:
        self.offset = self.offset * self.filter_coeff + self.amplitude * math.sin(self.phi) * (1 - self.filter_coeff)
        self.phi = (self.phi + self.step) % (2 * math.pi)
        return [x + self.offset if self.mask & (1 << j) else x for j, x in enumerate(ipo)]

    def command(self, state):
        q, self.next_q = self.next_q or self._sine(state.ipo_joint_position), None
        self.history.append((state.measured_joint_position, tuple(q)))
        return q

    def prepare_command(self):  # the next command from this message's ipo (held still): its reply goes out at once
        self.next_q = self._sine(self.robot_state.ipo_joint_position)
        return self.next_q


def main(argv=None):
    p = arguments(__doc__.splitlines()[0], duration_s=10.0)
    p.add_argument("--joint-mask", type=lambda x: int(x, 0), default=0x8, help="joints overlaid, bit j = A(j+1)")
    p.add_argument("--freq", type=float, default=0.25, help="sine frequency [Hz]")
    p.add_argument("--amplitude", type=float, default=0.04, help="sine amplitude [rad]")
    p.add_argument("--filter-coeff", type=float, default=0.99, help="low-pass coefficient, 0 (off) to 1")
    args = p.parse_args(argv)
    client = JointSineOverlay(args.joint_mask, args.freq, args.amplitude, args.filter_coeff)
    result = run(client, args)
    print(f"{result.outcome.value}: {result.detail}; {len(client.history)} commands")
    return result, client


if __name__ == "__main__":
    main()
