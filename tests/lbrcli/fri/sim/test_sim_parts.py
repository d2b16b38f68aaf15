"""The simulator's pure parts: the interpolator within the limits, connection quality, the session machine."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lbrcli.fri.constants import ConnectionQuality as Q
from lbrcli.fri.constants import SessionState as S
from lbrcli.fri.sim.interpolator import Interpolator
from lbrcli.fri.sim.session import QualityMonitor, QualityThresholds, SessionMachine, SessionTiming

DT = 0.002  # [s]


def _interp(limits, q0=None):
    return Interpolator(np.zeros(7) if q0 is None else q0, limits.velocity, limits.acceleration, DT)


def test_feasible_motion_is_followed_exactly(limits):
    ip = _interp(limits)
    t = np.arange(1, 600) * DT
    path = 0.4 * (1 - np.cos(2 * np.pi * 0.8 * t))[:, None] * np.linspace(0.3, 1.0, 7)  # a < 10 rad/s²
    tracking = [ip.step(q) for q in path]
    assert tracking == [1.0] * len(path)
    assert np.array_equal(ip.q, path[-1])


@pytest.mark.heavy
@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(-2.0, 2.0), min_size=7, max_size=7), st.integers(1, 3))
def test_clipped_motion_respects_the_limits_and_arrives(limits, target, hold):
    ip = _interp(limits)
    target = np.array(target)
    qs, tracking = [ip.q.copy()], []
    for _ in range(1500):  # 3 s: enough for any 2 rad move
        tracking.append(ip.step(target))
        qs.append(ip.q.copy())
    q = np.array(qs)
    v = np.diff(q, axis=0) / DT
    a = np.diff(v, axis=0) / DT
    assert np.all(np.abs(v) <= limits.velocity * (1 + 1e-9))
    assert np.all(np.abs(a) <= limits.acceleration * (1 + 1e-9))
    assert np.allclose(ip.q, target, atol=1e-12) and np.all(ip.v == 0.0)
    if np.abs(target).max() > 0.01:
        assert min(tracking) < 1.0
    assert tracking[-1] == 1.0
    # approaching a fixed target does not overshoot it by more than one acceleration step
    overshoot = np.max(np.sign(target) * (q - target), axis=0)
    assert np.all(overshoot <= limits.acceleration * DT * DT + 1e-12)


def test_a_moving_target_is_caught_up_with_and_then_followed_exactly(limits):
    ip = _interp(limits)
    speed = 0.5 * limits.velocity  # [rad/s] from the first cycle on: an infeasible velocity jump
    tracking, lag = [], []
    for k in range(1, 400):
        target = speed * k * DT
        tracking.append(ip.step(target))
        lag.append(target - ip.q)
    assert tracking[0] < 0.1
    assert tracking[-100:] == [1.0] * 100
    lag = np.array(lag)
    assert np.all(lag >= -limits.acceleration * DT * DT)  # never ahead by more than one acceleration step
    assert np.allclose(ip.v, speed)


def test_tracking_performance_is_the_achieved_fraction_of_the_step(limits):
    ip = _interp(limits)
    target = np.zeros(7)
    target[3] = 0.1  # one cycle could only take a_max·dt² of it
    tp = ip.step(target)
    assert tp == pytest.approx(limits.acceleration[3] * DT * DT / 0.1)
    assert ip.q[3] == pytest.approx(limits.acceleration[3] * DT * DT)


def test_a_joint_that_overshoots_a_sudden_stop_does_not_report_perfect_tracking(limits):
    ip = _interp(limits)
    v = 0.5 * limits.velocity[3]  # [rad/s] moving; then the target stops dead half a step ahead
    for k in range(1, 2000):
        target = np.zeros(7)
        target[3] = min(v, limits.acceleration[3] * k * DT) * DT + ip.q[3]
        ip.step(target)
    assert ip.v[3] == pytest.approx(v)
    target = ip.q.copy()
    asked = 0.5 * v * DT  # [rad] braking to half the speed in one cycle is beyond the acceleration limit
    target[3] += asked
    tp = ip.step(target)
    overshoot = ip.q[3] - target[3]
    assert overshoot > 0.0
    assert tp < 1.0 and tp == pytest.approx(1.0 - overshoot / asked)


def test_quality_from_the_share_of_timely_cycles():
    qm = QualityMonitor(QualityThresholds(window=10, fair=0.5, good=0.8, excellent=1.0))
    assert qm.quality is Q.POOR
    seen = [qm.push(True) for _ in range(10)]
    assert seen[4] is Q.FAIR and seen[7] is Q.GOOD and seen[-1] is Q.EXCELLENT
    assert qm.push(False) is Q.GOOD
    for _ in range(2):
        qm.push(False)
    assert qm.quality is Q.FAIR and qm.ratio == pytest.approx(0.7)


def _machine(**kw):
    return SessionMachine(
        SessionTiming(**{"commanding_after_s": 0.1, "wait_cycles": 3, "end_delay_s": 0.05, "idle_messages": 2, **kw})
    )


def test_session_machine_full_sequence_and_normal_end():
    m = _machine(session_duration_s=0.2)
    t, states = 0.0, []

    def step(q=Q.EXCELLENT, mirror=None, safety=False):
        nonlocal t
        t += 0.01
        s = m.advance(t, q, mirror, safety)
        if not states or states[-1] != s:
            states.append(s)
        return s

    assert step(Q.FAIR) is S.MONITORING_WAIT
    assert step() is S.MONITORING_READY
    while step() is S.MONITORING_READY:
        pass
    assert states[-1] is S.COMMANDING_WAIT and t >= 0.1
    step(mirror=True)
    step(mirror=False)  # an inconsistent command restarts the count
    step(mirror=True)
    step(mirror=True)
    assert m.state is S.COMMANDING_WAIT
    assert step(mirror=True) is S.COMMANDING_ACTIVE
    t_active = t
    while step() is S.COMMANDING_ACTIVE:
        pass
    assert t - t_active == pytest.approx(0.2, abs=0.011) and m.end_reason == "duration"
    while step() is not S.IDLE:
        pass
    assert states == [
        S.MONITORING_WAIT,
        S.MONITORING_READY,
        S.COMMANDING_WAIT,
        S.COMMANDING_ACTIVE,
        S.MONITORING_READY,
        S.IDLE,
    ]
    assert not m.finished
    m.note_idle_sent()
    m.note_idle_sent()
    assert m.finished


@pytest.mark.parametrize(
    "quality, safety, state, reason",
    [
        (Q.FAIR, False, S.MONITORING_WAIT, "quality"),
        (Q.EXCELLENT, True, S.MONITORING_READY, "safety_stop"),
    ],
)
def test_session_machine_leaves_commanding(quality, safety, state, reason):
    m = _machine()
    m.state = S.COMMANDING_ACTIVE
    assert m.advance(1.0, quality, None, safety) is state
    assert m.end_reason == reason
    assert m.advance(1.02, quality, None, False) is state
    assert m.advance(1.06, quality, None, False) is S.IDLE


def test_ready_falls_back_to_wait_when_quality_drops():
    m = _machine()
    assert m.advance(0.0, Q.GOOD, None, False) is S.MONITORING_READY
    assert m.advance(0.05, Q.FAIR, None, False) is S.MONITORING_WAIT
    assert m.end_reason == ""  # not an end: the application still waits for a good connection


def test_float_rk4_step_is_the_numpy_step():
    from planners.pendulum import rk4_step, rk4_step_floats

    rng = np.random.default_rng(1)
    for _ in range(20):
        s = rng.normal(size=3)
        s /= np.linalg.norm(s)
        v = rng.normal(size=3)
        v -= v.dot(s) * s
        a0, a1 = rng.normal(size=3) * 5, rng.normal(size=3) * 5
        ref = rk4_step(s, v, a0, a1, 0.002, 0.45, 0.2)
        got = rk4_step_floats(tuple(s), tuple(v), tuple(a0), tuple(a1), 0.002, 0.45, 0.2)
        assert np.allclose(got[0], ref[0], rtol=0, atol=1e-14) and np.allclose(got[1], ref[1], rtol=0, atol=1e-13)


def test_session_machine_without_overlay_only_monitors_then_ends():
    m = SessionMachine(SessionTiming(commanding_after_s=0.05, session_duration_s=0.3, end_delay_s=0.05, overlay=False))
    seen, t = [], 0.0
    while m.state is not S.IDLE and t < 2.0:
        t += 0.01
        s = m.advance(t, Q.EXCELLENT, True, False)  # even mirrored commands start no overlay
        if not seen or seen[-1] != s:
            seen.append(s)
    assert seen == [S.MONITORING_READY, S.IDLE] and m.end_reason == "duration"
    assert t == pytest.approx(0.01 + 0.3 + 0.05, abs=0.021)


def _flipping(k: int) -> Q:
    """Quality under load at 1 ms: GOOD and FAIR in turns of 7 cycles."""
    return Q.GOOD if (k // 7) % 2 == 0 else Q.FAIR


def test_without_overlay_quality_flips_do_not_restart_the_duration():
    """The duration is the application's run time from the first MONITORING_READY, not unbroken READY time."""
    m = SessionMachine(SessionTiming(session_duration_s=0.3, end_delay_s=0.05, overlay=False))
    t, k, flips, last, ready = 0.0, 0, 0, None, None
    while m.state is not S.IDLE and k < 5000:
        k += 1
        t = k * 1e-3
        s = m.advance(t, _flipping(k) if k > 20 else Q.FAIR, None, False)
        flips += last is not None and s is not last
        last = s
        ready = t if ready is None and s is S.MONITORING_READY else ready
    assert m.state is S.IDLE and m.end_reason == "duration" and flips > 40
    assert t - ready == pytest.approx(0.3 + 0.05, abs=0.0025)


def test_with_overlay_quality_flips_do_not_restart_the_overlay_start_nor_the_active_time():
    m = SessionMachine(SessionTiming(commanding_after_s=0.1, wait_cycles=3, session_duration_s=0.2, end_delay_s=0.05))
    t, k, seen = 0.0, 0, []
    while m.state is not S.IDLE and k < 5000:
        k += 1
        t = k * 1e-3
        active = m.state in (S.COMMANDING_WAIT, S.COMMANDING_ACTIVE)
        s = m.advance(t, Q.GOOD if active or m.end_reason else _flipping(k), True if active else None, False)
        if not seen or seen[-1][0] is not s:
            seen.append((s, t))
    states = [s for s, _ in seen]
    assert states[-4:] == [S.COMMANDING_WAIT, S.COMMANDING_ACTIVE, S.MONITORING_READY, S.IDLE]
    t_wait = seen[-4][1]
    assert 0.1 <= t_wait - 0.001 <= 0.1 + 0.015  # from the first READY, at the next GOOD cycle
    assert seen[-2][1] - seen[-3][1] == pytest.approx(0.2, abs=0.0015) and m.end_reason == "duration"


def test_close_sends_the_idle_messages_of_a_normal_ending():
    m = _machine()
    m.state = S.COMMANDING_ACTIVE
    m.close()
    assert m.advance(1.0, Q.EXCELLENT, None, False) is S.IDLE and not m.finished and m.end_reason == ""
    m.note_idle_sent()
    m.note_idle_sent()
    assert m.finished


@pytest.mark.heavy
def test_the_sim_package_imports_no_cli_planners_or_lab():
    """lbrcli.fri.sim is a library: a controller without plants pulls in neither the CLI, nor planners, nor lab."""
    import subprocess
    import sys

    code = (
        "import sys; from lbrcli.fri.sim import SimConfig; from lbrcli.fri.sim.controller import Controller; "
        "c = Controller(SimConfig(version='2.7')); c.cycle(0.0); "
        "bad = [m for m in sys.modules if m.split('.')[0] == 'planners' or m.startswith(('lbrcli.lab', "
        "'lbrcli.commands', 'lbrcli.app', 'typer'))]; print(bad); sys.exit(1 if bad else 0)"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stdout + res.stderr
