"""FRI client session over loopback against a scripted controller: states, counters, framings, receiveMultiplier,
loss, malformed/foreign/stale datagrams, end conditions, guard, far start, interrupt, and the execution log."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
from fri_scripted_controller import CA, CW, IDLE, MR, MW, Cycle, ScriptedController

from lbrcli.fri.client import COMPLETED, INTERRUPTED, REFUSED, STOPPED, FriSession
from lbrcli.fri.codec import FriCodec
from lbrcli.fri.guard import CommandGuard
from lbrcli.fri.log import LOG_COLUMNS, PHASE_HOLD, PHASE_MOVE, PHASE_SETTLE, PHASE_TRAJECTORY, ExecutionLog, LogLayout
from lbrcli.fri.motion import MOVE_SCALE, Plan, build_plan, jerk_limited_move, resample
from trajectories.csvio import read_table
from trajectories.errors import CheckFailed, FriError
from trajectories.trajectory import JointTrajectory

Q0 = (0.0, 0.071, 0.0, -1.3523, 0.0, 0.1301, 0.0)
SETTLE_S = 0.004  # 4 rows at 1 ms


def wave(n: int, amp: float = 0.005) -> np.ndarray:
    """(n, 7) smooth rest-to-rest trajectory from Q0 [rad], slow enough for 1 ms steps."""
    s = (1 - np.cos(np.linspace(0, 2 * np.pi, n))) / 2
    return np.array(Q0) + amp * s[:, None] * np.array([1, 0.5, -0.5, 1, 0.3, -1, 1])


def preamble(k: int = 1, **kw) -> list[Cycle]:
    return (
        [Cycle(state=IDLE, **kw)]
        # the client checks the start and plans at the first session message: give it the time a loaded machine
        # needs, so that no backlog builds up (the client drops a backlog unanswered, which would end these
        # strict lock-step scripts; test_backlog_dropped_after_preparing_keeps_every_kth_aligned covers that case)
        + [Cycle(state=MW, quality=1, receive_multiplier=k, pause_s=0.3, **kw)]
        + [Cycle(state=MW, quality=1, receive_multiplier=k, **kw)] * 2
        + [Cycle(state=MR, receive_multiplier=k, **kw)] * 3
        + [Cycle(state=CW, receive_multiplier=k, **kw)] * 4
    )


def run(script, traj=None, *, version="1.15", tmp_path=None, plan_fn=None, limits=None, on_cycle=None, hold=10,
        move_to_start=False, q_start=Q0, **controller):  # fmt: skip
    from trajectories.limits import default_limits

    lim = limits or default_limits()
    sess = FriSession("127.0.0.1", 0, bind_host="127.0.0.1", version=version, limits=lim,
                      first_message_timeout_s=10, silence_timeout_s=5, hold_cycles=hold)  # fmt: skip
    ctl = ScriptedController(sess.port, script, q_start, version=version, **controller)
    if on_cycle is not None:
        ctl.on_cycle = lambda i: on_cycle(i, sess)

    def prepare(mon, period_s):
        if plan_fn is not None:
            return plan_fn(mon, period_s)
        if traj is None:
            return None
        msr = np.array(mon.monitorData.measuredJointPosition.value)
        return build_plan(traj, msr, period_s, lim, start_tolerance=1e-3, move_to_start=move_to_start, settle_s=SETTLE_S)

    log_path = tmp_path / "log.csv" if tmp_path is not None else None
    ctl.start()
    error = None
    try:
        with ExecutionLog(log_path) if log_path else _null() as log:
            try:
                res = sess.run(prepare, log)
            except Exception as exc:  # noqa: BLE001 - returned to the test
                res, error = None, exc
    finally:
        ctl.client_done.set()
        ctl.join()
        sess.close()
    return res, ctl, log_path, error


class _null:
    def __enter__(self):
        return None

    def __exit__(self, *a):
        return None


def read_log(path):
    return read_table(path, LOG_COLUMNS, time="increasing")


def cmd_cols(tab):
    return np.column_stack([tab.column(f"cmd_q{j}") for j in range(1, 8)])


# -- the normal session ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("version", ["1.15", "2.7"])
def test_session_states_counters_and_rows(tmp_path, version):
    n = 40
    traj = wave(n)
    script = preamble() + [Cycle(state=CA)] * (n + 10)
    res, ctl, log_path, err = run(script, traj, version=version, tmp_path=tmp_path)
    assert err is None
    assert res.outcome == COMPLETED and res.trajectory_rows == n and res.settle_rows == 4
    assert res.states_seen == (IDLE, MW, MR, CW, CA)
    assert ctl.unexpected == [] and res.missed == 0 and res.malformed == 0 and res.foreign == 0
    # IDLE is never answered; every other message is, with consecutive client counters reflecting the message
    assert [r.header[0] for r in ctl.replies] == list(range(len(ctl.replies)))
    assert all(r.header[1] == r.seq for r in ctl.replies)
    assert all(r.state != IDLE for r in ctl.replies)
    by_state = {s: [r for r in ctl.replies if r.state == s] for s in (MW, MR, CW, CA)}
    assert len(by_state[MW]) == 3 and all(r.position is None for r in by_state[MW] + by_state[MR])
    assert all(r.position == Q0 for r in by_state[CW])  # mirror of ipo
    active = np.array([r.position for r in by_state[CA]])
    np.testing.assert_array_equal(active[:n], traj)  # the file's rows, in order, bit for bit
    np.testing.assert_array_equal(active[n:], np.repeat(traj[-1:], 4, axis=0))  # settle: hold the last row
    assert ctl.unanswered == [len(preamble()) + n + 4]  # then the client stops answering
    # the log: strict reader, one row per message, the commanded rows and their indices
    tab = read_log(log_path)
    assert len(tab.data) == res.cycles == res.log_rows
    phase = tab.column("phase")
    np.testing.assert_array_equal(cmd_cols(tab)[phase == PHASE_TRAJECTORY], traj)
    np.testing.assert_array_equal(tab.column("row")[phase == PHASE_TRAJECTORY], np.arange(n))
    assert (phase == PHASE_SETTLE).sum() == 4
    assert tab.has("ball_theta") and tab.has("gripper")
    np.testing.assert_allclose(tab.column("ball_theta"), 0.01)
    assert tab.has("ctl_q1") == (version == "1.15")
    np.testing.assert_array_equal(tab.column("msr_tau3"), 3.0)
    np.testing.assert_allclose(np.diff(tab.column("t")), 1e-3)
    assert res.max_ball_theta == pytest.approx(0.01) and res.min_tracking == 1.0
    # the ideal scripted robot is where the previous command put it
    assert res.max_tracking_error_prev == 0.0 and res.max_tracking_error == pytest.approx(np.abs(np.diff(traj, axis=0)).max())


def test_receive_multiplier_answers_every_kth(tmp_path):
    k, n = 3, 12
    traj = wave(n, 0.002)
    script = preamble(k) + [Cycle(state=CA, receive_multiplier=k)] * (k * (n + 4) + 2)
    res, ctl, log_path, err = run(script, traj, tmp_path=tmp_path)
    assert err is None and res.outcome == COMPLETED and ctl.unexpected == []
    # messages counted from the first non-IDLE one: the k-th, 2k-th, ... are answered
    answered_seqs = [r.seq for r in ctl.replies]
    assert answered_seqs == [1 + k * (i + 1) - 1 for i in range(len(answered_seqs))]
    active = np.array([r.position for r in ctl.replies if r.state == CA])
    np.testing.assert_array_equal(active[:n], traj)  # one row per ANSWERED cycle
    tab = read_log(log_path)
    assert tab.column("answered").sum() == res.answered == len(ctl.replies)
    assert res.period_s == pytest.approx(k * 1e-3)


def test_backlog_dropped_after_preparing_keeps_every_kth_aligned(tmp_path):
    """A slow preparation lets messages queue; the client drops them but still counts them toward the
    receive multiplier, so afterwards it answers exactly the messages the controller expects."""
    k, n = 3, 12
    traj = wave(n, 0.002)
    from trajectories.limits import default_limits

    lim = default_limits()

    def slow_plan(mon, period_s):
        time.sleep(0.1)  # the controller sends the rest of its group meanwhile
        msr = np.array(mon.monitorData.measuredJointPosition.value)
        return build_plan(traj, msr, period_s, lim, start_tolerance=1e-3, move_to_start=False, settle_s=SETTLE_S)

    script = (
        [Cycle(state=IDLE)]
        + [Cycle(state=MW, quality=1, receive_multiplier=k)] * (2 * k)
        + [Cycle(state=MR, receive_multiplier=k)] * k
        + [Cycle(state=CW, receive_multiplier=k)] * (2 * k)
        + [Cycle(state=CA, receive_multiplier=k)] * (k * (n + 4) + 2)
    )
    res, ctl, _, err = run(script, traj, tmp_path=tmp_path, plan_fn=slow_plan, reply_timeout=0.5,
                           tolerate_unanswered=1)  # fmt: skip
    assert err is None and res.outcome == COMPLETED
    assert res.skipped >= 2  # the rest of the first group was dropped, unanswered
    # only the dropped group's expected message (script cycle 3) went unanswered before the client completed,
    # and no reply went to a message the controller did not expect
    assert ctl.unanswered[0] == 3 and all(i > ctl.replies[-1].cycle for i in ctl.unanswered[1:])
    assert ctl.unexpected == []
    assert all((r.seq % k) == 0 for r in ctl.replies)  # every k-th message of the controller's count (seq from 1)
    active = np.array([r.position for r in ctl.replies if r.state == CA])
    np.testing.assert_array_equal(active[:n], traj)


def test_sequence_gaps_count_as_missed_and_rows_continue(tmp_path):
    n = 20
    traj = wave(n, 0.002)
    body = [Cycle(state=CA)] * (n + 8)
    body[5] = Cycle(state=CA, seq_jump=3)
    body[9] = Cycle(state=CA, seq_jump=1)
    res, ctl, log_path, err = run(preamble() + body, traj, tmp_path=tmp_path)
    assert err is None and res.outcome == COMPLETED
    assert res.missed == 4
    np.testing.assert_array_equal(np.array([r.position for r in ctl.replies if r.state == CA])[:n], traj)
    t = read_log(log_path).column("t")
    assert np.isclose(np.diff(t), 4e-3).sum() == 1 and np.isclose(np.diff(t), 2e-3).sum() == 1  # controller time


def test_malformed_foreign_and_stale_datagrams_are_ignored_and_counted(tmp_path):
    n = 20
    traj = wave(n, 0.002)
    good = FriCodec("1.15")
    cmd = good.new_command()
    cmd.header.messageIdentifier, cmd.header.sequenceCounter, cmd.header.reflectedSequenceCounter = 0x34001, 0, 0
    junk = [b"", b"\x00\x01garbage", FriCodec("2.7").frame(b"\x08\x01"), good.encode(cmd)]  # empty, noise, 2.7, wrong id
    body: list[Cycle] = []
    for i in range(n + 8):
        body.append(Cycle(state=CA))
        if i in (2, 7, 11, 13):
            body.append(Cycle(raw=junk[[2, 7, 11, 13].index(i)]))
        if i in (4, 9):
            body.append(Cycle(state=CA, foreign=True))
        if i == 6:
            body.append(Cycle(state=CA, repeat_seq=True))
    res, ctl, log_path, err = run(preamble() + body, traj, tmp_path=tmp_path)
    assert err is None and res.outcome == COMPLETED and ctl.unexpected == []
    assert (res.malformed, res.foreign, res.stale) == (4, 2, 1)
    np.testing.assert_array_equal(np.array([r.position for r in ctl.replies if r.state == CA])[:n], traj)
    assert len(read_log(log_path).data) == res.cycles  # ignored datagrams are not logged


# -- end conditions -------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "bad, reason",
    [
        (Cycle(state=CA, safety=2), "safety stop (SAFETY_STOP_LEVEL_1)"),
        (Cycle(state=CA, drive=0), "drives not active"),
        (Cycle(state=CA, quality=0), "connection quality POOR"),
        (Cycle(state=MW, quality=1), "left COMMANDING_ACTIVE (MONITORING_WAIT)"),
        (Cycle(state=IDLE), "closed the FRI session (IDLE)"),
    ],
)
def test_stream_ends_cleanly_on_robot_side_events(tmp_path, bad, reason):
    n = 30
    traj = wave(n, 0.002)
    body = [Cycle(state=CA)] * 10 + [bad] + [Cycle(state=CA)] * 5
    res, ctl, log_path, err = run(preamble() + body, traj, tmp_path=tmp_path)
    assert err is None and res.outcome == STOPPED and reason in res.end_reason
    assert res.trajectory_rows == 10
    active = [r for r in ctl.replies if r.state == CA]
    np.testing.assert_array_equal(np.array([r.position for r in active]), traj[:10])
    assert all(r.cycle < len(preamble()) + 10 for r in ctl.replies)  # nothing answered from the event on
    tab = read_log(log_path)  # complete and parseable, ending with the event
    assert len(tab.data) == res.cycles and tab.column("answered")[-1] == 0
    assert tab.column("state")[-1] == bad.state


def test_guard_refuses_a_jump_holds_then_stops(tmp_path):
    n, hold = 20, 5
    traj = wave(n, 0.002)
    bad = traj.copy()
    bad[12:] += 0.05  # a 50 mrad step in 1 ms = 50 rad/s

    def plan_fn(mon, period_s):
        return Plan(rows=bad, n_move=0, n_traj=n, n_settle=0, period_s=period_s)

    res, ctl, log_path, err = run(preamble() + [Cycle(state=CA)] * (n + 10), plan_fn=plan_fn, tmp_path=tmp_path, hold=hold)
    assert err is None and res.outcome == REFUSED
    assert "plan row 12" in res.end_reason and "velocity limit" in res.end_reason
    active = np.array([r.position for r in ctl.replies if r.state == CA])
    np.testing.assert_array_equal(active[:12], traj[:12])
    np.testing.assert_array_equal(active[12:], np.repeat(traj[11:12], hold, axis=0))  # held the last safe row
    tab = read_log(log_path)
    assert (tab.column("phase") == PHASE_HOLD).sum() == hold
    assert not np.any(np.abs(cmd_cols(tab) - traj[11]).max(axis=1) > 0.04)  # the jump never went out


def test_guard_limits():
    from trajectories.limits import default_limits

    lim = default_limits()
    g = CommandGuard.from_limits(lim, 1e-3)
    q = list(Q0)
    assert g.refuse(q, q) is None
    step = list(q)
    step[3] += 0.99 * lim.velocity[3] * 1e-3
    assert g.refuse(q, step) is None
    step[3] = q[3] + 1.01 * lim.velocity[3] * 1e-3
    assert "A4" in g.refuse(q, step) and "velocity" in g.refuse(q, step)
    edge = list(q)
    edge[0] = lim.position[0] + 1e-9
    assert "A1" in g.refuse(edge, edge) and "position limit" in g.refuse(edge, edge)
    nan = list(q)
    nan[6] = math.nan
    assert g.refuse(q, nan) is not None


def test_interrupt_holds_the_last_command_then_stops(tmp_path):
    n, hold = 60, 6
    traj = wave(n, 0.002)
    start_active = len(preamble())

    def on_cycle(i, sess):
        if i == start_active + 15:
            sess.interrupt()

    res, ctl, log_path, err = run(preamble() + [Cycle(state=CA)] * (n + 10), traj, tmp_path=tmp_path,
                                  on_cycle=on_cycle, hold=hold)  # fmt: skip
    assert err is None and res.outcome == INTERRUPTED
    active = np.array([r.position for r in ctl.replies if r.state == CA])
    k = res.trajectory_rows
    assert 14 <= k <= 16  # the interrupt lands within a cycle
    np.testing.assert_array_equal(active[:k], traj[:k])
    np.testing.assert_array_equal(active[k:], np.repeat(traj[k - 1 : k], hold, axis=0))
    tab = read_log(log_path)
    assert (tab.column("phase") == PHASE_HOLD).sum() == hold


def test_interrupt_while_monitoring_ends_at_once():
    res, ctl, _, err = run([Cycle(state=MR)] * 200, None, on_cycle=lambda i, s: s.interrupt() if i == 5 else None)
    assert err is None and res.outcome == INTERRUPTED and len(ctl.replies) <= 6


# -- start --------------------------------------------------------------------------------------------------
def test_far_start_is_refused_before_anything_is_sent(tmp_path):
    traj = wave(20) + 0.01  # 10 mrad from where the robot stands
    res, ctl, log_path, err = run(preamble() + [Cycle(state=CA)] * 30, traj, tmp_path=tmp_path)
    assert isinstance(err, CheckFailed) and "--start-tolerance" in str(err) and "--move-to-start" in str(err)
    assert ctl.replies == []
    tab = read_log(log_path)  # the IDLE message and the first session message are logged, unanswered
    assert len(tab.data) == 2 and not tab.column("answered").any() and tab.column("state")[-1] == MW


def test_move_to_start_is_jerk_limited_then_streams_the_file(tmp_path):
    from trajectories.limits import default_limits

    lim = default_limits()
    n = 10
    traj = wave(n, 0.001) + np.array([0.02, -0.01, 0, 0.01, 0, 0, 0.02])
    res, ctl, log_path, err = run(preamble() + [Cycle(state=CA)] * 2000, traj, tmp_path=tmp_path, move_to_start=True)
    assert err is None and res.outcome == COMPLETED and res.move_rows > 10
    active = np.array([r.position for r in ctl.replies if r.state == CA])
    move = np.vstack([Q0, active[: res.move_rows]])
    v = np.diff(move, axis=0) / 1e-3
    assert np.all(np.abs(v) <= MOVE_SCALE * lim.velocity + 1e-9)
    np.testing.assert_allclose(move[-1], traj[0], atol=1e-12)
    np.testing.assert_array_equal(active[res.move_rows : res.move_rows + n], traj)
    phase = read_log(log_path).column("phase")
    assert (phase == PHASE_MOVE).sum() == res.move_rows


def test_no_message_times_out_naming_the_cause():
    from trajectories.limits import default_limits

    with FriSession("127.0.0.1", 0, bind_host="127.0.0.1", limits=default_limits(), first_message_timeout_s=0.4) as s:
        ctl = ScriptedController(s.port, [Cycle(state=MR, foreign=True)] * 5, Q0).start()
        with pytest.raises(FriError, match="no FRI monitoring message.*other addresses"):
            s.run(None)
        ctl.join()


def test_wrong_version_is_malformed_and_named():
    from trajectories.limits import default_limits

    with FriSession("127.0.0.1", 0, bind_host="127.0.0.1", version="1.15", limits=default_limits(),
                    first_message_timeout_s=0.5) as s:  # fmt: skip
        ctl = ScriptedController(s.port, [Cycle(state=MR)], Q0, version="2.7", reply_timeout=0.2).start()
        with pytest.raises(FriError, match="did not decode as FRI 1.15"):
            s.run(None)
        ctl.join()


# -- monitoring (no plan): never commands motion ------------------------------------------------------------
def test_monitoring_session_mirrors_and_never_moves(tmp_path):
    script = preamble() + [Cycle(state=CA)] * 20 + [Cycle(state=MR)] * 3 + [Cycle(state=IDLE)]
    res, ctl, log_path, err = run(script, None, tmp_path=tmp_path)
    assert err is None and res.outcome == STOPPED and "IDLE" in res.end_reason
    assert all(r.position in (None, Q0) for r in ctl.replies)
    assert len(ctl.replies) == len(script) - 2  # all but the two IDLE messages


# -- log and motion units -------------------------------------------------------------------------------------
def test_log_layout_io_columns_and_missing_values(tmp_path):
    codec = FriCodec("1.15")
    m = codec.new_monitoring()
    m.header.messageIdentifier, m.header.sequenceCounter, m.header.reflectedSequenceCounter = 0x245142, 0, 0
    m.connectionInfo.sessionState, m.connectionInfo.quality = 2, 3
    for name, val in (("ball_theta", 0.2), ("t", 1.0), ("a,b", 2.0)):
        io = m.monitorData.readIORequest.add()
        io.name, io.type, io.direction, io.analogValue = name, 2, 0, val
    layout = LogLayout(m, "1.15", extra=("flange_x",))
    assert layout.names[-4:] == ("flange_x", "ball_theta", "io_t", "a_b")
    path = tmp_path / "l.csv"
    with ExecutionLog(path) as log:
        log.start(layout)
        log.write(layout.format(0.0, m, Q0, -1, 0, 0, 0, -1, (0.5,)))
        del m.monitorData.readIORequest[:]  # later message without IO values: keep the last ones
        log.write(layout.format(0.001, m, Q0, 0, 1, 0, 0, -1, (0.6,)))
    tab = read_log(path)
    np.testing.assert_array_equal(tab.column("ball_theta"), [0.2, 0.2])
    np.testing.assert_array_equal(tab.column("a_b"), [2.0, 2.0])
    np.testing.assert_array_equal(tab.column("msr_q1"), [0.0, 0.0])  # not sent → 0
    np.testing.assert_array_equal(tab.column("cmd_q4"), [Q0[3]] * 2)


def test_resample_and_jerk_limited_move(limits):
    t = np.arange(0, 1.0 + 1e-12, 0.005)
    q = np.array(Q0) + np.sin(np.pi * t)[:, None] * 0.1
    rs = resample(JointTrajectory(t=t, q=q), 0.001)
    assert len(rs) == 1001 and rs.dt == pytest.approx(0.001)
    np.testing.assert_allclose(rs.q[::5], q, atol=1e-12)
    np.testing.assert_allclose(rs.q, np.array(Q0) + np.sin(np.pi * rs.t)[:, None] * 0.1, atol=1e-6)
    goal = np.array(Q0) + 0.3
    move = jerk_limited_move(np.array(Q0), goal, limits, 0.002, scale=0.2, minimum_duration=2.0)
    assert len(move) * 0.002 == pytest.approx(2.0, abs=0.0021)
    np.testing.assert_array_equal(move[-1], goal)
    path = np.vstack([Q0, move])
    assert np.all(np.abs(np.diff(path, axis=0)) / 0.002 <= 0.2 * limits.velocity + 1e-9)
    plan = build_plan(move, np.array(Q0) + 5e-4, 0.002, limits, start_tolerance=1e-3, move_to_start=False, settle_s=0.01)
    assert (plan.n_move, plan.n_traj, plan.n_settle) == (0, len(move), 5)
    assert plan.phase(len(move)) == (PHASE_SETTLE, -1) and plan.phase(3) == (PHASE_TRAJECTORY, 3)


def test_period_change_mid_stream_stops_it(tmp_path):
    n = 30
    traj = wave(n, 0.002)
    body = [Cycle(state=CA)] * 8 + [Cycle(state=CA, send_period=2)] + [Cycle(state=CA)] * 5
    res, ctl, log_path, err = run(preamble() + body, traj, tmp_path=tmp_path)
    assert err is None and res.outcome == STOPPED and "changed its period from 1 ms × 1 to 2 ms × 1" in res.end_reason
    assert res.trajectory_rows == 8


def test_log_without_any_message_is_removed(tmp_path):
    log = ExecutionLog(tmp_path / "empty.csv")
    assert (tmp_path / "empty.csv").exists()
    log.close()
    assert not (tmp_path / "empty.csv").exists()


def test_messages_queued_during_preparation_are_dropped():
    import socket

    from trajectories.limits import default_limits

    n = 20
    traj = wave(n, 0.002)
    codec = FriCodec("1.15")
    port = {}

    def plan_fn(mon, period_s):  # three messages arrive while the plan is being made
        m = codec.new_monitoring()
        m.header.messageIdentifier, m.header.reflectedSequenceCounter = 0x245142, 0
        m.connectionInfo.sessionState, m.connectionInfo.quality = MW, 1
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            for k in range(3):
                m.header.sequenceCounter = 10_000 + k
                s.sendto(codec.encode(m), ("127.0.0.1", port["p"]))
        time.sleep(0.05)
        msr = np.array(mon.monitorData.measuredJointPosition.value)
        return build_plan(traj, msr, period_s, default_limits(), start_tolerance=1e-3, move_to_start=False, settle_s=0)

    def on_cycle(i, sess):
        port["p"] = sess.port

    res, ctl, _, err = run(preamble() + [Cycle(state=CA)] * (n + 5), plan_fn=plan_fn, on_cycle=on_cycle)
    assert err is None and res.outcome == COMPLETED and res.skipped == 3 and res.prepare_ms >= 50
    assert res.missed == 0  # the dropped ones were not from the session's sequence (other counters)
    np.testing.assert_array_equal(np.array([r.position for r in ctl.replies if r.state == CA])[:n], traj)
