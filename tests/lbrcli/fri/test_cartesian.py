"""FRI 2.7 CARTESIAN_POSE and transformation requests: pose conversions, the pose solver (IK with A3 at E1), the
simulated controller executing and refusing poses, the client application guarding Cartesian commands in joint
space (a refusal or an interrupt brakes within the joint limits) and the TransformationClient."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from lbrcli.fri import ClientApplication, LBRClient, TransformationClient
from lbrcli.fri.cartesian import PoseSolver, pose_matrix, pose_to_wire, wire_to_pose
from lbrcli.fri.codec import FriCodec
from lbrcli.fri import EndReason
from lbrcli.fri.constants import COMMAND_MESSAGE_ID
from lbrcli.fri.sim import THESIS_Q0, SimConfig, SimulatorProcess, lenient_quality
from lbrcli.fri.sim.controller import Controller

from tests.helpers.cli import run_in_process
from lbrcli.fri.testing.dh import pose_error
from lbrcli.fri.testing.relay import Relay

CW, CA = 3, 4
CODEC = FriCodec("2.7")


def test_pose_forms_and_wire_round_trip():
    rng = np.random.default_rng(3)
    for _ in range(20):
        m = pin.SE3.Random()
        m.translation = rng.uniform(-1, 1, 3)
        wire = pose_to_wire(m.translation, m.rotation)
        assert wire[3] >= 0.0 and np.allclose(np.array(wire[:3]) * 1e-3, m.translation)
        p, r = wire_to_pose(wire)
        assert np.allclose(p, m.translation) and np.allclose(r, m.rotation, atol=1e-12)
        h = m.homogeneous
        for form in (h, h[:3], h[:3].ravel(), [*m.translation, *wire[3:]]):
            assert np.allclose(pose_matrix(form), h, atol=1e-12)
    for bad in ([0.0] * 6, np.eye(3), np.diag([1.0, 1.0, -1.0, 1.0]), [0, 0, 0, 0, 0, 0, 0.0], [np.nan] * 12):
        with pytest.raises(ValueError):
            pose_matrix(bad)


@pytest.fixture(scope="module")
def solver():
    from trajectories.limits import default_limits
    from trajectories.robot import Robot

    return PoseSolver(Robot(), default_limits(), 0.001)


def test_pose_solver_recovers_joints_with_a3_at_e1(solver):
    rng = np.random.default_rng(7)
    q0 = np.array(THESIS_Q0)
    for _ in range(10):
        q = q0 + rng.uniform(-0.01, 0.01, 7)  # within one jump of the seed
        p, r = solver.tcp(q)
        sol = solver.solve(q0, p, r, q[2])
        assert sol.problem is None and np.abs(sol.q - q).max() < 1e-5 and sol.q[2] == q[2]
        assert sol.position_error < 1e-6


def test_pose_solver_refuses_unreachable_jumps_and_bad_e1(solver):
    q0 = np.array(THESIS_Q0)
    p, r = solver.tcp(q0)
    assert "unreachable" in solver.solve(q0, p + [1.5, 0, 0], r, 0.0).problem
    assert "jumps" in solver.solve(q0, p + [0.05, 0, 0], r, 0.0).problem  # 5 cm in one 1 ms command
    assert "E1" in solver.solve(q0, p, r, 3.0).problem


# -- the simulated controller, driven cycle by cycle ------------------------------------------------------------
def drive(ctl: Controller, answer, cycles: int):
    """Run ``cycles`` cycles; ``answer(mon, k)`` returns the command message (or None) for each message."""
    msgs = []
    for k in range(cycles):
        mon = CODEC.decode_monitoring(ctl.cycle(k * ctl.period))
        msgs.append(mon)
        if mon.connectionInfo.sessionState == 0 and k > 0:
            break
        cmd = answer(mon, k)
        if cmd is not None:
            cmd.header.messageIdentifier = COMMAND_MESSAGE_ID
            cmd.header.sequenceCounter = k
            cmd.header.reflectedSequenceCounter = mon.header.sequenceCounter
            ctl.on_datagram(CODEC.encode(cmd), 0.0)
    return msgs


def cartesian_answer(offset_at):
    """Mirror the ipo pose; in COMMANDING_ACTIVE add ``offset_at(n)`` [mm] to it (None: send no pose)."""
    n = [0]

    def answer(mon, k):
        cmd = CODEC.new_command()
        state = mon.connectionInfo.sessionState
        if state in (CW, CA):
            pose = list(mon.ipoData.cartesianPose.element)
            if state == CA:
                off = offset_at(n[0])
                n[0] += 1
                if off is None:
                    return cmd
                pose[:3] = [a + b for a, b in zip(pose[:3], off)]
            cmd.commandData.cartesianPose.name = ""
            cmd.commandData.cartesianPose.element.extend(pose)
            cmd.commandData.redundancyInformation.strategy = 0
            cmd.commandData.redundancyInformation.value = mon.ipoData.redundancyInformation.value
        return cmd

    return answer


CFG = dict(
    version="2.7",
    command_mode="cartesian",
    period_ms=2,
    commanding_after_s=0.0,
    quality_window=5,
    end_delay_s=0.02,
    session_duration_s=2.0,
)


@pytest.mark.parametrize(
    "offset, reason",
    [
        (lambda n: (0.0, 0.0, 1500.0 if n > 50 else 0.0), "cartesian_refused"),
        (lambda n: None if n > 50 else (0, 0, 0), "command_missing"),
    ],
)
def test_controller_ends_the_overlay_on_a_pose_it_cannot_execute(offset, reason):
    ctl = Controller(SimConfig(**CFG))
    msgs = drive(ctl, cartesian_answer(offset), 600)
    assert ctl.machine.end_reason == reason and not ctl.safety
    assert CA in ctl.states_seen and ctl.states_seen[-1] == 0
    if reason == "cartesian_refused":
        assert "unreachable" in ctl.command_problem
    q = np.array([m.monitorData.measuredJointPosition.value for m in msgs])
    assert np.abs(q - np.array(THESIS_Q0)).max() < 1e-6  # nothing moved: the commands were the ipo pose


@pytest.mark.heavy
def test_controller_executes_poses_and_needs_a_mirror():
    ctl = Controller(SimConfig(**CFG))
    msgs = drive(ctl, cartesian_answer(lambda n: (20.0 * (1 - math.cos(n * 0.01)), 0.0, 0.0)), 1500)
    assert ctl.machine.end_reason == "duration" and ctl.counts["poses"] > 900
    active = [m for m in msgs if m.connectionInfo.sessionState == CA]
    x = np.array([m.monitorData.measuredCartesianPose.element[0] - m.ipoData.cartesianPose.element[0] for m in active])
    n = np.arange(len(x)) - 1  # the command of message n is measured in message n + 1
    assert np.abs(x[1:] - 20.0 * (1 - np.cos(n[1:] * 0.01))).max() < 1e-3 and x.max() > 39.0  # [mm]
    # a pose 5 cm off the ipo pose never mirrors: the overlay never starts
    ctl = Controller(SimConfig(**{**CFG, "session_duration_s": 0.2}))
    drive(ctl, lambda mon, k: cartesian_answer(lambda n: (0, 0, 0))(mon, k) if mon.connectionInfo.sessionState != CW
          else _offset_mirror(mon), 300)  # fmt: skip
    assert CA not in ctl.states_seen


def _offset_mirror(mon):
    cmd = CODEC.new_command()
    pose = list(mon.ipoData.cartesianPose.element)
    pose[0] += 50.0
    cmd.commandData.cartesianPose.name = ""
    cmd.commandData.cartesianPose.element.extend(pose)
    return cmd


def test_controller_requests_transformations_and_keeps_the_values():
    ctl = Controller(SimConfig(version="2.7", transformations=("PBase", "Cam")))
    mon = CODEC.decode_monitoring(ctl.cycle(0.0))
    assert [t.name for t in mon.requestedTransformations] == ["PBase", "Cam"]
    cmd = CODEC.new_command()
    cmd.header.messageIdentifier = COMMAND_MESSAGE_ID
    cmd.header.sequenceCounter = cmd.header.reflectedSequenceCounter = 0
    for name, x in (("PBase", 10.0), ("Other", 1.0), ("Cam", 20.0)):
        t = cmd.commandData.commandedTransformations.add()
        t.name = name
        t.element.extend([x, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0])
        t.timestamp.sec, t.timestamp.nanosec = 5, 500_000_000
    ctl.on_datagram(CODEC.encode(cmd), 0.0)
    fig = ctl.transforms.figures()
    assert fig["PBase"]["received"] == 1 and fig["PBase"]["last"][0] == pytest.approx(0.010)
    assert fig["Cam"]["timestamp_s"] == pytest.approx(5.5) and ctl.transforms.refused == 1


def test_cli_refuses_cartesian_and_transformations_outside_fri_27():
    for argv in (["sim", "--mode", "cartesian"], ["sim", "--transformation", "PBase"]):
        code, out, err = run_in_process(argv)
        assert code == 2 and "2.7" in err and len(err.strip().splitlines()) == 1


# -- the client application against the simulator (lock-step: independent of this machine's speed) -------------
class LineClient(LBRClient):
    """Moves the TCP along +x (raised-cosine speed up to ``speed`` [m/s]); at command ``event_at`` either jumps
    5 cm (``jump``) or asks the application to stop (``interrupt``); provides the requested frames."""

    def __init__(self, speed=0.1, event_at=None, event="jump", app=None):
        self.n, self.speed, self.event_at, self.event, self.app = 0, speed, event_at, event, app
        self.sent = []

    def command(self, state):
        p = np.array(state.ipo_cartesian_pose)
        t = self.n * state.sample_time
        ramp = 0.3  # [s]
        # [m] speed ramps up along a raised cosine over ``ramp``, then stays
        s = self.speed * (0.5 * (t - ramp / math.pi * math.sin(math.pi * t / ramp)) if t < ramp else t - ramp / 2)
        p[0] += s
        if self.n == self.event_at:
            if self.event == "jump":
                p[0] += 0.05
            else:
                self.app.interrupt()
        self.n += 1
        self.robot_command.set_cartesian_pose(p, redundancy=state.ipo_redundancy_value)
        self.sent.append(p)


class Frames(TransformationClient):
    def provide(self):
        for i, name in enumerate(self.requested_transformation_ids()):
            self.set_transformation(name, [0.1 * (i + 1), 0.0, 0.0, 1.0, 0.0, 0.0, 0.0])


def lockstep_session(client, duration=1.2, frames=None):
    app = ClientApplication(client, "127.0.0.1", 0, version="2.7", transformation_client=frames, paced_by_replies=True)
    app.connect()
    if hasattr(client, "app"):
        client.app = app
    with Relay(app.port) as relay:
        cfg = SimConfig(client_port=relay.port, version="2.7", command_mode="cartesian", period_ms=2,
                        session_duration_s=duration, commanding_after_s=0.05, lockstep_timeout_s=0.5,
                        transformations=("PBase", "Tool") if frames else (), **lenient_quality(2))  # fmt: skip
        with SimulatorProcess(cfg) as sim:
            result = app.run()
            stats = sim.wait(20.0) or sim.stop()
    app.close()
    return (
        result,
        stats,
        [CODEC.decode_monitoring(d) for d in relay.to_client],
        [CODEC.decode_command(d) for d in relay.to_sim],
    )


@pytest.mark.heavy
def test_client_cartesian_line_is_executed_and_frames_arrive():
    client = LineClient(speed=0.1)
    result, stats, mons, cmds = lockstep_session(client, frames=Frames())
    assert stats.end_reason == "duration" and stats.command_problem == "" and stats.min_tracking_performance == 1.0
    active = [m for m in mons if m.connectionInfo.sessionState == CA]
    x = np.array([m.monitorData.measuredCartesianPose.element[0] - m.ipoData.cartesianPose.element[0] for m in active])
    assert 0.1 * (1.2 - 0.15) * 1e3 * 0.95 < x.max() < 0.1 * 1.2e3  # [mm] it moved at 0.1 m/s
    sent = [c for c in cmds if len(c.commandData.cartesianPose.element) == 7]
    assert sent and all(not c.commandData.jointPosition.value for c in sent)
    # the second judge: the DH flange of the executed joints is the pose commanded one message earlier
    by_seq = {m.header.sequenceCounter: m for m in mons}
    errs = [pose_error(by_seq[c.header.reflectedSequenceCounter + 1].monitorData.measuredJointPosition.value,
                       c.commandData.cartesianPose.element)
            for c in sent if c.header.reflectedSequenceCounter + 1 in by_seq
            and by_seq[c.header.reflectedSequenceCounter].connectionInfo.sessionState == CA]  # fmt: skip
    assert len(errs) > 400 and max(e[0] for e in errs) < 1e-4 and max(e[1] for e in errs) < 1e-3
    assert stats.transformations["PBase"]["last"][0] == pytest.approx(0.1)
    assert stats.transformations["Tool"]["received"] > 400


@pytest.mark.heavy
@pytest.mark.parametrize("event", ["jump", "interrupt"])
def test_client_cartesian_stop_brakes_within_the_joint_limits(event, limits):
    client = LineClient(speed=0.15, event_at=250, event=event)
    result, stats, mons, cmds = lockstep_session(client, duration=3.0)
    want = EndReason.GUARD if event == "jump" else EndReason.SIGINT
    assert result.reason is want and result.braking_cycles > 5
    if event == "jump":
        assert "jumps" in result.detail
    assert stats.command_problem == "" and not stats.safety_stop  # nothing unexecutable reached the controller
    assert stats.min_tracking_performance == 1.0  # the stop's joints stayed inside the interpolator's limits
    q = np.array([m.monitorData.measuredJointPosition.value for m in mons if m.connectionInfo.sessionState == CA])
    h = 0.002
    v = np.diff(q, axis=0) / h
    a = np.diff(q, 2, axis=0) / h**2
    assert np.all(np.abs(v) <= limits.velocity * 1.001) and np.all(np.abs(a) <= limits.acceleration * 1.001)
    assert np.abs(v[-3:]).max() < 1e-3  # at rest before the session ended
    assert np.abs(v[200:240]).max() > 0.05  # it was moving when it stopped
