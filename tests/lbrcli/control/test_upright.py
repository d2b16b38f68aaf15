"""The upright client's start check: a robot away from the rail's start is refused with a message that names the
setting (``UprightClient.move_to_start``), which `lbr control upright` turns into its flag; with the move asked for
it is not refused."""

from __future__ import annotations

from types import SimpleNamespace

import pytest
from tests.helpers.cli import Q_START

from lbrcli.commands.control import UPRIGHT_FLAGS
from lbrcli.control import UprightClient
from lbrcli.fri import StopSession
from lbrcli.option_groups import name_text
from trajectories.limits import default_limits


def test_a_robot_away_from_the_rail_start_is_refused_naming_the_setting():
    rail = SimpleNamespace(q_start=tuple(Q_START.tolist()))  # the check reads only the rail's start
    away = SimpleNamespace(measured_joint_position=tuple((Q_START + 0.01).tolist()))  # [rad]
    with pytest.raises(StopSession) as refused:
        UprightClient(rail, 0.5, default_limits()).monitor(away)
    text = refused.value.reason
    assert "0.0100 rad from the rail's start pose" in text and "--" not in text  # library code names no flag
    assert name_text(text, UPRIGHT_FLAGS).endswith("(lbr ptp) or let the session move it there (--move-to-start)")
    UprightClient(rail, 0.5, default_limits(), move_to_start=True).monitor(away)  # the move was asked for
    UprightClient(rail, 0.5, default_limits()).monitor(SimpleNamespace(measured_joint_position=rail.q_start))
