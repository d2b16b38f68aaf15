"""KUKA's LBRTorqueSineOverlay on lbrcli.fri: TORQUE mode, the ipo position plus a torque sine on joints.

    python examples/torque_sine_overlay.py [--robot IP]      # the robot application must use TORQUE mode

Unlike KUKA's client, which answers until IDLE, the run ends when the session leaves COMMANDING_ACTIVE
(lbrcli.fri's robot-side end) or after --duration. KUKA's defaults are 0.25 Hz and 15 Nm; 1 Hz and 5 Nm show
whole periods. Each reply is prepared after the last (prepare_command, prepare_overlay): it goes out at once.
"""

from __future__ import annotations

import math

from _connect import arguments, run

from lbrcli.fri import ClientCommandMode, LBRClient, SessionState


class TorqueSineOverlay(LBRClient):
    def __init__(self, joint_mask: int = 0x08, freq_hz: float = 1.0, amplitude: float = 5.0):  # [Hz], [Nm]
        self.mask, self.freq_hz, self.amplitude = joint_mask, freq_hz, amplitude
        self.phi, self.step, self.torques = 0.0, 0.0, [0.0] * 7
        self.next_q, self.measured = None, []  # the command prepared after the last reply; measured positions

    def on_state_change(self, old: SessionState, new: SessionState) -> None:
        if new is SessionState.MONITORING_READY:
            self.torques, self.phi, self.next_q = [0.0] * 7, 0.0, None
            self.step = 2 * math.pi * self.freq_hz * self.robot_state.sample_time

    def _next(self, ipo) -> list[float]:  # a command: the ipo position, the sine's next torque on the masked joints
        self.torques = [self.amplitude * math.sin(self.phi) if self.mask & (1 << j) else 0.0 for j in range(7)]
        self.phi = (self.phi + self.step) % (2 * math.pi)
        return list(ipo)

    def command(self, state):
        if state.client_command_mode is not ClientCommandMode.TORQUE:
            return super().command(state)
        q, self.next_q = self.next_q or self._next(state.ipo_joint_position), None
        self.robot_command.set_torque(self.torques)
        self.measured.append(state.measured_joint_position)
        return q

    def prepare_command(self):  # the next command from this message's ipo (held still): its reply goes out at once
        if self.robot_state.client_command_mode is ClientCommandMode.TORQUE:
            self.next_q = self._next(self.robot_state.ipo_joint_position)
            return self.next_q

    def prepare_overlay(self):  # ... with the torque that goes with it
        return self.torques


def main(argv=None):
    client = TorqueSineOverlay()
    result = run(client, arguments(__doc__.splitlines()[0]).parse_args(argv), command_mode="torque")
    print(f"{result.outcome.value}: {result.detail}")
    return result, client


if __name__ == "__main__":
    main()
