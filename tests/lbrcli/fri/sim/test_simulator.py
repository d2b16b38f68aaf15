"""The FRI controller simulator over real loopback UDP, driven by a small scripted client.

Sessions are short (≤ ~1 s at a 2–4 ms period) and the assertions are about what happened (states, counters,
positions, the ball), never about how fast: the machine may be loaded.
"""

from __future__ import annotations

import socket

import numpy as np
import pytest

from lbrcli.fri.codec import FriCodec
from lbrcli.fri.constants import COMMAND_MESSAGE_ID, MONITORING_MESSAGE_ID, SessionState
from lbrcli.fri.sim import SimConfig, SimulatorProcess
from lbrcli.plants import BALL_IO_NAMES, default_plants
from trajectories.errors import FriError, OptionError

from tests.helpers.scripted_client import ScriptedClient
from tests.helpers.sim import assert_sequence, TEST_DEFAULTS

MW, MR, CW, CA, IDLE = (
    int(s)
    for s in (
        SessionState.MONITORING_WAIT,
        SessionState.MONITORING_READY,
        SessionState.COMMANDING_WAIT,
        SessionState.COMMANDING_ACTIVE,
        SessionState.IDLE,
    )
)
# the simulator waits for each reply the client owes (on the period's grid): what these tests judge does not change
# with this machine's load; the tests of the timing rules themselves run in real time (REAL_TIME)
LOCKSTEP = dict(lockstep_timeout_s=2.0)
REAL_TIME = dict(lockstep_timeout_s=None)


def run_session(version="1.15", policy=None, multiplier=1, before=None, answer=None, client_timeout=8.0, **cfg):
    """Start the simulator for a scripted client, run the session, return (client run, sim stats, config)."""
    client = ScriptedClient(version)
    config = SimConfig(
        client_port=client.port, version=version, receive_multiplier=multiplier, **{**TEST_DEFAULTS, **LOCKSTEP, **cfg}
    )
    try:
        with SimulatorProcess(config) as sim:
            if before is not None:
                before(sim.address)
            run = client.run(policy, multiplier=multiplier, timeout=client_timeout, answer_monitoring=answer)
            stats = sim.wait(10.0) or sim.stop()
    finally:
        client.close()
    return run, stats, config


@pytest.mark.heavy
@pytest.mark.parametrize("version", ["1.15", "2.7"])
def test_state_sequence_and_counters(version):
    run, stats, cfg = run_session(version, session_duration_s=0.3)
    assert_sequence(run.states)
    assert run.states[-2] == MR  # the app ended the overlay: back to monitoring (READY), then IDLE
    assert stats.states_seen == tuple(run.states)
    assert stats.end_reason == "duration"
    # the controller's counter: 0, 1, 2, ... with no gaps on loopback
    seqs = [r.seq for r in run.received]
    assert seqs == list(range(len(seqs)))
    # it reflects our counters: only values we sent, never decreasing, and in the end our last ones
    reflected = [r.reflected for r in run.received]
    sent = set(run.sent_seq)
    assert all(x in sent for x in reflected[1:] if x != 0) and np.all(np.diff(reflected) >= 0)
    assert reflected[-1] >= run.sent_seq[-1] - 2
    # our counters arrived without gaps, every reply was counted
    assert stats.client_sequence_gaps == 0
    assert len(run.sent_seq) - 2 <= stats.replies <= len(run.sent_seq)
    assert stats.malformed_received == 0 and stats.foreign_received == 0 and not stats.safety_stop
    # the static content of the messages
    r = run.where(CA)[0]
    assert (r.send_period, r.multiplier, r.mode, r.overlay) == (cfg.period_ms, 1, 1, 1)
    assert r.drives == (2,) * 7 and r.safety == 0
    assert all(x.tracking == 0.0 for x in run.received if x.state != CA)
    assert all(x.tracking == 1.0 for x in run.where(CA))  # holding still is tracked perfectly
    assert np.allclose(run.received[0].msr_q, cfg.q0) and np.allclose(run.where(CA)[-1].msr_q, cfg.q0)
    stamps = [s + ns * 1e-9 for s, ns in (x.stamp for x in run.received)]
    assert stamps[0] > 1.6e9 and np.all(np.diff(stamps) > 0)
    assert stats.commanded_rows > 0.5 * len(run.where(CA))
    assert stats.reply_latency_ms_p50 is not None and stats.period_ms_p50 is not None


@pytest.mark.heavy
def test_measured_torques_are_the_inverse_dynamics(robot):
    run, stats, cfg = run_session(session_duration_s=0.1)
    r = run.where(CA)[-1]
    tau = robot.inverse_dynamics(r.msr_q, np.zeros(7), np.zeros(7))
    assert np.allclose(r.msr_tau, tau, atol=1e-9)
    assert abs(r.msr_tau[1]) > 1.0  # gravity loads the shoulder


@pytest.mark.heavy
def test_receive_multiplier_is_honoured_and_commands_are_fine_interpolated():
    ramp = 4e-4  # [rad] per cycle on A7 (0.05 rad/s at 8 ms)

    def policy(k, q0):
        q = q0.copy()
        q[6] += ramp * max(0, k - 5)
        return q

    # a longer period: with k = 3 one late reply costs three cycles of the quality window
    run, stats, _ = run_session(policy=policy, multiplier=3, period_ms=8, session_duration_s=0.5)
    assert all(r.multiplier == 3 for r in run.received)
    assert CA in run.states and stats.end_reason == "duration"
    active = run.where(CA)
    assert 0.2 * len(active) <= stats.commanded_rows <= 0.5 * len(active)
    # between commands the controller interpolates: A7 moves every cycle, not in steps of three
    dq = np.diff([r.msr_q[6] for r in active[len(active) // 2 :]])
    assert np.all(dq > 0.2 * ramp)
    assert np.median(dq) == pytest.approx(ramp, rel=0.2)


@pytest.mark.heavy
def test_falls_back_to_monitoring_when_replies_stop():
    silent = []

    def policy(k, q0):
        if k >= 40:
            silent.append(k)  # from here on the client stops answering altogether
            return None
        return q0

    run, stats, _ = run_session(policy=policy, answer=lambda r: not silent, **REAL_TIME)
    states = run.states
    i = states.index(CA)
    assert states[i + 1 :] == [MW, IDLE]
    assert stats.end_reason == "quality"
    assert stats.missed_replies >= 3 and stats.untimely_active_cycles >= 3  # the quality rule saw them in commanding
    after = [r for r in run.received if r.state == MW and r.seq > run.where(CA)[-1].seq]
    assert after and after[-1].quality <= 1  # POOR or FAIR
    assert all(r.tracking == 0.0 for r in after)


def test_a_session_dropped_for_quality_says_so_when_the_simulator_is_stopped_afterwards():
    """The client gives up after the drop and stops the simulator before its IDLE: the statistics keep the session's
    own end ("quality", what a user's error message explains), not only "stopped"."""
    silent = []

    def policy(k, q0):
        if k >= 40:
            silent.append(k)
            return None
        return q0

    client = ScriptedClient("1.15")
    config = SimConfig(client_port=client.port, **{**TEST_DEFAULTS, "end_delay_s": 30.0})  # no IDLE on its own
    try:
        with SimulatorProcess(config) as sim:
            run = client.run(policy, timeout=1.5, answer_monitoring=lambda r: not silent)
            stats = sim.stop()
    finally:
        client.close()
    assert CA in run.states and run.states[-1] == MW  # dropped, then stopped before the simulator's IDLE
    assert stats.end_reason == "quality"


@pytest.mark.heavy
def test_safety_stop_on_a_command_outside_the_position_limits(limits):
    def policy(k, q0):
        q = q0.copy()
        if k >= 20:
            q[0] = limits.position[0] + 0.01  # just beyond A1's limit
        return q

    run, stats, _ = run_session(policy=policy, session_duration_s=1.0)
    assert stats.safety_stop and stats.end_reason == "safety_stop"
    i = run.states.index(CA)
    assert run.states[i + 1] in (MR, MW) and run.states[-1] == IDLE
    stopped = [r for r in run.received if r.safety == 2]  # SAFETY_STOP_LEVEL_1
    assert stopped and all(r.state != CA for r in stopped[1:])
    assert stopped[-1].drives == (0,) * 7  # stop category 1: drives off once stopped
    assert max(abs(r.msr_q[0]) for r in run.received) < limits.position[0]


@pytest.mark.heavy
def test_a_reply_without_joint_positions_in_commanding_active_ends_the_overlay():
    """KUKA's LBRClient sets the joint positions in every COMMANDING_ACTIVE cycle; a reply without them is an error:
    the overlay ends, the robot stops where it is (drives on), the session goes back to monitoring and closes."""

    def policy(k, q0):
        return () if k >= 20 else q0 + 1e-3 * k  # a slow move, then replies with the header only

    run, stats, _ = run_session(policy=policy, session_duration_s=2.0)
    assert stats.end_reason == "command_missing" and stats.commands_without_position >= 1
    assert not stats.safety_stop
    i = run.states.index(CA)
    assert run.states[i + 1] in (MR, MW) and run.states[-1] == IDLE
    active = run.where(CA)
    assert 20 <= len(active) < 60  # it ended within a few cycles of the first reply without positions
    after = [r for r in run.received if r.seq > active[-1].seq]
    assert after and all(r.drives == (2,) * 7 for r in after)  # stopped, drives on (not a safety stop)


@pytest.mark.heavy
def test_header_only_replies_in_the_monitoring_states_are_the_protocol():
    run, stats, _ = run_session(session_duration_s=0.2)
    assert stats.end_reason == "duration" and stats.commands_without_position == 0


@pytest.mark.heavy
def test_clipping_lowers_the_tracking_performance(limits):
    step = 0.2  # [rad] on A4, far beyond what one cycle allows

    def policy(k, q0):
        q = q0.copy()
        if k >= 10:
            q[3] += step
        return q

    run, stats, cfg = run_session(policy=policy, session_duration_s=0.6)
    active = run.where(CA)
    tracking = np.array([r.tracking for r in active])
    assert np.all(tracking[:10] == 1.0)
    assert tracking.min() < 0.5 and stats.min_tracking_performance == pytest.approx(tracking.min())
    assert tracking[-1] == 1.0  # the target was reached in the end
    q4 = np.array([r.msr_q[3] for r in active])
    h = cfg.period_ms * 1e-3
    v = np.diff(q4) / h
    assert np.abs(v).max() <= limits.velocity[3] * (1 + 1e-6)
    assert np.abs(np.diff(v) / h).max() <= limits.acceleration[3] * (1 + 1e-6)
    assert q4[-1] == pytest.approx(cfg.q0[3] + step, abs=1e-9)
    # PositionHold: the ipo position stays where the robot stood when the overlay started
    assert all(np.array_equal(r.ipo_q, cfg.q0) for r in run.received if r.state in (CW, CA))


@pytest.mark.heavy
def test_ball_hangs_still_without_motion():
    run, stats, _ = run_session(session_duration_s=0.2, plants=default_plants(0.5))
    assert stats.max_ball_theta is not None and stats.max_ball_theta < 1e-12
    assert all(set(r.io) == set(BALL_IO_NAMES) for r in run.received)
    assert max(abs(r.io["ball_theta_x"]) for r in run.received) < 1e-12


@pytest.mark.heavy
def test_ball_swings_after_a_jerk_of_the_flange_as_the_pendulum_model_predicts(robot):
    from planners.string_model import StringModel
    from planners.string_sim import PivotMotion, simulate_string

    n_move = 120  # cycles of a smooth 0.25 rad turn of A1 (0.48 s), then hold

    def policy(k, q0):
        s = min(max(k - 5, 0) / n_move, 1.0)
        q = q0.copy()
        q[0] += 0.25 * (10 * s**3 - 15 * s**4 + 6 * s**5)
        return q

    length = 0.45
    run, stats, cfg = run_session(policy=policy, session_duration_s=0.8, plants=default_plants(length))
    assert stats.max_ball_theta > 0.05
    rec = run.received[:-1]  # without the IDLE message
    assert [r.seq for r in rec] == list(range(len(rec)))
    # still swinging after the robot stopped (no damping)
    still = [r for r in run.where(CA)[-40:]]
    assert max(r.io["ball_theta"] for r in still) > 0.02
    # the simulator's ball agrees with the offline model driven by the executed TCP path
    h = cfg.period_ms * 1e-3
    q = np.array([r.msr_q for r in rec])
    t = np.arange(len(q)) * h
    pos, _ = robot.fk_path(q)
    ref = simulate_string(
        StringModel(length, cup=None), PivotMotion(t, pos), float(t[-1])
    )  # the same model, event-driven
    d = ref.string_direction
    m = len(q) - 3
    sim_tx = np.array([r.io["ball_theta_x"] for r in rec[1 : m + 1]])  # message k carries the ball at t[k−1]
    sim_ty = np.array([r.io["ball_theta_y"] for r in rec[1 : m + 1]])
    assert np.abs(sim_tx - np.arctan2(d[:m, 0], -d[:m, 2])).max() < 1e-4
    assert np.abs(sim_ty - ref.theta_y[:m]).max() < 1e-4
    sim_theta = np.array([r.io["ball_theta"] for r in rec[1 : m + 1]])
    assert np.abs(sim_theta - ref.theta[:m]).max() < 1e-4
    sim_ball = np.array([[r.io[f"ball_{c}"] for c in "xyz"] for r in rec[1 : m + 1]])
    assert np.abs(sim_ball - ref.position[:m]).max() < 1e-4  # [m]
    assert {r.io["ball_phase"] for r in rec[1 : m + 1]} == {0.0}  # taut throughout


@pytest.mark.heavy
def test_loss_injection_is_counted_and_bridged():
    run, stats, _ = run_session(loss=0.04, seed=3, session_duration_s=0.4)
    assert CA in run.states
    received = run.received
    missing = received[-1].seq + 1 - len(received)  # controller counters the client never saw
    assert missing > 0
    assert missing <= stats.lost_sent <= missing + 2  # (+ IDLE messages lost after the client left)
    assert stats.missed_replies >= missing - 2


@pytest.mark.heavy
def test_malformed_injection_is_counted():
    run, stats, _ = run_session(malformed=0.04, seed=5, session_duration_s=0.4)
    assert CA in run.states
    assert run.undecodable > 0
    assert run.undecodable <= stats.malformed_sent <= run.undecodable + 2
    received = run.received
    assert received[-1].seq + 1 - len(received) == run.undecodable  # every corrupted message still took a counter


@pytest.mark.heavy
def test_delays_within_the_period_are_tolerated():
    # in lock-step: the delay line delivers every message and the session runs its course; whether a loaded machine
    # still answers in time is a question for the benchmarks
    run, stats, _ = run_session(period_ms=4, delay_ms=0.5, jitter_ms=1.0, session_duration_s=0.3)
    assert_sequence(run.states)
    assert stats.end_reason == "duration"
    assert stats.reply_latency_ms_p50 >= 0.0


@pytest.mark.heavy
def test_replies_later_than_the_next_send_keep_the_session_in_monitoring_wait():
    run, stats, _ = run_session(delay_ms=6.0, max_runtime_s=0.6, client_timeout=0.8, **REAL_TIME)
    assert stats.states_seen == (MW, IDLE)  # the timeout closes the session
    assert stats.end_reason == "max_runtime"
    # most are late (a loaded machine may stretch a simulator cycle beyond the delay now and then)
    assert stats.replies > 30 and stats.late_replies >= 0.8 * stats.replies
    assert all(r.quality == 0 for r in run.received)


@pytest.mark.heavy
def test_foreign_and_malformed_datagrams_are_counted_and_ignored():
    counts = {}

    def send_foreign(address):
        c115, c27 = FriCodec("1.15"), FriCodec("2.7")
        cmd = c115.new_command()
        cmd.header.messageIdentifier, cmd.header.sequenceCounter, cmd.header.reflectedSequenceCounter = (
            COMMAND_MESSAGE_ID,
            99,
            0,
        )
        cmd.commandData.jointPosition.value.extend([3.0] * 7)  # would be a safety stop if it were accepted
        mon = c115.new_monitoring()
        mon.header.messageIdentifier, mon.header.sequenceCounter, mon.header.reflectedSequenceCounter = (
            MONITORING_MESSAGE_ID,
            1,
            2,
        )
        cmd27 = c27.new_command()
        cmd27.header.messageIdentifier, cmd27.header.sequenceCounter, cmd27.header.reflectedSequenceCounter = (
            COMMAND_MESSAGE_ID,
            1,
            2,
        )
        local = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        local.bind(("127.0.0.1", 0))
        sends = (
            [(local, c115.encode(mon))] * 2
            + [(local, b"\xff" * n) for n in (1, 10, 100)]
            + [(local, c27.encode(cmd27)), (local, b"")]
        )
        foreign_host = 0
        other = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            other.bind(("127.0.0.2", 0))
            sends += [(other, c115.encode(cmd))] * 3
            foreign_host = 3
        except OSError:
            pass
        for sock, data in sends:
            sock.sendto(data, address)
        local.close()
        other.close()
        counts.update(foreign=2 + foreign_host, malformed=5)

    # in lock-step: the quality rule is not what is tested here, and a loaded machine dropped the session to
    # MONITORING_WAIT once (the counts held)
    run, stats, _ = run_session(before=send_foreign, session_duration_s=0.2)
    assert stats.foreign_received == counts["foreign"]
    assert stats.malformed_received == counts["malformed"]
    assert_sequence(run.states)
    assert not stats.safety_stop and stats.client_sequence_gaps == 0


def test_stop_without_a_client():
    silent = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    silent.bind(("127.0.0.1", 0))
    cfg = SimConfig(client_port=silent.getsockname()[1], period_ms=2)
    silent.settimeout(30.0)
    try:
        with SimulatorProcess(cfg) as sim:
            first = [silent.recvfrom(2048)[0] for _ in range(25)]  # 25 cycles sent (however slowly a loaded PC runs)
            assert sim.wait(0.1) is None  # nobody answers: the session does not end by itself
            stats = sim.stop()
    finally:
        silent.close()
    m = FriCodec("1.15").decode_monitoring(first[0])
    assert m.header.sequenceCounter == 0 and m.connectionInfo.sessionState == MW
    assert stats.end_reason == "stopped" and stats.states_seen == (MW, IDLE)  # stop() closes the session
    assert stats.cycles >= 25 and stats.replies == 0 and stats.missed_replies == 0


def test_bad_configuration_is_refused():
    with pytest.raises(OptionError, match="SimConfig.period_ms"):  # the field (a command names its option)
        SimulatorProcess(SimConfig(period_ms=0)).start()
    with pytest.raises(OptionError, match="SimConfig.loss"):
        SimConfig(loss=1.5).validate()
    with pytest.raises(OptionError, match="SimConfig.version"):
        SimConfig(version="3.0").validate()
    with pytest.raises(OptionError, match="SimConfig.q0"):
        SimConfig(q0=(0.0,) * 6).validate()
    taken = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    taken.bind(("127.0.0.1", 0))
    try:
        with pytest.raises(FriError, match="cannot bind"):
            SimulatorProcess(SimConfig(port=taken.getsockname()[1])).start()
    finally:
        taken.close()


@pytest.mark.heavy
def test_lbr_sim_command_runs_a_session_and_reports_json():
    import json
    import subprocess
    import sys

    client = ScriptedClient("2.7")
    try:
        proc = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "lbrcli",
                "sim",
                "--client",
                f"127.0.0.1:{client.port}",
                "--period",
                "5",
                "--quality-window",
                "25",
                "--quality-good",
                "0.75",
                "--duration",
                "0.2",
                "--commanding-after",
                "0.05",
                "--fri-version",
                "2.7",
                "--length",
                "0.4",
                "--q0",
                "0,10deg,0,-80deg,0,30deg,0",
                "--timeout",
                "20",
                "--json",
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        run = client.run(timeout=30.0)
        out, err = proc.communicate(timeout=30)
    finally:
        client.close()
    assert proc.returncode == 0, err
    figures = json.loads(out)
    assert figures["states_seen"][:1] == ["MONITORING_WAIT"] and figures["states_seen"][-1] == "IDLE"
    assert "COMMANDING_ACTIVE" in figures["states_seen"] and figures["end_reason"] == "duration"
    assert figures["fri_version"] == "2.7" and figures["max_ball_theta"] == 0.0
    assert figures["replies"] == pytest.approx(len(run.sent_seq), abs=2)
    assert np.allclose(run.received[0].msr_q, np.radians([0, 10, 0, -80, 0, 30, 0]))
    assert "COMMANDING_ACTIVE" in err  # the states as they change, on stderr with --json


@pytest.mark.heavy
@pytest.mark.parametrize(
    "args, message",
    [
        (["--period", "0"], "--period"),
        (["--period", "101"], "--period"),
        (["--client", "nohost"], "--client"),
        (["--client", "127.0.0.1:x"], "--client"),
        (["--q0", "1,2,3"], "--q0"),
        (["--q0", "3,0,0,0,0,0,0"], "--q0"),
        (["--fri-version", "3"], "--fri-version"),
        (["--loss", "2"], "--loss"),
        (["--length", "-1"], "--length"),
        (["--operation-mode", "T9"], "--operation-mode"),
        (["--quality-good", "1.5"], "quality"),
        (["--mode", "speed"], "--mode"),
        (["--io", "X:float:in"], "--io"),
        (["--io", "X:analog"], "--io"),
        (["--io", "X:analog:out", "--io", "X:digital:in"], "--io"),
        (["--io-preset", "nope"], "--io-preset"),
        (["--external-force", "1,2"], "--external-force"),
        (["--stiffness", "0"], "--stiffness"),
        (["--pendulum-pty"], "needs a simulated ball"),
    ],
)
def test_lbr_sim_bad_options_exit_2_with_one_line(lbr, args, message):
    res = lbr("sim", *args, "--timeout", "0.1")
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("lbr: error:") and message in lines[0]
