"""Replies prepared one cycle ahead (``LBRClient.prepare_command``, ``lbrcli.fri.replying``) against the scripted
controller: the same commands as the cycle-by-cycle path bit for bit (both wire formats, gaps, stale, foreign and
garbage datagrams, robot-side ends, a pushed robot), inconsistent messages never answered, a client whose
prediction is wrong stopped by a braking stop, and the supervision's stop one command later within the limits; torque
and wrench replies prepared with ``prepare_overlay`` (the same as cycle by cycle, a wrong one stopped with its effort
ramped down from the last sent, one outside the guard left to the full cycle)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from lbrcli.fri.testing import CA, IDLE, MR, Cycle
from tests.helpers.fri_session import LIM, Q0, assert_within_limits, fast_ramp, min_jerk, preamble, run, sent_positions

from lbrcli.fri import EndReason, LBRClient, Outcome, TrajectoryPlayer


def both(script, make_client, **kw):
    """The run with prepared replies and the run without, each (result, controller)."""
    out = []
    for prepare in (True, False):
        res, ctl, _, err = run(script, make_client(), prepare=prepare, **kw)
        assert err is None
        out.append((res, ctl))
    return out


def replies(ctl):
    return [(r.state, r.seq, r.header, r.position) for r in ctl.replies]


@pytest.mark.parametrize("version", ["1.15", "2.7"])
def test_prepared_replies_carry_exactly_what_the_cycle_by_cycle_path_sends(version):
    n, settle = 150, 4
    traj = min_jerk(n)
    script = preamble() + [Cycle(state=CA)] * (n + 20)
    (res, ctl), (res0, ctl0) = both(script, lambda: TrajectoryPlayer(traj, LIM, period_s=1e-3, settle_cycles=settle),
                                    version=version)  # fmt: skip
    assert res.outcome is Outcome.COMPLETED and res0.outcome is Outcome.COMPLETED
    assert ctl.unexpected == [] and ctl0.unexpected == []
    # every row after the first (activation) and every settle command went out prepared; none without preparing
    assert res.prepared_replies == n - 1 + settle and res0.prepared_replies == 0
    assert replies(ctl) == replies(ctl0)
    np.testing.assert_array_equal(sent_positions(ctl)[:n], traj)
    assert [r.header[0] for r in ctl.replies] == list(range(len(ctl.replies)))
    assert all(r.header[1] == r.seq for r in ctl.replies)


@pytest.mark.heavy
def test_gaps_stale_foreign_and_garbage_take_the_full_cycle_and_change_nothing():
    n = 400
    traj = min_jerk(n)
    ca = [Cycle(state=CA)] * 100
    script = (preamble() + ca + [Cycle(state=CA, seq_jump=2)] + [Cycle(state=CA, repeat_seq=True)]
              + [Cycle(state=CA, foreign=True), Cycle(raw=b"\x00\x01garbage"), Cycle(state=CA, stale_by=3)]
              + [Cycle(state=CA)] * 100 + [Cycle(state=CA, seq_jump=1)] + [Cycle(state=CA)] * (n + 100))  # fmt: skip
    (res, ctl), (res0, ctl0) = both(script, lambda: TrajectoryPlayer(traj, LIM, period_s=1e-3),
                                    tolerate_unanswered=0)  # fmt: skip
    assert res.outcome is Outcome.COMPLETED and res.missed == 3 and res.stale == 2 and res.malformed == 1
    assert res.prepared_replies > n - 20  # (after the gaps the player rejoins its rows itself: no offset, prepared)
    assert replies(ctl) == replies(ctl0)  # (the sent positions skip what the controller extrapolated)


@pytest.mark.heavy
@pytest.mark.parametrize(
    "mutate",
    [
        lambda m: m.ipoData.jointPosition.value.__setitem__(3, 1e6),
        lambda m: m.monitorData.measuredJointPosition.value.__setitem__(0, math.nan),
        lambda m: m.monitorData.measuredJointPosition.value.__setitem__(6, math.inf),
        lambda m: m.monitorData.measuredJointPosition.value.pop(),
        lambda m: m.ClearField("connectionInfo"),
    ],
    ids=["ipo-1e6", "nan-measured", "inf-measured", "six-measured", "no-connection-info"],
)
def test_an_inconsistent_message_is_never_answered_even_with_a_reply_prepared(mutate):
    n = 300
    traj = min_jerk(n)
    k = len(preamble()) + 50
    script = preamble() + [Cycle(state=CA)] * 50 + [Cycle(state=CA, mutate=mutate)] + [Cycle(state=CA)] * (n + 50)
    (res, ctl), (res0, ctl0) = both(script, lambda: TrajectoryPlayer(traj, LIM, period_s=1e-3),
                                    tolerate_unanswered=1, reply_timeout=1.0)  # fmt: skip
    assert res.outcome is Outcome.COMPLETED and res.malformed == 1
    assert k in ctl.unanswered and all(r.cycle != k for r in ctl.replies)
    assert res.prepared_replies > n - 20  # preparing went on after it
    assert replies(ctl) == replies(ctl0)


@pytest.mark.parametrize("bad, reason", [(dict(safety=2), EndReason.SAFETY_STOP), (dict(drive=1), EndReason.DRIVES_OFF),
                                         (dict(quality=0), EndReason.QUALITY_POOR), (dict(state=MR), EndReason.LEFT_COMMANDING),
                                         (dict(send_period=2), EndReason.PERIOD_CHANGED)])  # fmt: skip
def test_a_robot_side_end_is_not_answered_with_the_prepared_reply(bad, reason):
    script = preamble() + [Cycle(state=CA)] * 30 + [Cycle(**{"state": CA, **bad})] + [Cycle(state=CA)] * 5
    res, ctl, _, err = run(script, TrajectoryPlayer(min_jerk(100), LIM, period_s=1e-3))
    assert err is None and res.reason is reason and res.prepared_replies >= 28
    assert ctl.unanswered == [len(preamble()) + 30]


class Predicting(LBRClient):
    """Streams ``rows`` [rad] and predicts them; from row ``lie_at`` on, command() moves 1e-7 rad off the
    prediction on A1 (a client whose prediction is wrong)."""

    def __init__(self, rows, lie_at: int | None = None) -> None:
        self.rows, self.i, self.lie_at = [tuple(r) for r in rows], 0, lie_at

    def prepare_command(self):
        return self.rows[self.i] if 0 < self.i < len(self.rows) else None

    def command(self, state):
        q = self.rows[min(self.i, len(self.rows) - 1)]
        if self.lie_at is not None and self.i >= self.lie_at:
            q = (q[0] + 1e-7, *q[1:])
        self.i += 1
        return q


def test_a_wrong_prediction_ends_in_a_braking_stop_naming_the_client():
    n = 600
    traj = fast_ramp(n)  # fast: the stop must really brake
    script = preamble() + [Cycle(state=CA)] * (n + 400)
    res, ctl, _, err = run(script, Predicting(traj, lie_at=300))
    assert err is None and res.outcome is Outcome.FAILED and res.reason is EndReason.CLIENT_ERROR
    assert "prepare_command" in res.detail
    sent = sent_positions(ctl)
    np.testing.assert_array_equal(sent[:300], traj[:300])  # the prepared rows went out as predicted
    assert res.braking_cycles > 50  # from 0.73 of the velocity limit
    assert_within_limits(sent, 1e-3)
    v_end = np.abs(sent[-1] - sent[-2]) / 1e-3
    assert np.all(v_end < 1e-9)


@pytest.mark.heavy
def test_an_honest_prediction_never_trips_the_check():
    n = 300
    traj = fast_ramp(n)
    script = preamble() + [Cycle(state=CA)] * (n + 400)
    res, ctl, _, err = run(script, Predicting(traj))
    # the rows end moving: the client's last call raises nothing, the command repeats the last row → refused
    assert err is None and res.reason is not EndReason.CLIENT_ERROR and res.prepared_replies >= n - 2


@pytest.mark.heavy
def test_supervision_brakes_from_the_command_after_the_message_it_judged():
    n = 1500
    traj = fast_ramp(n)
    k = 600
    script = preamble() + [Cycle(state=CA)] * k + [Cycle(state=CA, push=0.3)] * 5 + [Cycle(state=CA)] * (n + 400)
    (res, ctl), (res0, ctl0) = both(script, lambda: TrajectoryPlayer(traj, LIM, period_s=1e-3))
    for r, c in ((res, ctl), (res0, ctl0)):
        assert r.outcome is Outcome.STOPPED and r.reason is EndReason.SUPERVISION and "A1" in r.detail
        sent = sent_positions(c)
        assert_within_limits(sent, 1e-3)
        assert len(sent) == k + 1 + r.braking_cycles  # the pushed message's reply is the row; braking follows
        np.testing.assert_array_equal(sent[: k + 1], traj[: k + 1])
    assert replies(ctl) == replies(ctl0)
    assert all(r.state != IDLE for r in ctl.replies)


@pytest.mark.heavy
@pytest.mark.parametrize("shaped", [False, True], ids=["ruckig", "shaped"])
@pytest.mark.parametrize("gap_at", [None, 40, 150], ids=["no-gap", "gap-in-move", "gap-in-rows"])
def test_moves_to_the_start_are_prepared_step_by_step_and_change_nothing(shaped, gap_at):
    from types import SimpleNamespace

    traj = min_jerk(120) + np.array([0, 0, 0, 0.02, 0, 0, 0.01])
    shaper = SimpleNamespace(amplitudes=(0.5, 0.5), times=(0.0, 0.05)) if shaped else None
    active = [Cycle(state=CA)] * 1500
    if gap_at is not None:
        active[gap_at] = Cycle(state=CA, seq_jump=2)
    (res, ctl), (res0, ctl0) = both(preamble() + active, lambda: TrajectoryPlayer(
        traj, LIM, period_s=1e-3, move_to_start=True, move_shaper=shaper))  # fmt: skip
    assert res.outcome is Outcome.COMPLETED and res0.outcome is Outcome.COMPLETED
    assert replies(ctl) == replies(ctl0)
    moved = sent_positions(ctl)
    # (before a gap, everything; from a gap on, the way back onto the path runs the full cycle)
    assert 10 < len(moved) and res.prepared_replies > 0.9 * (min(gap_at or len(moved), len(moved)) - res.braking_cycles)
    if gap_at is None:
        assert_within_limits(moved, 1e-3, before=np.array([Q0, Q0]))


class TorqueOrWrench(LBRClient):
    """Holds Q0 and overlays a sine torque on A4 (TORQUE) or a sine force along x (WRENCH), predicting both;
    ``lie_at``: from that cycle on, command() sets the effort 1e-9 off the prediction; ``amplitude`` [Nm] or [N]."""

    def __init__(self, wrench: bool, lie_at: int | None = None, amplitude: float = 5.0) -> None:
        self.wrench, self.lie_at, self.amplitude = wrench, lie_at, amplitude
        self.k, self.next, self.efforts = 0, None, []

    def _effort(self, k: int) -> tuple[float, ...]:
        e = self.amplitude * math.sin(0.05 * k)
        return (e, 0.0, 0.0, 0.0, 0.0, 0.0) if self.wrench else (0.0, 0.0, 0.0, e, 0.0, 0.0, 0.0)

    def prepare_command(self):
        return tuple(Q0)

    def prepare_overlay(self):
        return self._effort(self.k)

    def command(self, state):
        e = self._effort(self.k)
        if self.lie_at is not None and self.k >= self.lie_at:
            e = (e[0] + 1e-9, *e[1:])
        self.k += 1
        self.efforts.append(e)
        self.robot_command.set_wrench(e) if self.wrench else self.robot_command.set_torque(e)
        return tuple(Q0)


@pytest.mark.parametrize("wrench", [False, True], ids=["torque", "wrench"])
def test_torque_and_wrench_replies_are_prepared_and_carry_what_the_cycle_by_cycle_path_sends(wrench):
    from dataclasses import replace

    mode = 2 if wrench else 3
    script = [replace(c, mode=mode) for c in preamble() + [Cycle(state=CA)] * 200]
    runs = []
    for prepare in (True, False):
        client = TorqueOrWrench(wrench)
        res, ctl, _, err = run(script, client, prepare=prepare, version="2.7" if wrench else "1.15")
        assert err is None and ctl.unexpected == []
        runs.append((res, ctl, client))
    (res, ctl, client), (res0, ctl0, _) = runs
    assert res.prepared_replies >= 195 and res0.prepared_replies == 0
    assert replies(ctl) == replies(ctl0)
    efforts = [r.wrench if wrench else r.torque for r in ctl.replies if r.state == CA]
    assert efforts == [r.wrench if wrench else r.torque for r in ctl0.replies if r.state == CA]
    np.testing.assert_array_equal(np.array(efforts), np.array(client.efforts))  # each cycle's, none skipped
    assert max(abs(e[0 if wrench else 3]) for e in efforts) > 4.0


@pytest.mark.parametrize("wrench", [False, True], ids=["torque", "wrench"])
def test_a_wrong_torque_or_wrench_prediction_ends_in_a_braking_stop_whose_effort_ramps_from_the_last_sent(wrench):
    from dataclasses import replace

    script = [replace(c, mode=2 if wrench else 3) for c in preamble() + [Cycle(state=CA)] * 400]
    client = TorqueOrWrench(wrench, lie_at=120)
    res, ctl, _, err = run(script, client, version="2.7" if wrench else "1.15")
    assert err is None and res.outcome is Outcome.FAILED and res.reason is EndReason.CLIENT_ERROR
    assert "prepare_command" in res.detail and ("wrench" if wrench else "torque") in res.detail
    efforts = np.array([r.wrench if wrench else r.torque for r in ctl.replies if r.state == CA])
    j = 0 if wrench else 3
    np.testing.assert_array_equal(efforts[:120], np.array(client.efforts[:120]))  # the prepared ones, as predicted
    # the stop ramps the effort down from the last one sent (the prepared one), with no step at its start
    step = np.abs(np.diff(efforts[:, j]))
    assert step.max() < 0.3 and abs(efforts[-1, j]) < 1e-9


def test_a_prepared_torque_outside_the_guard_is_not_sent_and_the_full_cycle_refuses_it_as_before():
    from dataclasses import replace

    script = [replace(c, mode=3) for c in preamble() + [Cycle(state=CA)] * 60]
    out = []
    for prepare in (True, False):
        res, ctl, _, err = run(script, TorqueOrWrench(False, amplitude=1e4), prepare=prepare)
        assert err is None
        out.append((res, ctl))
    (res, ctl), (res0, ctl0) = out
    assert res.reason is res0.reason and res.detail == res0.detail and "torque" in res.detail
    assert replies(ctl) == replies(ctl0)
    assert all(abs(r.torque[3]) <= 200.0 for r in ctl.replies if r.torque is not None)
