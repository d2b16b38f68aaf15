"""The FRI client application over loopback against a scripted controller: states, counters, both wire formats,
version detection, receiveMultiplier, loss, malformed / foreign / stale / inconsistent datagrams, robot-side ends,
the guard, braking stops, far starts, interrupts, client errors, a failing log, and the execution log."""

from __future__ import annotations

import math
import os
import sys
import time

import numpy as np
import pytest
from lbrcli.fri.testing import CA, CW, IDLE, MR, MW, Cycle, ScriptedController

from lbrcli.fri import (
    ClientApplication,
    EndReason,
    ExecutionLog,
    FriTimeout,
    LBRClient,
    LogObserver,
    Outcome,
    Phase,
    StopSession,
    TrajectoryPlayer,
)
from lbrcli.fri.log import LOG_COLUMNS
from trajectories.csvio import read_table
from tests.helpers.fri_session import assert_within_limits, fast_ramp, LIM, min_jerk, preamble, Q0, run, sent_positions


def read_log(path):
    return read_table(path, LOG_COLUMNS, time="increasing")


# -- the normal session ---------------------------------------------------------------------------------------
@pytest.mark.heavy
@pytest.mark.parametrize("version", ["1.15", "2.7"])
@pytest.mark.parametrize("detect", [False, True])
def test_session_streams_every_row_bit_exact_and_logs(tmp_path, version, detect):
    n = 100
    traj = min_jerk(n)
    player = TrajectoryPlayer(traj, LIM, period_s=1e-3, settle_cycles=4)
    script = preamble() + [Cycle(state=CA)] * (n + 20)
    res, ctl, log_path, err = run(script, player, version=version, detect=detect, tmp_path=tmp_path)
    assert err is None
    assert res.outcome is Outcome.COMPLETED and res.reason is EndReason.FINISHED and res.version == version
    assert player.trajectory_rows == n and player.settle_rows == 4 and player.move_rows == 0
    assert res.states_seen == (IDLE, MW, MR, CW, CA)
    assert ctl.unexpected == [] and res.missed == 0 and res.malformed == 0 and res.foreign == 0
    assert res.unanswered_at_start == 0
    # IDLE is never answered; every other message is, with consecutive client counters reflecting the message
    assert [r.header[0] for r in ctl.replies] == list(range(len(ctl.replies)))
    assert all(r.header[1] == r.seq for r in ctl.replies) and all(r.state != IDLE for r in ctl.replies)
    assert all(r.position is None for r in ctl.replies if r.state in (MW, MR))  # header only
    assert all(r.position == Q0 for r in ctl.replies if r.state == CW)  # the ipo position held
    active = sent_positions(ctl)
    np.testing.assert_array_equal(active[:n], traj)  # the file's rows, in order, bit for bit
    np.testing.assert_array_equal(active[n:], np.repeat(traj[-1:], len(active) - n, axis=0))  # settle, then the stop
    assert res.braking_cycles == len(active) - n - 4  # at rest: the stop holds a few cycles, then ends
    tab = read_log(log_path)
    assert len(tab.data) == res.cycles == res.figures["log_rows"]
    phase = tab.column("phase")
    cmd = np.column_stack([tab.column(f"cmd_q{j}") for j in range(1, 8)])
    np.testing.assert_array_equal(cmd[phase == Phase.TRAJECTORY], traj)
    np.testing.assert_array_equal(tab.column("row")[phase == Phase.TRAJECTORY], np.arange(n))
    assert (phase == Phase.SETTLE).sum() == 4 and (phase == Phase.BRAKE).sum() == res.braking_cycles
    assert tab.has("ball_theta") and tab.has("gripper") and tab.has("ctl_q1") == (version == "1.15")
    np.testing.assert_allclose(np.diff(tab.column("t")), 1e-3)
    assert res.figures["max_ball_theta"] == pytest.approx(0.01) and res.figures["min_tracking"] == 1.0


def test_receive_multiplier_calls_every_message_and_sends_every_kth():
    k, n = 3, 30
    traj = min_jerk(n)
    calls, periods = [], set()

    class Counting(TrajectoryPlayer):
        def command(self, state):
            calls.append(self.reply_due)
            periods.add(self.command_period_s)  # the application's, not recomputed by the client
            return super().command(state)

    player = Counting(traj, LIM, period_s=k * 1e-3, settle_cycles=2)
    script = preamble(k) + [Cycle(state=CA, receive_multiplier=k)] * ((n + 12) * k)
    res, ctl, _, err = run(script, player)
    assert err is None and res.outcome is Outcome.COMPLETED and ctl.unexpected == []
    active = sent_positions(ctl)
    np.testing.assert_array_equal(active[:n], traj)
    # KUKA's counting: a callback for every message, every k-th one sent
    assert len(calls) >= 3 * (len(active) - res.braking_cycles) - 3
    assert calls.count(True) == len(active) - res.braking_cycles + 1  # the last call ended the stream
    assert all(calls[i : i + k].count(True) == 1 for i in range(0, len(calls) - k, k))
    assert res.period_s == pytest.approx(3e-3) and periods == {res.period_s}


def test_gaps_stale_foreign_and_malformed_are_counted_and_never_answered():
    n = 400  # within the jerk limit (a rejoin is jerk-limited)
    traj = min_jerk(n)
    player = TrajectoryPlayer(traj, LIM, period_s=1e-3)
    ca = [Cycle(state=CA)] * 100
    script = (preamble() + ca + [Cycle(state=CA, seq_jump=2)] + [Cycle(state=CA, repeat_seq=True)]
              + [Cycle(state=CA, foreign=True), Cycle(raw=b"\x00\x01garbage")] + [Cycle(state=CA)] * (n + 100))  # fmt: skip
    res, ctl, _, err = run(script, player)
    assert err is None and res.outcome is Outcome.COMPLETED
    # the jump skips 2 counters (the controller bridged 2 cycles): the rows it would have executed are skipped
    assert res.missed == 2 and res.stale == 1 and res.foreign == 1 and res.malformed == 1
    assert res.extrapolated_cycles == 2 and player.skipped_rows == 2
    assert ctl.unexpected == []
    sent = sent_positions(ctl)
    np.testing.assert_array_equal(sent[:100], traj[:100])
    # a short jerk-limited rejoin from where the controller's extrapolation left the robot, then the rows in step
    back = next(k for k in range(100, n - 2) if np.array_equal(sent[k : n - 2], traj[k + 2 :]))
    assert back <= 100 + 100  # [cycles] catching up an acceleration of 2.8 rad/s² at the jerk limit takes time
    assert max(ctl.command_ratios(LIM.velocity, LIM.acceleration)) <= 1.0


def test_a_loss_is_answered_at_once_by_the_constant_velocity_continuation_and_rejoined_after_the_reply(monkeypatch):
    """The cycle that finds lost messages does not plan the rejoin (ruckig, tenths of a ms at 1 ms: the reply would be
    late and the next message found waiting, a cascade of late replies): it answers with where the controller's
    extrapolation is one period on, and the rejoin is planned in ``after_reply``."""
    from lbrcli.fri import players

    n = 400
    traj = min_jerk(n)
    inside, calls = [False], []
    plan = players.rejoin

    def recording(*a, **k):
        calls.append(inside[0])
        return plan(*a, **k)

    class Player(TrajectoryPlayer):  # (a subclass that overrides nothing of the streaming)
        pass

    def after_reply(self):
        inside[0] = True
        try:
            if self._deferred:
                self._plan_deferred()
        finally:
            inside[0] = False

    monkeypatch.setattr(players, "rejoin", recording)
    monkeypatch.setattr(TrajectoryPlayer, "after_reply", after_reply)
    player = Player(traj, LIM, period_s=1e-3)
    script = preamble() + [Cycle(state=CA)] * 100 + [Cycle(state=CA, seq_jump=3)] + [Cycle(state=CA)] * (n + 100)
    res, ctl, _, err = run(script, player)
    assert err is None and res.outcome is Outcome.COMPLETED and res.missed == 3
    assert calls == [True]  # planned once, behind the reply
    sent = sent_positions(ctl)
    np.testing.assert_array_equal(sent[:100], traj[:100])
    np.testing.assert_allclose(sent[100], traj[99] + 4 * (traj[99] - traj[98]), atol=1e-12)  # 3 bridged + 1
    back = next(k for k in range(101, n - 3) if np.array_equal(sent[k : n - 3], traj[k + 3 :]))
    assert back <= 100 + 120  # (as a rejoin planned in the cycle after one more lost period)
    assert player.skipped_rows == 3 and player.trajectory_rows + player.skipped_rows == n
    assert max(ctl.command_ratios(LIM.velocity, LIM.acceleration)) <= 1.0


@pytest.mark.heavy
@pytest.mark.parametrize(
    "mutate",
    [
        lambda m: m.ipoData.jointPosition.value.__delitem__(slice(6, 7)),  # 6 ipo values
        lambda m: m.ipoData.ClearField("jointPosition"),  # none
        lambda m: m.ipoData.jointPosition.value.__setitem__(3, 1e6),  # absurd
        lambda m: m.monitorData.measuredJointPosition.value.__setitem__(0, math.nan),
        lambda m: m.ClearField("connectionInfo"),  # truncated before its connection info
    ],
    ids=["six-ipo", "no-ipo", "ipo-1e6", "nan-measured", "no-connection-info"],
)
def test_a_message_that_is_not_self_consistent_is_never_answered(mutate):
    player = TrajectoryPlayer(min_jerk(20), LIM, period_s=1e-3)
    bad = Cycle(state=CW, mutate=mutate)
    script = preamble()[:-1] + [bad] + [Cycle(state=CW)] * 2 + [Cycle(state=CA)] * 100
    # the controller gives up on the unanswered message well within the client's 3 s silence timeout
    res, ctl, _, err = run(script, player, tolerate_unanswered=1, reply_timeout=1.0)
    assert err is None
    assert res.malformed == 1 and res.outcome is Outcome.COMPLETED
    bad_index = len(preamble()) - 1
    assert bad_index in ctl.unanswered
    assert all(len(r.position) == 7 and max(abs(v) for v in r.position) < 3 for r in ctl.replies if r.position)


@pytest.mark.parametrize(
    "bad, reason",
    [
        (dict(safety=2), EndReason.SAFETY_STOP),
        (dict(drive=1), EndReason.DRIVES_OFF),
        (dict(quality=0), EndReason.QUALITY_POOR),
        (dict(state=MR), EndReason.LEFT_COMMANDING),
        (dict(state=IDLE), EndReason.IDLE),
        (dict(send_period=2), EndReason.PERIOD_CHANGED),
    ],
)
def test_robot_side_events_end_the_session_at_once(bad, reason):
    player = TrajectoryPlayer(min_jerk(60), LIM, period_s=1e-3)
    script = preamble() + [Cycle(state=CA)] * 20 + [Cycle(**{"state": CA, **bad})] + [Cycle(state=CA)] * 5
    res, ctl, _, err = run(script, player)
    assert err is None and res.outcome is Outcome.STOPPED and res.reason is reason
    # the event's message gets no command (an IDLE message expects none: the next one goes unanswered)
    assert ctl.unanswered == [len(preamble()) + 20 + (reason is EndReason.IDLE)]


@pytest.mark.heavy
def test_interrupt_mid_motion_is_a_jerk_limited_braking_stop(tmp_path):
    n = 600
    traj = fast_ramp(n)
    assert_within_limits(traj, 1e-3)
    player = TrajectoryPlayer(traj, LIM, period_s=1e-3)
    at = len(preamble()) + 400

    def on_cycle(i, app):
        if i == at:
            app.interrupt(EndReason.SIGTERM)

    script = preamble() + [Cycle(state=CA)] * (n + 500)
    res, ctl, log_path, err = run(script, player, tmp_path=tmp_path, on_cycle=on_cycle)
    assert err is None and res.outcome is Outcome.INTERRUPTED and res.reason is EndReason.SIGTERM
    q = sent_positions(ctl)
    assert_within_limits(q, 1e-3, before=np.array([Q0, Q0]))
    assert res.braking_cycles > 50  # 0.73 of the velocity limit takes time to stop
    v_end = np.abs(q[-1] - q[-2]) / 1e-3
    assert np.all(v_end < 1e-9)  # at rest when the session ends
    jerk = np.abs(np.diff(q, 3, axis=0)) / 1e-9
    assert np.all(jerk[-res.braking_cycles :] <= LIM.jerk * 1.01)
    tab = read_log(log_path)
    assert (tab.column("phase") == Phase.BRAKE).sum() == res.braking_cycles


@pytest.mark.heavy
def test_guard_refusal_mid_motion_brakes_instead_of_sending_the_jump():
    n = 500
    traj = fast_ramp(n, speed=0.5)
    traj[350:, 3] += 0.05  # a jump the robot cannot follow
    player = TrajectoryPlayer(traj, LIM, period_s=1e-3)
    script = preamble() + [Cycle(state=CA)] * (n + 500)
    res, ctl, _, err = run(script, player)
    assert err is None and res.outcome is Outcome.REFUSED and res.reason is EndReason.GUARD
    assert "A4" in res.detail and "velocity" in res.detail
    q = sent_positions(ctl)
    np.testing.assert_array_equal(q[:350], traj[:350])
    assert_within_limits(q, 1e-3, before=np.array([Q0, Q0]))
    assert res.braking_cycles > 20


def test_oscillating_rows_are_refused_by_the_second_difference():
    n = 60
    traj = np.repeat(np.array(Q0)[None], n, axis=0)
    traj[10:, 0] += 0.95 * LIM.velocity[0] * 1e-3 * (np.arange(n - 10) % 2)  # ±0.95 of the velocity step
    player = TrajectoryPlayer(traj, LIM, period_s=1e-3)
    res, ctl, _, err = run(preamble() + [Cycle(state=CA)] * (n + 50), player)
    assert err is None and res.reason is EndReason.GUARD and "acceleration" in res.detail
    assert_within_limits(sent_positions(ctl), 1e-3, before=np.array([Q0, Q0]))


def test_client_error_and_stop_session_end_cleanly():
    class Faulty(LBRClient):
        def __init__(self):
            self.n = 0

        def command(self, state):
            self.n += 1
            if self.n == 5:
                raise ZeroDivisionError("boom")
            return super().command(state)

    res, ctl, _, err = run(preamble() + [Cycle(state=CA)] * 30, Faulty())
    assert err is None and res.outcome is Outcome.FAILED and res.reason is EndReason.CLIENT_ERROR
    assert "ZeroDivisionError" in res.detail

    class Done(LBRClient):
        def monitor(self, state):
            raise StopSession("nothing to do", completed=True)

    res, ctl, _, err = run(preamble() + [Cycle(state=CA)] * 5, Done())
    assert err is None and res.outcome is Outcome.COMPLETED and res.answered == 0  # ended before any reply


def test_far_start_is_refused_before_anything_is_sent():
    traj = min_jerk(30) + 0.01
    player = TrajectoryPlayer(traj, LIM, period_s=1e-3, start_tolerance=1e-3)
    res, ctl, _, err = run(preamble() + [Cycle(state=CA)] * 40, player)
    assert err is None and res.outcome is Outcome.REFUSED and res.reason is EndReason.CLIENT_REFUSED
    assert "TrajectoryPlayer.move_to_start" in res.detail and ctl.replies == [] and res.answered == 0


@pytest.mark.heavy
def test_move_to_start_is_jerk_limited_then_streams_the_file():
    traj = min_jerk(30) + np.array([0, 0, 0, 0.02, 0, 0, 0])
    player = TrajectoryPlayer(traj, LIM, period_s=1e-3, move_to_start=True)
    res, ctl, _, err = run(preamble() + [Cycle(state=CA)] * 2000, player)
    assert err is None and res.outcome is Outcome.COMPLETED and player.move_rows > 10
    q = sent_positions(ctl)
    assert_within_limits(q, 1e-3, before=np.array([Q0, Q0]))
    np.testing.assert_array_equal(q[player.move_rows : player.move_rows + 30], traj)
    v = np.abs(np.diff(q[: player.move_rows + 1], axis=0)) / 1e-3
    assert np.all(v <= 0.2 * LIM.velocity * 1.001)  # the move runs at ≤ 20 % of the limits


def test_a_small_start_offset_is_closed_by_a_move_never_a_jump():
    traj = min_jerk(30) + 5e-4  # within --start-tolerance 1e-3, but 0.5 rad/s as one step
    player = TrajectoryPlayer(traj, LIM, period_s=1e-3)
    res, ctl, _, err = run(preamble() + [Cycle(state=CA)] * 400, player)
    assert err is None and res.outcome is Outcome.COMPLETED and player.move_rows > 0
    assert_within_limits(sent_positions(ctl), 1e-3, before=np.array([Q0, Q0]))


# -- connecting ------------------------------------------------------------------------------------------------
def test_no_message_times_out_naming_the_cause():
    app = ClientApplication(LBRClient(), "127.0.0.1", 0, bind_host="127.0.0.1", first_message_timeout_s=0.3)
    with app:
        t0 = time.monotonic()
        with pytest.raises(FriTimeout, match="no FRI monitoring message"):
            app.run()
        assert time.monotonic() - t0 < 1.0


@pytest.mark.parametrize("catch_up", [True, False])
def test_a_client_behind_answers_the_newest_message_waiting_and_counts_the_older_as_missed(catch_up):
    from lbrcli.fri.codec import FriCodec

    ctl = ScriptedController(0, [], Q0)  # (for its messages, sent here by hand)
    ctl.sock.settimeout(2.0)
    app = ClientApplication(LBRClient(), "127.0.0.1", 0, bind_host="127.0.0.1", version="1.15", catch_up=catch_up)

    def send(*seqs: int) -> int:  # the reflected counter of the reply to the next step
        for seq in seqs:
            ctl.sock.sendto(ctl._message(Cycle(state=MW, quality=1), seq, 0), ("127.0.0.1", app.port))
        time.sleep(0.05)  # (loopback delivers at once; a margin for a loaded machine)
        assert app.step()
        return FriCodec("1.15").decode_command(ctl.sock.recv(4096)).header.reflectedSequenceCounter

    with app:
        app.start()
        assert send(0) == 0
        # four messages arrived while the client was stalled: caught up, the newest is answered and the three
        # before it are missed (the controller bridged them); else the oldest, each in turn
        assert send(1, 2, 3, 4) == (4 if catch_up else 1)
        assert app.answered == 2 and app.missed == app.transport.overtaken == (3 if catch_up else 0)
    ctl.sock.close()
    ctl.foreign_sock.close()


@pytest.mark.heavy
def test_wait_is_honoured_while_garbage_keeps_arriving():
    import socket
    import threading

    app = ClientApplication(LBRClient(), "127.0.0.1", 0, bind_host="127.0.0.1", first_message_timeout_s=0.5)
    app.connect()
    stop = threading.Event()

    def spam():
        s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        while not stop.is_set():
            s.sendto(b"\x07not fri at all", ("127.0.0.1", app.port))
            time.sleep(0.0005)
        s.close()

    th = threading.Thread(target=spam, daemon=True)
    th.start()
    t0 = time.monotonic()
    try:
        with pytest.raises(FriTimeout, match="did not decode"):
            app.run()
    finally:
        stop.set()
        th.join()
        app.close()
    assert time.monotonic() - t0 < 0.5 + 0.5


@pytest.mark.heavy
@pytest.mark.parametrize("version", ["1.15", "2.7"])
def test_version_is_detected_from_the_first_datagram(version):
    res, ctl, _, err = run(preamble() + [Cycle(state=CA)] * 5, LBRClient(), version=version, detect=True, duration=0.05)
    assert err is None and res.version == version and res.malformed == 0


def test_a_log_that_cannot_be_written_brakes_and_ends(tmp_path):
    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full on this system")
    n = 500
    traj = fast_ramp(n, speed=0.5)
    player = TrajectoryPlayer(traj, LIM, period_s=1e-3)
    log = ExecutionLog("/dev/full")

    res, ctl, _, err = run(preamble() + [Cycle(state=CA)] * (n + 300), player, observers=[LogObserver(log)])
    assert err is None and res.outcome is Outcome.FAILED and res.reason is EndReason.OBSERVER_FAILED
    assert "log" in res.detail


class _Memory:
    """The transport's interface over a scripted controller's messages built on demand (reflecting our last reply
    as a controller that received it); the replies are kept."""

    def __init__(self, ctl: ScriptedController) -> None:
        self.ctl, self.i, self.sent, self.port, self.robot_ip, self.foreign, self.warm = (
            ctl,
            0,
            [],
            0,
            "127.0.0.1",
            0,
            None,
        )

    def receive(self) -> bytes | None:
        if self.i >= len(self.ctl.script):
            return None
        c = self.ctl.script[self.i]
        self.ctl.clock_ns = self.i * 1_000_000  # [ns] the controller's clock at 1 ms
        self.i += 1
        self.raws = getattr(self, "raws", 0) + (c.raw is not None)  # (a garbage datagram takes no sequence number)
        return c.raw if c.raw is not None else self.ctl._message(c, self.i - 1 - self.raws, max(len(self.sent) - 1, 0))

    def send(self, data: bytes) -> None:
        self.sent.append(data)

    def expect_period(self, period_s) -> None:
        pass

    def drain(self) -> int:
        return 0

    def close(self) -> None:
        pass


@pytest.mark.parametrize("version", ["1.15", "2.7"])
def test_warming_between_messages_changes_nothing(version):
    """The busy-wait's warming (the last good message decoded again into the same message, the checks run again)
    leaves the state and every reply as they were; a garbage datagram in between is not what gets warmed."""
    n = 120
    traj = np.tile(Q0, (n, 1)) + 1e-7 * np.arange(n)[:, None]  # [rad] (the scripted robot stays where it is)
    script = preamble() + [Cycle(state=CA)] * 50 + [Cycle(raw=b"\x00garbage")] + [Cycle(state=CA)] * (n + 20)
    sent, warmed = [], 0
    for warm in (False, True):
        ctl = ScriptedController(0, script, Q0, version=version)
        ctl.sock.close()
        ctl.foreign_sock.close()
        app = ClientApplication(TrajectoryPlayer(traj, LIM, period_s=1e-3), "127.0.0.1", 0, version=version, limits=LIM,
                                busy_wait_s=1e-4)  # fmt: skip
        app.transport = _Memory(ctl)
        app.start()
        last_good = None
        while app.step():
            if warm and app.transport.warm is not None:
                mon = app.state.message
                if mon.IsInitialized():  # a message as decoded: warming keeps it as it is
                    before = (mon.SerializeToString(), app.state.measured_joint_position, app.state.session_state)
                    app.transport.warm()
                    assert (
                        mon.SerializeToString(),
                        app.state.measured_joint_position,
                        app.state.session_state,
                    ) == before
                    last_good = before[0]
                else:  # what the garbage left: warming restores the last good message
                    app.transport.warm()
                    assert mon.SerializeToString() == last_good
                warmed += 1
        assert app.result.outcome is Outcome.COMPLETED and app.result.malformed == 1, app.result.detail
        assert app.result.prepared_replies > n - 10
        sent.append(app.transport.sent)
    assert warmed > n and sent[0] == sent[1] and len(sent[0]) > n


@pytest.mark.parametrize("paced_by_replies", [False, True])
def test_a_controller_that_sends_faster_than_its_clock_says_is_stopped_unless_paced_by_replies(paced_by_replies):
    """Its timestamps step 5 ms per message but its messages come as fast as we answer (well under 5 ms apart): a
    controller does not do that, and the kernel's receive times show it; a simulator in lock-step does, on purpose."""
    if not sys.platform.startswith("linux"):
        pytest.skip("receive time stamps: Linux")
    app = ClientApplication(LBRClient(), "127.0.0.1", 0, bind_host="127.0.0.1", version="1.15",
                            first_message_timeout_s=10, silence_timeout_s=3, paced_by_replies=paced_by_replies)  # fmt: skip
    app.connect()
    script = [Cycle(state=MW, quality=1, send_period=5)] * 60 + [Cycle(state=IDLE)]
    ctl = ScriptedController(app.port, script, tuple(Q0), pace_s=0.0).start()
    try:
        res = app.run()
    finally:
        ctl.finish(app)
    if paced_by_replies:
        assert res.reason is not EndReason.SUPERVISION, res.detail
        assert res.cycles >= 60
    else:
        assert res.reason is EndReason.SUPERVISION and "messages advanced" in res.detail, res.detail
        assert res.cycles < 30
