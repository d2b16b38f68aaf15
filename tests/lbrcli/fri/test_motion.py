"""ExecutedMotion: the history the guard judges against, continued over lost messages as the controller does."""

from __future__ import annotations

import numpy as np
import pytest

from lbrcli.fri.motion import EFFORT_RANGE_S, ExecutedMotion
from trajectories.limits import default_limits

ACTIVE, POSITION = 4, 1


@pytest.mark.parametrize("lost_after, lost", [(1, 1), (3, 2), (10, 1), (25, 4)])
def test_a_braking_stop_interrupted_by_lost_messages_goes_on_within_the_limits(lost_after, lost):
    lim, dt = default_limits(), 0.001
    m = ExecutedMotion(lim, dt, 1e9, 1e9, hold_cycles=2, q=(0.0,) * 7)
    v = 0.8 * lim.velocity  # [rad/s] cruising at 80 % of every joint's limit
    sent = [np.zeros(7)]
    for k in range(1, 400):  # accelerate within the limits, then cruise
        speed = np.minimum(v, 0.5 * lim.acceleration * k * dt)
        q = tuple(sent[-1] + speed * dt)
        cmd, *_, why = m.next_command(q, ACTIVE, POSITION, q, None, None)
        assert why is None
        m.sent(cmd, ACTIVE)
        sent.append(np.array(cmd))
    m.begin_braking()
    for k in range(400):
        if k == lost_after:  # the controller's messages were lost: it extrapolated our last commands
            m.extrapolate(lost)
            for _ in range(lost):  # at the last commands' velocity
                sent.append(2 * sent[-1] - sent[-2])
            assert np.allclose(m.prev, sent[-1])
        cmd, *_, why = m.next_command(sent[-1], ACTIVE, POSITION, sent[-1], None, None)  # the brake replaces it
        assert why is None
        m.sent(cmd, ACTIVE)
        sent.append(np.array(cmd))
        if m.brake.done:
            break
    assert m.brake.done
    q = np.array(sent)
    assert np.all(np.abs(np.diff(q, axis=0)) / dt <= lim.velocity * (1 + 1e-9))
    assert np.all(np.abs(np.diff(q, 2, axis=0)) / dt**2 <= lim.acceleration * (1 + 1e-6))
    assert np.allclose(q[-1], q[-2], atol=1e-12)  # at rest


def _drive(m: ExecutedMotion, wants, n: int, mode: int = POSITION, tau=None, wrench=None, exact=False, jerk=False):
    """Feed ``n`` commands ``wants(k, prev)`` through the core; the positions sent and the reasons given."""
    sent, reasons = [np.array(m.prev)], []
    for k in range(n):
        want = wants(k, m.prev)
        cmd, t, w, why = m.next_command(want, ACTIVE, mode, want, tau, wrench, exact, jerk)
        m.sent(tuple(cmd), ACTIVE)
        sent.append(np.array(cmd))
        reasons.append(why)
    return np.array(sent), reasons


def _ratios(q: np.ndarray, dt: float, lim) -> tuple[float, float, float]:
    v = np.diff(q, axis=0) / dt
    a = np.diff(v, axis=0) / dt
    j = np.diff(a, axis=0) / dt
    return (float((np.abs(v) / lim.velocity).max()), float((np.abs(a) / lim.acceleration).max()),
            float((np.abs(j) / lim.jerk).max()))  # fmt: skip


@pytest.mark.heavy
def test_a_feedback_client_that_asks_too_much_is_clamped_and_can_always_brake():
    """A client that wants 3× the velocity limit toward A1's and A4's position limits and then stops asking: every
    command it gets is inside the limits, none is refused, and the brake from wherever it is stays inside too."""
    lim, dt = default_limits(), 1e-3
    q0 = (1.5, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)
    m = ExecutedMotion(lim, dt, 1e9, 1e9, hold_cycles=1, q=q0)
    push = np.array([3.0, 0, 0, 3.0, 0, 0, 0]) * lim.velocity * dt
    q, reasons = _drive(m, lambda k, prev: tuple(np.array(prev) + push), 1500)
    assert all(r is None for r in reasons) and m.clamped_cycles > 1000
    assert np.all(np.abs(q) <= lim.position * (1 + 1e-9))
    v, a, _ = _ratios(q, dt, lim)
    assert v <= 1 + 1e-9 and a <= 1 + 1e-9
    # pressed against the limits: the robot stands just inside them
    assert lim.position[0] - q[-1, 0] < 1e-3 and lim.position[3] - q[-1, 3] < 1e-3
    # mid-approach at full speed: a stop from any admitted state stays inside the limits
    m2 = ExecutedMotion(lim, dt, 1e9, 1e9, hold_cycles=1, q=q0)
    head, _ = _drive(m2, lambda k, prev: tuple(np.array(prev) + push), 300)
    m2.begin_braking()
    tail, _ = _drive(m2, lambda k, prev: prev, 800)
    v, a, j = _ratios(np.vstack([head, tail[1:]])[-810:], dt, lim)  # the last approach and the whole stop
    assert m2.brake.done and v <= 1 + 1e-9 and a <= 1 + 1e-6 and j <= 1 + 1e-6
    assert np.all(np.abs(tail) <= lim.position * (1 + 1e-9))


def test_exact_commands_are_not_clamped_but_refused_with_a_braking_stop():
    lim, dt = default_limits(), 1e-3
    m = ExecutedMotion(lim, dt, 1e9, 1e9, hold_cycles=1, q=(0.0,) * 7)
    step = np.zeros(7)
    step[2] = 1.5 * lim.velocity[2] * dt  # a jump A3 cannot follow
    q, reasons = _drive(m, lambda k, prev: tuple(np.array(prev) + (step if k == 20 else 0.0)), 40, exact=True)
    assert reasons[20] is not None and "A3" in reasons[20] and m.braking and m.clamped_cycles == 0
    v, a, _ = _ratios(q, dt, lim)
    assert v <= 1 + 1e-9 and a <= 1 + 1e-9


def test_jerk_limited_clients_are_clamped_in_jerk_too():
    lim, dt = default_limits(), 1e-3
    m = ExecutedMotion(lim, dt, 1e9, 1e9, hold_cycles=1, q=(0.0,) * 7)
    rng = np.random.default_rng(5)
    q, _ = _drive(m, lambda k, prev: tuple(np.array(prev) + rng.normal(0, 1, 7) * lim.velocity * dt), 600, jerk=True)
    v, a, j = _ratios(q, dt, lim)
    assert v <= 1 + 1e-9 and a <= 1 + 1e-9 and j <= 1 + 1e-6


def _bridging_session(m: ExecutedMotion, wants, lost: set[int], n: int, jerk: bool = True, braking_at: int = -1,
                      late: frozenset[int] = frozenset()):  # fmt: skip
    """A controller that bridges every reply in ``lost`` or ``late`` (cycle numbers) by holding the velocity, as
    KUKA's and the scripted one do, executes a ``late`` one a period later carried forward by that period (as our
    simulator does, unless the next reply is in time), and reports where it stands in its next message;
    ``wants(k)`` the client's command. The executed positions and, per executed step, whether it was ours (our
    command, in time) or the controller's."""
    exe, ours, sent = [np.array(m.prev)] * 3, [True] * 3, [np.array(m.prev)] * 2
    lost = set(lost) | set(late)
    for k in range(n):
        if k - 1 in lost:  # the message says our last reply had not arrived: it shows where the robot is
            m.reply_lost(tuple(exe[-1]))
        elif m.coasting:  # it says our last reply arrived in time (as the link tells the motion)
            m.confirmed()
        if k == braking_at:
            m.begin_braking()
        want = wants(k)
        cmd, _, _, why = m.next_command(want, ACTIVE, POSITION, want, None, None, False, jerk)
        m.sent(tuple(cmd), ACTIVE)
        sent.append(np.array(cmd))
        if k not in lost:
            exe.append(sent[-1])
        elif k - 1 in late:  # the late reply arrives now, carried forward by its lateness
            exe.append(2 * sent[-2] - sent[-3])
        else:
            exe.append(2 * exe[-1] - exe[-2])
        ours.append(k not in lost)
    return np.array(exe), np.array(ours)


def _our_ratios(exe: np.ndarray, ours: np.ndarray, dt: float, lim) -> tuple[float, float, float]:
    """Peak velocity, acceleration and jerk over the limits of our steps, measured against the executed history."""
    v = np.diff(exe, axis=0) / dt
    a = np.diff(v, axis=0) / dt
    j = np.diff(a, axis=0) / dt
    return (float((np.abs(v[ours[1:]]) / lim.velocity).max()), float((np.abs(a[ours[2:]]) / lim.acceleration).max()),
            float((np.abs(j[ours[3:]]) / lim.jerk).max()))  # fmt: skip


def test_after_a_reply_the_controller_bridged_our_commands_rejoin_the_path_within_the_limits_of_what_it_executed():
    """A jerk-limited client (ruckig at half the limits intercepting a smooth wave at 20 % of A1's and A4's
    acceleration limits, as the bridge's follower does); replies lost singly and two in a row, two late (the first
    executed a period late). The controller's bridge steps its acceleration to 0 (its own); every command after it
    keeps the velocity, acceleration and jerk limits measured against the history the controller executed, and the
    motion is back on the client's path."""
    from lbrcli.bridge.tracker import ReferenceTracker

    lim, dt = default_limits(), 1e-3
    m = ExecutedMotion(lim, dt, 1e9, 1e9, hold_cycles=1, q=(0.0,) * 7)
    w = 2 * np.pi  # [rad/s]; (1 − cos wt)² starts at rest with no acceleration, its peak is 2.25·w²
    amp = np.array([0.2, 0, 0, 0.2, 0, 0, 0]) * lim.acceleration / (2.25 * w**2)

    def ref(t: float):
        c, s = np.cos(w * t), np.sin(w * t)
        return amp * (1 - c) ** 2, amp * 2 * w * (1 - c) * s, amp * 2 * w**2 * (s * s + c - c * c)

    tracker = ReferenceTracker(lim.scaled(0.5), dt, m.prev)
    plan = [tuple(tracker.step(lambda t, k=k: ref(k * dt + t))) for k in range(1200)]
    exe, ours = _bridging_session(m, lambda k: plan[k], {150, 220, 221, 400, 470}, 1200, late=frozenset({300, 301}))
    v, a, j = _our_ratios(exe, ours, dt, lim)
    # (7 replies bridged; the second late one executed our first one carried forward, which was ours: the coast's)
    assert m.rebased_cycles == 6 and m.rejoin_cycles > 0 and m.coast_cycles > 0 and not m.braking
    assert v <= 1 + 1e-9 and a <= 1 + 1e-9 and j <= 1 + 1e-6
    assert np.abs(exe[-1] - plan[-1]).max() < 1e-12  # back on the client's path


def test_a_braking_stop_after_a_reply_the_controller_bridged_brakes_within_the_limits_of_what_it_executed():
    """Braking from 80 % of the velocity limits, a reply lost mid-stop: the stop is re-planned from the bridged
    history, so its steps keep every limit against what the controller executed."""
    lim, dt = default_limits(), 1e-3
    m = ExecutedMotion(lim, dt, 1e9, 1e9, hold_cycles=1, q=(0.0,) * 7)
    speed = lambda k: np.minimum(0.8 * lim.velocity, 0.4 * lim.acceleration * k * dt)  # noqa: E731
    pos = np.cumsum([speed(k) * dt for k in range(400)], axis=0)
    exe, ours = _bridging_session(m, lambda k: tuple(pos[min(k, 399)]), {415, 470}, 900, jerk=False, braking_at=400)
    v, a, j = _our_ratios(exe[400:], ours[400:], dt, lim)  # (the cruise before: a file's rows, not jerk-limited)
    assert m.brake.done and m.rebased_cycles == 2
    assert v <= 1 + 1e-9 and a <= 1 + 1e-6 and j <= 1 + 1e-6


@pytest.mark.parametrize("mode", [3, 2])  # TORQUE, WRENCH
def test_a_stop_in_torque_or_wrench_mode_ramps_the_effort_down_within_its_rate(mode):
    lim, dt = default_limits(), 1e-3
    m = ExecutedMotion(lim, dt, 20.0, 2.0, hold_cycles=2, q=(0.0,) * 7)
    tau = (39.6,) * 7 if mode == 3 else None
    wrench = (20.0, -20.0, 10.0, 2.0, -2.0, 1.0) if mode == 2 else None
    efforts = []
    for k in range(50):
        if k == 10:
            m.begin_braking()
        cmd, t, w, why = m.next_command(m.prev, ACTIVE, mode, m.prev, tau, wrench)
        assert why is None
        m.sent(tuple(cmd), ACTIVE)
        efforts.append(t if mode == 3 else w)
    k = 50
    while not m.held_long_enough():
        cmd, t, w, _ = m.next_command(m.prev, ACTIVE, mode, m.prev, tau, wrench)
        m.sent(tuple(cmd), ACTIVE)
        efforts.append(t if mode == 3 else w)
        k += 1
        assert k < 5000
    e = np.array(efforts)
    assert np.allclose(e[:10], e[0]) and np.allclose(e[-1], 0.0)  # the client's effort, then down to zero …
    rate = np.abs(np.diff(e, axis=0)).max(axis=0) / dt
    bound = (lim.torque if mode == 3 else np.array([20.0] * 3 + [2.0] * 3)) / EFFORT_RANGE_S
    assert np.all(rate <= bound * (1 + 1e-6))  # … no faster than the whole range per EFFORT_RANGE_S
    assert np.all(np.abs(np.diff(e, axis=0)).max(axis=0) < np.abs(e[0]) / 10)  # never in one cycle


def test_a_client_that_replans_from_the_executed_motion_gets_no_offset_of_the_core_on_top():
    """A client that re-plans from what the controller executed (``replans``: the upright cart, the bridge's follower)
    ramps A1 and A4 to 0.6 of their acceleration limits within the jerk limit, messages lost now and then (the
    controller held the velocity). The core takes no path through the gap and plans no offset back onto it (the
    client's re-plan already starts from the executed history: an offset would count the gap twice, and a clamp's
    offset, started at the clamp's acceleration, ran away to 0.05 rad in the upright session); a clamp tells the
    client to re-plan. Every step stays within the limits of the executed history, and the client's commands are
    sent as they are."""
    lim, dt = default_limits(), 1e-3
    m = ExecutedMotion(lim, dt, 1e9, 1e9, hold_cycles=1, q=(0.0,) * 7)
    m.replans = True
    target = np.array([0.6, 0, 0, 0.6, 0, 0, 0]) * lim.acceleration  # [rad/s²]
    jerk = 0.9 * lim.jerk  # [rad/s³]
    exe, ours, gaps, clamps = [np.array(m.prev)] * 3, [True] * 3, {60, 61, 140, 200, 230, 231, 232, 300}, []
    for k in range(400):
        if k in gaps:  # the controller's message is lost: it extrapolated our last command
            m.extrapolate(1)
            exe.append(np.array(m.prev))
            ours.append(False)
            continue
        p, v, a = np.array(m.position), np.array(m.velocity), np.array(m.acceleration)  # re-planned each cycle
        a_next = np.clip(target, a - jerk * dt, a + jerk * dt)
        want = tuple(p + (v - 0.5 * a * dt) * dt + 0.5 * (a + a_next) * dt * dt)  # (continuous → step velocity)
        cmd, _, _, why = m.next_command(want, ACTIVE, POSITION, want, None, None, False, False)
        assert why is None, why
        clamps.append(float(np.abs(np.array(cmd) - want).max()))
        m.sent(tuple(cmd), ACTIVE)
        exe.append(np.array(cmd))
        ours.append(True)
    v, a, j = _our_ratios(np.array(exe), np.array(ours), dt, lim)
    assert m.extrapolated_cycles == len(gaps) and m.rejoin_cycles == 0 and m.rejoin.done
    assert v <= 1 + 1e-9 and a <= 1 + 1e-9 and j <= 1 + 1e-6, (v, a, j)
    assert max(clamps) < 1e-9, max(clamps)


@pytest.mark.parametrize("gap", [5, 30])
def test_the_offset_back_onto_the_path_after_a_gap_ends_within_the_jerk_limit(gap):
    """A client (not jerk-limited itself) whose path uses 0.9 of the jerk limit — a wave on every joint — loses
    ``gap`` messages in a row; the controller extrapolates. The core joins its path through the gap and brings the
    offset to zero: every step it sends, the offset's last ones and the first after it included, stays within the
    velocity, acceleration and jerk limits of what the controller executed (the offset's end once left the jerk
    check while the path's own jerk filled the limit: 1.48 × in the upright session)."""
    lim, dt = default_limits(), 1e-3
    m = ExecutedMotion(lim, dt, 1e9, 1e9, hold_cycles=1, q=(0.0,) * 7)
    w = 2 * np.pi * 8.0  # [rad/s]
    # (1 − cos wt)²/4 starts at rest; its jerk peaks at 1.5·w³, its acceleration at w² (per unit amplitude)
    amp = 0.9 * lim.jerk / (1.5 * w**3) * np.array([1.0, -1.0, 1.0, -1.0, 1.0, -1.0, 1.0])  # [rad]
    assert np.all(np.abs(amp) * w**2 < 0.5 * lim.acceleration)
    path = lambda k: tuple(amp * (1 - np.cos(w * k * dt)) ** 2 / 4)  # noqa: E731
    exe, ours, rejoined = [np.array(m.prev)] * 3, [True] * 3, 0
    for k in range(1500):
        if k == 400:  # the controller's messages are lost: it extrapolates our last commands
            m.extrapolate(gap)
            for _ in range(gap):
                exe.append(2 * exe[-1] - exe[-2])
                ours.append(False)
            continue
        if 400 <= k < 400 + gap:
            continue
        want = path(k)
        cmd, _, _, why = m.next_command(want, ACTIVE, POSITION, want, None, None, False, False)
        assert why is None, why
        m.sent(tuple(cmd), ACTIVE)
        rejoined = max(rejoined, m.rejoin_cycles)
        exe.append(np.array(cmd))
        ours.append(True)
    v, a, j = _our_ratios(np.array(exe), np.array(ours), dt, lim)
    assert rejoined > 0 and m.rejoin.done
    assert v <= 1 + 1e-9 and a <= 1 + 1e-9 and j <= 1 + 1e-6, (v, a, j)
    assert np.abs(exe[-1] - np.array(path(1499))).max() < 1e-12  # back on the client's path
