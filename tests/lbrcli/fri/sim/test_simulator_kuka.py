"""The simulator against a client that answers like KUKA's example clients (joint/torque/wrench sine overlays,
IOAccess): PositionHold semantics, the three command modes, IO, the FRI 2.7 fields, safety braking."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from lbrcli.fri.sim import IO_PRESETS, IoChannel, SimConfig, SimulatorProcess

from lbrcli.fri.testing.kuka_client import CA, KukaLikeClient, joint_sine

FAST = dict(
    commanding_after_s=0.05,
    quality_window=25,
    quality_good=0.5,
    quality_fair=0.3,
    quality_excellent=0.9,
    end_delay_s=0.05,
    max_runtime_s=15.0,
)
# these tests are about the protocol's semantics and the plant's response, not about timing (tests/lbrcli/test_sim_spacing.py
# is): the simulator waits for every reply (simulated time advances one period per cycle), so load changes nothing
LOCKSTEP = dict(lockstep_timeout_s=2.0, lockstep_free=True)


def session(version="1.15", client_overlay=None, mode="position", io_writer=None, **cfg):
    client = KukaLikeClient(version)
    config = SimConfig(client_port=client.port, version=version, command_mode=mode, **{**FAST, **LOCKSTEP, **cfg})
    try:
        with SimulatorProcess(config) as sim:
            run = client.run(client_overlay, mode=mode, io=io_writer, timeout=20.0)
            stats = sim.wait(10.0) or sim.stop()
    finally:
        client.close()
    return run, stats, config


def q_of(field) -> np.ndarray:
    return np.array(field.value)


@pytest.mark.heavy
@pytest.mark.parametrize("version", ["1.15", "2.7"])
@pytest.mark.parametrize("period_ms", [1, 2, 5])
def test_joint_sine_overlay_moves_measured_not_ipo(version, period_ms):
    """KUKA's LBRJointSineOverlay: command = ipo + 0.04·sin on A4 → measured = ipo + sine one cycle later."""
    run, stats, cfg = session(
        version,
        joint_sine(3, 0.04, 1.0),
        period_ms=period_ms,
        session_duration_s=max(0.6, 150 * period_ms * 1e-3),
        quality_window=max(50, 500 // period_ms),
        quality_good=0.2,
        quality_fair=0.1,
    )  # loaded machine
    assert not stats.safety_stop and stats.end_reason == "duration"
    active = run.active()
    ipo = np.array([q_of(m.ipoData.jointPosition) for m in active])
    assert np.ptp(ipo, axis=0).max() == 0.0 and np.allclose(ipo[0], cfg.q0)  # PositionHold: ipo constant
    # timely commands, and not while the interpolator still catches up after a long gap of late replies (a loaded
    # machine; it reports that as tracking performance < 1)
    pairs = [
        (s, m)
        for s, m in run.executed_pairs(steady=3)
        if m.connectionInfo.sessionState == CA and s.q is not None and m.ipoData.trackingPerformance == 1.0
    ]
    assert len(pairs) > 0.3 * len(active)
    err = [np.abs(q_of(m.monitorData.measuredJointPosition) - s.q).max() for s, m in pairs]
    assert max(err) < 1e-6
    msr = np.array([q_of(m.monitorData.measuredJointPosition) for m in active])
    assert np.ptp(msr[:, 3]) > 0.01  # the (filtered) sine really ran
    assert np.abs(msr[:, [0, 1, 2, 4, 5, 6]] - ipo[:, [0, 1, 2, 4, 5, 6]]).max() < 1e-12
    if version == "1.15":  # the command in force
        assert max(np.abs(q_of(m.monitorData.commandedJointPosition) - s.q).max() for s, m in pairs) < 1e-6
    assert min(m.ipoData.trackingPerformance for _, m in pairs) == 1.0


@pytest.mark.heavy
def test_torque_mode_response_is_the_joint_impedance_dynamics(robot):
    """A torque sine on A4 under joint impedance (K, ζ): the deflection e = q − ipo follows
    (K − ω² M + iω D)⁻¹ τ (linearised about the ipo pose), a constant torque deflects by τ/K."""
    amp, f, K, zeta = 8.0, 2.0, 800.0, 0.7
    bias = 4.0  # [Nm] a constant part: static deflection bias/K

    def overlay(n, h):
        tau = np.zeros(7)
        tau[3] = bias + amp * math.sin(2 * math.pi * f * h * n)
        return np.zeros(7), tau, None

    run, stats, cfg = session(
        "1.15",
        overlay,
        mode="torque",
        period_ms=2,
        session_duration_s=1.6,
        joint_stiffness=K,
        damping_ratio=zeta,
    )
    assert not stats.safety_stop and stats.incomplete_commands == 0
    active = run.active()
    assert all(m.ipoData.clientCommandMode == 3 and m.robotInfo.controlMode == 2 for m in active)
    h = cfg.period_ms * 1e-3
    seq = np.array([m.header.sequenceCounter for m in active], dtype=float)
    e = np.array([q_of(m.monitorData.measuredJointPosition)[3] - q_of(m.ipoData.jointPosition)[3] for m in active])
    # the torque in force during the cycle before each message: the command answering the message before it
    by_reflected = {s.reflected: s.torque[3] for s in run.sent if s.torque is not None}
    tau = np.array([by_reflected.get(int(s) - 1, np.nan) for s in seq])
    keep = (seq - seq[0]) * h > 0.5  # after the transient
    keep &= np.isfinite(tau)
    t = seq[keep] * h
    basis = np.column_stack([np.sin(2 * np.pi * f * t), np.cos(2 * np.pi * f * t), np.ones_like(t)])
    ce, *_ = np.linalg.lstsq(basis, e[keep], rcond=None)
    ct, *_ = np.linalg.lstsq(basis, tau[keep], rcond=None)
    ratio = complex(ce[0], ce[1]) / complex(ct[0], ct[1])  # deflection per torque [rad/Nm], complex
    M = pin.crba(robot.model, robot.data, np.array(cfg.q0))
    D = 2 * zeta * np.sqrt(K * np.diag(M))
    w = 2 * np.pi * f
    H = np.linalg.inv(K * np.eye(7) - w**2 * M + 1j * w * np.diag(D))[3, 3] * np.exp(-0.5j * w * h)  # ZOH delay
    assert abs(ratio) == pytest.approx(abs(H), rel=0.05)
    assert abs(np.angle(ratio / H)) < 0.06
    assert ce[2] == pytest.approx(bias / K, rel=0.05)
    assert abs(np.angle(H)) > 0.3  # the dynamics matter at this frequency (not a static spring)
    # torques: what the sensors read = gravity + impedance + command; nothing external
    last = active[-1]
    q = q_of(last.monitorData.measuredJointPosition)
    g = pin.computeGeneralizedGravity(robot.model, robot.data, q)
    assert np.abs(q_of(last.monitorData.measuredTorque) - g).max() < 3 * amp
    assert np.allclose(q_of(last.monitorData.externalTorque), 0.0)


@pytest.mark.heavy
def test_wrench_mode_constant_force_deflects_by_force_over_stiffness(robot):
    """Cartesian impedance: a constant 20 N along the TCP's x moves the TCP along it by F/k at steady state."""
    F, k = 20.0, 2000.0

    def overlay(n, h):
        return np.zeros(7), None, np.array([F, 0, 0, 0, 0, 0])

    run, stats, cfg = session(
        "2.7",
        overlay,
        mode="wrench",
        period_ms=2,
        session_duration_s=2.0,
        cartesian_stiffness=(k, 150.0),
    )
    assert not stats.safety_stop and stats.incomplete_commands == 0
    active = run.active()
    assert all(m.ipoData.overlayType == 2 and m.robotInfo.controlMode == 1 for m in active)
    q_ipo = q_of(active[0].ipoData.jointPosition)
    start = robot.fk(q_ipo)
    x_tcp = start.rotation[:, 0]
    # steady state: from 1 s of simulated time on (one message per 2 ms cycle)
    steady = active[500:]
    assert len(steady) >= 50, f"only {len(active)} cycles in COMMANDING_ACTIVE (machine too loaded)"
    d = np.array([robot.fk(q_of(m.monitorData.measuredJointPosition)).translation for m in steady]) - start.translation
    along = d @ x_tcp
    assert np.ptp(along) < 0.02 * F / k  # settled
    assert along.mean() == pytest.approx(F / k, rel=0.01)
    assert np.linalg.norm(d[-1] - along[-1] * x_tcp) < 0.01 * F / k
    end = robot.fk(q_of(steady[-1].monitorData.measuredJointPosition))
    assert np.linalg.norm(pin.log3(start.rotation.T @ end.rotation)) < 1e-3


@pytest.mark.heavy
def test_io_outputs_are_written_inputs_reported_wrong_writes_refused():
    """The IOAccess example's channels plus an analog input: outputs read back, inputs reported, bad writes refused."""
    channels = IO_PRESETS["kuka-ioaccess"] + (IoChannel("Ext.Analog_In", "analog", "in", 0.5),)

    def io(mon):
        n = mon.header.sequenceCounter
        return [
            ("FRI.Out_Analog_Deci_Seconds", 2, 0.01 * n),
            ("FRI.Out_Integer_Seconds", 1, n),
            ("FRI.In_Bool_Clock_Enabled", 0, 0),
            ("No.Such.Channel", 2, 1.0),
        ]

    # like KUKA's IOAccess: a monitoring-only application (it mirrors no positions), IO read and written throughout
    run, stats, _ = session("2.7", None, io_writer=io, period_ms=4, session_duration_s=0.2, io=channels, overlay=False)
    assert stats.states_seen == (1, 2, 0) and stats.end_reason == "duration"
    assert stats.io_writes == 2 * stats.replies and stats.io_refused == 2 * stats.replies
    for m in run.messages[:-1]:
        got = {x.name: x for x in m.monitorData.readIORequest}
        assert set(got) == {c.name for c in channels}
        assert got["FRI.In_Bool_Clock_Enabled"].direction == 0 and got["FRI.In_Bool_Clock_Enabled"].digitalValue == 1
        assert got["Ext.Analog_In"].direction == 0 and got["Ext.Analog_In"].analogValue == 0.5
        assert got["FRI.Out_Analog_Deci_Seconds"].direction == 1 and got["FRI.Out_Integer_Seconds"].type == 1
    pairs = list(run.executed_pairs())
    assert len(pairs) > 0.5 * len(run.messages)
    for s, m in pairs:  # the written outputs are read back in the next message
        got = {x.name: x for x in m.monitorData.readIORequest}
        assert got["FRI.Out_Analog_Deci_Seconds"].analogValue == s.io["FRI.Out_Analog_Deci_Seconds"]
        assert got["FRI.Out_Integer_Seconds"].digitalValue == s.io["FRI.Out_Integer_Seconds"]


@pytest.mark.heavy
def test_fri_2_7_fields_are_the_kinematics_of_the_measured_pose(robot):
    force = np.array([0.0, 0.0, -15.0, 0.0, 0.0, 0.0])  # a 15 N downward pull on the TCP (base axes)
    run, stats, _ = session(
        "2.7", joint_sine(1, 0.05, 2.0, 0.9), period_ms=4, session_duration_s=0.4, external_force=tuple(force)
    )
    assert not stats.safety_stop
    for m in run.messages[:-1]:
        md, ipo = m.monitorData, m.ipoData
        q = q_of(md.measuredJointPosition)
        pose = robot.fk(q)
        x, y, z, w = pin.Quaternion(pose.rotation).coeffs()
        want = np.r_[pose.translation * 1e3, w, x, y, z]
        got = np.array(md.measuredCartesianPose.element)
        assert np.abs(got - want).max() < 1e-9 or np.abs(got - np.r_[want[:3], -want[3:]]).max() < 1e-9
        assert md.measuredRedundancyInformation.strategy == 0 and md.measuredRedundancyInformation.value == q[2]
        qi = q_of(ipo.jointPosition)
        assert np.abs(np.array(ipo.cartesianPose.element[:3]) - robot.fk(qi).translation * 1e3).max() < 1e-9
        assert ipo.redundancyInformation.value == qi[2]
        # the pull: external force in the TCP frame, external torques Jᵀ F, motors hold against it
        assert np.allclose(md.externalForce.element, np.r_[pose.rotation.T @ force[:3], 0, 0, 0])
        J = pin.computeFrameJacobian(robot.model, robot.data, q, robot.tcp_id, pin.LOCAL_WORLD_ALIGNED)
        assert np.allclose(q_of(md.externalTorque), J.T @ force)
    assert np.ptp([q_of(m.monitorData.measuredJointPosition)[1] for m in run.active()]) > 0.05


@pytest.mark.heavy
@pytest.mark.parametrize("mode", ["position", "torque"])
def test_safety_stop_brakes_inside_the_position_limits(limits, mode):
    """A runaway command on A4 (accelerating towards its limit) → safety stop; A4 never passes 120°."""
    lim = limits.position[3]

    def overlay(n, h):  # −(acceleration 4 rad/s²) t²/2 on A4: the measured position runs after it at speed
        off = np.zeros(7)
        off[3] = -2.0 * (n * h) ** 2
        return off, None, None

    run, stats, cfg = session(
        "1.15",
        overlay,
        mode=mode,
        period_ms=2,
        session_duration_s=3.0,
        end_delay_s=0.5,
        quality_window=250,
        quality_good=0.2,
        quality_fair=0.1,
    )  # a loaded machine answers late
    assert stats.safety_stop and stats.end_reason == "safety_stop"
    q4 = np.array([q_of(m.monitorData.measuredJointPosition)[3] for m in run.messages])
    assert np.abs(q4).max() <= lim + 1e-12 and abs(stats.final_q[3]) <= math.radians(120) + 1e-12
    assert np.abs(q4).max() > lim - 0.3  # it did run towards the limit
    assert run.messages[-2].robotInfo.driveState[0] == 0  # stopped, drives off


@pytest.mark.heavy
def test_torque_mode_wait_needs_a_torque():
    """KUKA's consistency check: in torque mode COMMANDING_WAIT needs a torque with the mirrored position."""
    client = KukaLikeClient("1.15")
    config = SimConfig(client_port=client.port, command_mode="torque", period_ms=4, **{**FAST, "max_runtime_s": 0.6})
    try:
        with SimulatorProcess(config) as sim:
            run = client.run(None, mode="position", timeout=2.0)  # mirrors positions only
            stats = sim.wait(5.0) or sim.stop()
    finally:
        client.close()
    assert stats.states_seen[-2:] == (3, 0) and 4 not in stats.states_seen  # stuck in COMMANDING_WAIT, then closed
    assert stats.incomplete_commands > 10 and run.messages
