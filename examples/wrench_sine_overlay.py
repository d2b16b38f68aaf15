"""KUKA's LBRWrenchSineOverlay on lbrcli.fri: WRENCH mode, the ipo position plus a force sine along x and y.

    python examples/wrench_sine_overlay.py [--robot IP]      # the robot application must use WRENCH mode

Unlike KUKA's client, which answers until IDLE, the run ends when the session leaves COMMANDING_ACTIVE
(lbrcli.fri's robot-side end) or after --duration. KUKA's default is 0.25 Hz; 0.5 and 1 Hz show whole periods.
Each reply is prepared after the last (prepare_command, prepare_overlay) and goes out as soon as a message is checked.
"""

from __future__ import annotations

import math

from _connect import arguments, run

from lbrcli.fri import ClientCommandMode, LBRClient, SessionState


class WrenchSineOverlay(LBRClient):
    def __init__(self, freq_hz=(0.5, 1.0), amplitude=(5.0, 5.0)):  # [Hz], [N]
        self.freq_hz, self.amplitude = freq_hz, amplitude
        self.phi, self.step, self.wrench = [0.0, 0.0], [0.0, 0.0], [0.0] * 6
        self.next_q, self.measured = None, []  # the command prepared after the last reply; measured positions

    def on_state_change(self, old: SessionState, new: SessionState) -> None:
        if new is SessionState.MONITORING_READY:
            self.wrench, self.phi, self.next_q = [0.0] * 6, [0.0, 0.0], None
            self.step = [2 * math.pi * f * self.robot_state.sample_time for f in self.freq_hz]

    def _next(self, ipo) -> list[float]:  # a command: the ipo position, the sines' next forces along x and y
        self.wrench = [a * math.sin(p) for a, p in zip(self.amplitude, self.phi)] + [0.0] * 4
        self.phi = [(p + s) % (2 * math.pi) for p, s in zip(self.phi, self.step)]
        return list(ipo)

    def command(self, state):
        if state.client_command_mode is not ClientCommandMode.WRENCH:
            return super().command(state)
        q, self.next_q = self.next_q or self._next(state.ipo_joint_position), None
        self.robot_command.set_wrench(self.wrench)
        self.measured.append(state.measured_joint_position)
        return q

    def prepare_command(self):  # the next command from this message's ipo (held still): its reply goes out at once
        if self.robot_state.client_command_mode is ClientCommandMode.WRENCH:
            self.next_q = self._next(self.robot_state.ipo_joint_position)
            return self.next_q

    def prepare_overlay(self):  # ... with the wrench that goes with it
        return self.wrench


def main(argv=None):
    client = WrenchSineOverlay()
    result = run(client, arguments(__doc__.splitlines()[0]).parse_args(argv), command_mode="wrench")
    print(f"{result.outcome.value}: {result.detail}")
    return result, client


if __name__ == "__main__":
    main()
