"""KUKA's LBRTorqueSineOverlay on lbrcli.fri: TORQUE mode, the ipo position plus a torque sine on joints.

    python examples/torque_sine_overlay.py [--robot IP]      # the robot application must use TORQUE mode

Unlike KUKA's client, which answers until IDLE, the run ends when the session leaves COMMANDING_ACTIVE
(lbrcli.fri's robot-side end) or after --duration. KUKA's defaults are 0.25 Hz and 15 Nm; 1 Hz and 5 Nm here
show whole periods in a short run.
"""

from __future__ import annotations

import math

from _connect import arguments, run

from lbrcli.fri import ClientCommandMode, LBRClient, SessionState


class TorqueSineOverlay(LBRClient):
    def __init__(self, joint_mask: int = 0x08, freq_hz: float = 1.0, amplitude: float = 5.0):  # [Hz], [Nm]
        self.mask, self.freq_hz, self.amplitude = joint_mask, freq_hz, amplitude
        self.phi = self.step = 0.0
        self.torques = [0.0] * 7
        self.measured: list[tuple[float, ...]] = []

    def on_state_change(self, old: SessionState, new: SessionState) -> None:
        if new is SessionState.MONITORING_READY:
            self.torques, self.phi = [0.0] * 7, 0.0
            self.step = 2 * math.pi * self.freq_hz * self.robot_state.sample_time

    def wait_for_command(self, state) -> None:
        super().wait_for_command(state)
        if state.client_command_mode is ClientCommandMode.TORQUE:
            self.robot_command.set_torque(self.torques)

    def command(self, state):
        self.hold_ipo(state)
        if state.client_command_mode is ClientCommandMode.TORQUE:
            offset = self.amplitude * math.sin(self.phi)
            self.phi = (self.phi + self.step) % (2 * math.pi)
            self.torques = [offset if self.mask & (1 << j) else 0.0 for j in range(7)]
            self.robot_command.set_torque(self.torques)
        self.measured.append(state.measured_joint_position)


def main(argv=None):
    args = arguments(__doc__.splitlines()[0]).parse_args(argv)
    client = TorqueSineOverlay()
    result = run(client, args, command_mode="torque")
    print(f"{result.outcome.value}: {result.detail}")
    return result, client


if __name__ == "__main__":
    main()
