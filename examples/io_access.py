"""KUKA's IOAccess on lbrcli.fri: while the clock input is on, write the controller's seconds to two outputs.

    python examples/io_access.py [--robot 192.170.10.2] [--duration 5]

The robot application needs the FRI IO channels FRI.In_Bool_Clock_Enabled (boolean in),
FRI.Out_Integer_Seconds (digital out) and FRI.Out_Analog_Deci_Seconds (analog out); the robot is held still.
Unlike KUKA's client, which answers until IDLE, the run ends when the session leaves COMMANDING_ACTIVE (if the
application has an overlay: lbrcli.fri's robot-side end) or after --duration.
"""

from __future__ import annotations

from _connect import arguments, run

from lbrcli.fri import LBRClient
from lbrcli.fri.sim import IO_PRESETS


class IOAccess(LBRClient):
    def __init__(self) -> None:
        self.written: list[tuple[int, float]] = []  # (digital, analog) per answered cycle
        self.read_back: list[tuple[int, float]] = []  # the outputs as the controller reports them

    def _clock(self, state) -> None:
        self.read_back.append((state.digital_io("FRI.Out_Integer_Seconds"),
                               state.analog_io("FRI.Out_Analog_Deci_Seconds")))  # fmt: skip
        if state.boolean_io("FRI.In_Bool_Clock_Enabled"):
            seconds = state.timestamp_sec
            digital, analog = seconds % 64, (state.timestamp_nanosec // 100_000_000) * 0.1  # [s], [s]
            self.robot_command.set_digital_io("FRI.Out_Integer_Seconds", digital)
            self.robot_command.set_analog_io("FRI.Out_Analog_Deci_Seconds", analog)
            self.written.append((digital, analog))

    def monitor(self, state) -> None:
        self._clock(state)

    def wait_for_command(self, state) -> None:
        super().wait_for_command(state)
        self._clock(state)

    def command(self, state):
        self._clock(state)
        return super().command(state)  # hold the ipo position


def main(argv=None):
    args = arguments(__doc__.splitlines()[0]).parse_args(argv)
    client = IOAccess()
    result = run(client, args, io=IO_PRESETS["kuka-ioaccess"])
    print(f"{result.outcome.value}: {result.detail}; {len(client.written)} IO writes")
    return result, client


if __name__ == "__main__":
    main()
