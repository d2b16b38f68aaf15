"""KUKA's LBRWrenchSineOverlay on lbrcli.fri: WRENCH mode, the ipo position plus a force sine along x and y.

    python examples/wrench_sine_overlay.py [--robot IP]      # the robot application must use WRENCH mode

Unlike KUKA's client, which answers until IDLE, the run ends when the session leaves COMMANDING_ACTIVE
(lbrcli.fri's robot-side end) or after --duration. KUKA's default is 0.25 Hz on both axes; 0.5 and 1 Hz here
show whole periods in a short run.
"""

from __future__ import annotations

import math

from _connect import arguments, run

from lbrcli.fri import ClientCommandMode, LBRClient, SessionState


class WrenchSineOverlay(LBRClient):
    def __init__(self, freq_hz=(0.5, 1.0), amplitude=(5.0, 5.0)):  # [Hz], [N]
        self.freq_hz, self.amplitude = freq_hz, amplitude
        self.phi, self.step = [0.0, 0.0], [0.0, 0.0]
        self.wrench = [0.0] * 6
        self.measured: list[tuple[float, ...]] = []

    def on_state_change(self, old: SessionState, new: SessionState) -> None:
        if new is SessionState.MONITORING_READY:
            self.wrench, self.phi = [0.0] * 6, [0.0, 0.0]
            self.step = [2 * math.pi * f * self.robot_state.sample_time for f in self.freq_hz]

    def wait_for_command(self, state) -> None:
        super().wait_for_command(state)
        if state.client_command_mode is ClientCommandMode.WRENCH:
            self.robot_command.set_wrench(self.wrench)

    def command(self, state):
        self.hold_ipo(state)
        if state.client_command_mode is ClientCommandMode.WRENCH:
            for i in (0, 1):
                self.wrench[i] = self.amplitude[i] * math.sin(self.phi[i])
                self.phi[i] = (self.phi[i] + self.step[i]) % (2 * math.pi)
            self.robot_command.set_wrench(self.wrench)
        self.measured.append(state.measured_joint_position)


def main(argv=None):
    args = arguments(__doc__.splitlines()[0]).parse_args(argv)
    client = WrenchSineOverlay()
    result = run(client, args, command_mode="wrench")
    print(f"{result.outcome.value}: {result.detail}")
    return result, client


if __name__ == "__main__":
    main()
