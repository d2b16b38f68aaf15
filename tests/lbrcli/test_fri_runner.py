"""lbrcli.fri_runner: what a user reads when the embedded simulator dropped the session for late replies."""

from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace

import pytest

from lbrcli.fri import EndReason, Outcome
from lbrcli.fri_runner import LATE_REPLIES_HINT, _SessionParts
from lbrcli.fri_options import SESSION_FLAGS
from lbrcli.option_groups import name_text
from lbrcli.session_settings import SimulatorSettings


@dataclass(frozen=True)
class _Result:  # the fields of lbrcli.fri.SessionResult that judging reads
    ok: bool
    outcome: Outcome
    reason: EndReason
    detail: str


def _result(ok: bool) -> _Result:
    return _Result(ok, Outcome.COMPLETED if ok else Outcome.STOPPED, EndReason.LEFT_COMMANDING,
                   "the session left COMMANDING_ACTIVE (MONITORING_WAIT)")  # fmt: skip


def _parts(sim: SimulatorSettings | None, end_reason: str):
    parts = _SessionParts(rep=None, app=None, session=None, simulator=sim, lab=None)
    parts.sim_stats = SimpleNamespace(end_reason=end_reason)
    return parts


@pytest.mark.parametrize(
    "sim, end_reason, hinted",
    [
        (SimulatorSettings(), "quality", True),  # on the period's grid, dropped for its timing: say why, say what helps
        (SimulatorSettings(), "safety_stop", False),  # another reason: its own words
        (SimulatorSettings(lockstep=True), "quality", False),  # lock-step waits for replies: not a timing drop
        (SimulatorSettings(loss=0.3), "quality", False),  # injected faults are their own explanation
        (None, "quality", False),  # a real robot: the controller's reason is the one the session reports
    ],
)
def test_a_drop_for_late_replies_is_explained_with_what_helps(sim, end_reason, hinted):
    judged = _parts(sim, end_reason).judged(_result(ok=False))
    assert judged.detail.endswith(LATE_REPLIES_HINT) is hinted
    assert judged.detail.startswith("the session left COMMANDING_ACTIVE")
    if hinted:
        assert "SimulatorSettings.lockstep" in judged.detail and "late replies" in judged.detail
        assert "lock-step (--sim-lockstep) waits" in name_text(judged.detail, SESSION_FLAGS)  # as the commands say it


def test_a_completed_session_is_not_touched():
    result = _result(ok=True)
    assert _parts(SimulatorSettings(), "quality").judged(result) is result
