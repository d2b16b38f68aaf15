"""The damping client inside a session: the work of reading the sensor each cycle stays the same all session long
(the cause of `lbr control damp`'s sessions that all ended at 547 commanding cycles)."""

from __future__ import annotations

import numpy as np
import pytest

from planners.pendulum import natural_period
from tests.helpers.damp import DT, write_moves
from tests.helpers.tracing import line_events


@pytest.mark.heavy
def test_reading_the_sensor_costs_the_same_late_in_the_session_as_early(tmp_path):
    """Lines of Python per cycle's sensor reading (``DampingClient._read``: the readings, their checks, the
    observer), counted over a lock-step session: late in the rows as early. The checks once made a pass over their
    1 s window for every reading once it had filled — 0.7 ms per reading and axis at 1 ms, every cycle late from
    0.54 s on, so the simulator's quality rule ended every real-time session at the same cycle."""
    from lbrcli.console import Reporter
    from lbrcli.control import DampingClient
    from lbrcli.fri_runner import run_client
    from lbrcli.plants.ball import BallSpec
    from lbrcli.session_settings import SessionSettings, SimulatorSettings
    from planners.feedback.correction import correction_plan
    from trajectories.csvio import read_joint_csv
    from trajectories.limits import default_limits
    from trajectories.robot import Flange, Robot, RobotConfig

    path = tmp_path / "moves.csv"
    write_moves(path, ((np.array([0.12, 0, 0, 0, 0, 0, 0]), 1.2),))
    lim, traj = default_limits(), read_joint_csv(path, None)
    plan = correction_plan(Robot(RobotConfig(flange=Flange("touch-electric"))), traj.q, lim, DT)
    client = DampingClient(traj.q, lim, DT, 0.25, plan, damp_s=natural_period(0.25), sensor_delay_s=0.015)
    lines: list[int] = []  # per call of _read
    read = client._read

    def counted(state):
        lines.append(line_events(lambda: read(state)))

    client._read = counted
    sim = SimulatorSettings(period_ms=5, start=traj.q[0], ball=BallSpec(0.25, 0.0, io_delay_ms=10), max_runtime_s=60,
                            fast=True)  # fmt: skip
    result, _, _ = run_client(Reporter(True), client, SessionSettings(port=0, limits=lim), sim)
    assert client.trajectory_rows == len(traj.q) and client.sensor_fault is None, result.detail  # every row, damped
    per_s = int(round(1.0 / DT))
    assert len(lines) > 3 * per_s  # the session ran well past the checks' windows (1 s)
    early, late = np.median(lines[: per_s // 2]), np.array(lines[2 * per_s :])
    assert client.readings > 0 and early > 0
    assert late.max() < 3 * early  # (the pass over the window: 2,348 lines against 137 early, at this period)
