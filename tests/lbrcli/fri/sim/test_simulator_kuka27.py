"""KUKA's own FRI 2.7 example clients (C++, built from lbr-stack/fri's SDK copy: lbrcli/fri/testing/kuka_sdk.py) against
`lbr sim`'s controller: LBRCartesianOverlay in CARTESIAN_POSE mode, TransformationProvider and
SimulatedTransformationProvider with requested frames. Skipped with the reason when there is no compiler or source.
Every datagram passes a recording relay; the checks decode them with lbrcli.fri.codec and judge the motion also
with an independent DH forward kinematics (dh_fk.py)."""

from __future__ import annotations

import math
import subprocess

import numpy as np
import pytest

from lbrcli.fri.codec import FriCodec
from lbrcli.fri.sim import SimConfig, SimulatorProcess, lenient_quality

from lbrcli.fri.testing.dh import pose_error
from lbrcli.fri.testing.relay import Relay, free_udp_port
from lbrcli.fri.testing.kuka_sdk import kuka_app

CA = 4
CODEC = FriCodec("2.7")


def app_or_skip(name: str) -> str:
    path, why = kuka_app(name)
    if path is None:
        pytest.skip(why)
    return path


def run_kuka(argv_of_port, period_ms: int, duration_s: float, leaves_on_idle: bool, **cfg):
    """Run KUKA's client (``argv_of_port(port)``) against the simulator through the relay; (stats, monitoring
    messages, command messages, the client's return code or None if it had to be stopped)."""
    port = free_udp_port()
    proc = subprocess.Popen(argv_of_port(port), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        with Relay(port) as relay:
            config = SimConfig(client_port=relay.port, version="2.7", period_ms=period_ms,
                               session_duration_s=duration_s, commanding_after_s=0.05, end_delay_s=0.05,
                               max_runtime_s=30.0, **{**lenient_quality(period_ms), **cfg})  # fmt: skip
            with SimulatorProcess(config) as sim:
                stats = sim.wait(40.0) or sim.stop()
            try:
                code = proc.wait(5.0 if leaves_on_idle else 0.5)
            except subprocess.TimeoutExpired:
                code = None
        mons = [CODEC.decode_monitoring(d) for d in relay.to_client]
        cmds = [CODEC.decode_command(d) for d in relay.to_sim]
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    return stats, mons, cmds, code


def steady_pairs(mons, cmds):
    """(command, message executing it): the command answered message n in COMMANDING_ACTIVE and message n + 1,
    also in COMMANDING_ACTIVE with tracking performance 1, reflects it (it arrived in time)."""
    by_seq = {m.header.sequenceCounter: m for m in mons}
    for c in cmds:
        n = c.header.reflectedSequenceCounter
        m0, m1 = by_seq.get(n), by_seq.get(n + 1)
        if (m0 is not None and m1 is not None and m0.connectionInfo.sessionState == CA
                and m1.connectionInfo.sessionState == CA and m1.header.reflectedSequenceCounter == c.header.sequenceCounter
                and m1.ipoData.trackingPerformance == 1.0):  # fmt: skip
            yield c, m1


@pytest.mark.heavy
def test_kuka_cartesian_overlay_moves_the_flange_by_its_amplitude():
    """LBRCartesianOverlay (defaults: 0.15 Hz, 30 "rad" added to x and y in mm, filter 0.99, E1 swept ±45° by 0.1°
    per command): the commanded offsets are its source's formula; the measured flange follows them (our model and
    the DH judge), A3 follows E1, the session ends on IDLE."""
    exe = app_or_skip("LBRCartesianOverlay")
    h, freq, amp, c = 0.002, 0.15, 30.0, 0.99  # [s], [Hz], [mm], filter
    stats, mons, cmds, _ = run_kuka(lambda port: [exe, "", str(port)], period_ms=2, duration_s=4.0,
                                    leaves_on_idle=False, command_mode="cartesian",
                                    lockstep_timeout_s=0.5)  # fmt: skip  # every reply in time, also on a loaded PC
    assert stats.end_reason == "duration" and stats.states_seen[-1] == 0 and not stats.safety_stop
    assert stats.command_problem == "" and stats.cartesian_poses > 1000
    by_seq = {m.header.sequenceCounter: m for m in mons}
    active = [
        x
        for x in cmds
        if by_seq.get(x.header.reflectedSequenceCounter) is not None
        and by_seq[x.header.reflectedSequenceCounter].connectionInfo.sessionState == CA
    ]
    assert all(len(x.commandData.cartesianPose.element) == 7 and not x.commandData.jointPosition.value for x in active)
    ipos = np.array([m.ipoData.cartesianPose.element[:3] for m in mons if m.connectionInfo.sessionState == CA])
    assert np.ptp(ipos, axis=0).max() == 0.0  # PositionHold: the ipo pose stays while commanding
    ipo = ipos[0]  # [mm]
    # the source's formula, one step per COMMANDING_ACTIVE message answered
    off_sin = off_cos = phi = 0.0
    expected = []
    for _ in active:
        off_sin = off_sin * c + amp * math.sin(phi) * (1 - c)
        off_cos = off_cos * c + amp * math.cos(phi) * (1 - c)
        phi = (phi + 2 * math.pi * freq * h) % (2 * math.pi)
        expected.append((off_sin, off_cos))
    sent = np.array([np.array(x.commandData.cartesianPose.element[:2]) - ipo[:2] for x in active])
    assert np.abs(sent - np.array(expected)).max() < 1e-6  # [mm]
    pairs = list(steady_pairs(mons, cmds))
    assert len(pairs) > 0.5 * len(active)
    msr = np.array([m.monitorData.measuredCartesianPose.element[:3] for _, m in pairs]) - ipo
    cmd = np.array([x.commandData.cartesianPose.element[:3] for x, _ in pairs]) - ipo
    assert np.abs(msr - cmd).max() < 0.01  # [mm] executed exactly where the interpolator keeps up
    assert 0.97 * amp < np.abs(msr[:, 0]).max() <= amp  # the flange swings ±30 mm in x
    e1 = [
        (x.commandData.redundancyInformation.value, m.monitorData.measuredRedundancyInformation.value) for x, m in pairs
    ]
    assert max(abs(a - b) for a, b in e1) < 1e-9 and max(abs(a) for a, _ in e1) > math.radians(5)
    dh = np.array([pose_error(m.monitorData.measuredJointPosition.value, x.commandData.cartesianPose.element)
                   for x, m in pairs])  # fmt: skip
    assert dh[:, 0].max() < 1e-4 and dh[:, 1].max() < 1e-3  # [m], [rad]: the second judge


@pytest.mark.heavy
def test_kuka_transformation_provider_values_arrive():
    """TransformationProvider sends PBase with x, y, z [mm] stepping 1, 5, 10 per message (wrapping at 100, 200,
    300), stamped with the message's time; the simulator keeps them; the client leaves on IDLE by itself."""
    exe = app_or_skip("TransformationProvider")
    stats, mons, cmds, code = run_kuka(lambda port: [exe, "", str(port)], period_ms=2, duration_s=1.0,
                                       leaves_on_idle=True, transformations=("PBase",))  # fmt: skip
    assert stats.states_seen[-1] == 0 and code == 1  # KUKA's main returns 1 after leaving its loop on IDLE
    fig = stats.transformations["PBase"]
    trs = [(x, x.commandData.commandedTransformations) for x in cmds]
    assert all(len(t) == 1 and t[0].name == "PBase" for _, t in trs)
    assert fig["received"] == len(trs) > 300 and stats.transformations_refused == 0
    xyz = np.array([t[0].element[:3] for _, t in trs])  # [mm]
    step = np.diff(xyz, axis=0)
    assert set(np.round(step[:, 0], 9)) <= {1.0, -100.0} and set(np.round(step[:, 1], 9)) <= {5.0, -200.0}
    assert set(np.round(step[:, 2], 9)) <= {10.0, -300.0}
    assert np.allclose(np.array(fig["last"][:3]), xyz[-1] * 1e-3)  # reported in metres
    stamps = {m.header.sequenceCounter: (m.monitorData.timestamp.sec, m.monitorData.timestamp.nanosec) for m in mons}
    assert all(
        (t[0].timestamp.sec, t[0].timestamp.nanosec) == stamps[x.header.reflectedSequenceCounter] for x, t in trs
    )


@pytest.mark.heavy
def test_kuka_simulated_transformation_provider_runs_and_its_data_arrive():
    """SimulatedTransformationProvider provides getRequestedTransformationIDs()[0] from its recorded data (it
    crashed when the controller requested nothing): the first second holds row 0, a 30° rotation about x."""
    exe = app_or_skip("SimulatedTransformationProvider")
    stats, mons, cmds, code = run_kuka(lambda port: [exe, "2", "2", "1", "1000", "", str(port)], period_ms=2,
                                       duration_s=1.5, leaves_on_idle=True, transformations=("Sensor",))  # fmt: skip
    assert stats.states_seen[-1] == 0 and code == 1  # left on IDLE, no crash
    assert stats.transformations["Sensor"]["received"] == len(cmds) > 300
    first = np.array(cmds[0].commandData.commandedTransformations[0].element)
    half = math.radians(15.0)
    assert np.abs(first - [0, 0, 0, math.cos(half), math.sin(half), 0, 0]).max() < 1e-3
    last = np.array(stats.transformations["Sensor"]["last"])
    assert abs(np.linalg.norm(last[3:]) - 1.0) < 1e-3 and np.abs(last[3:] - first[3:]).max() > 1e-3  # it moved on
