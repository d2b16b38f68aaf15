"""The simulator in lock-step (``SimConfig.lockstep_timeout_s``): it waits for the reply the client owes before its
next cycle and its time advances one period per cycle — a client that answers three periods late (a busy machine)
runs the session a real-time controller would have dropped, with every reply timely and an exact clock; a client that
stops answering is waited for once, not every cycle."""

from __future__ import annotations

import pytest

import time

import numpy as np

from lbrcli.fri.sim import SimConfig, SimulatorProcess

from tests.helpers.scripted_client import ScriptedClient
from lbrcli.fri.testing import CA, IDLE, MW
from tests.helpers.sim import TEST_DEFAULTS, assert_sequence


def _session(answer=None, policy=None, client_timeout=20.0, **cfg):
    client = ScriptedClient()
    config = SimConfig(client_port=client.port, **{**TEST_DEFAULTS, "lockstep_timeout_s": 0.5, **cfg})
    try:
        with SimulatorProcess(config) as sim:
            run = client.run(policy, timeout=client_timeout, answer_monitoring=answer)
            stats = sim.wait(30.0) or sim.stop()
    finally:
        client.close()
    return run, stats


def _late(r) -> bool:
    time.sleep(0.012)  # three 4 ms periods, every message
    return True


@pytest.mark.heavy
def test_a_client_three_periods_late_keeps_an_exact_session():
    def policy(k, q0):
        time.sleep(0.012)
        q = q0.copy()
        q[6] += 2e-4 * k  # [rad] a slow ramp on A7
        return q

    run, stats = _session(answer=_late, policy=policy, session_duration_s=0.3)
    assert_sequence(run.states)
    # late only before its first reply (the messages sent while the simulator did not know yet that it answers: how many
    # depends on how soon this machine runs the client), never once commanding
    assert stats.end_reason == "duration" and stats.late_replies < 0.1 * stats.replies and stats.missed_replies <= 1, (
        stats
    )
    assert stats.untimely_active_cycles == 0
    # the controller's clock: exactly one period per message, however long the client took
    ns = np.array([s * 1_000_000_000 + n for s, n in (r.stamp for r in run.received)], dtype=np.int64)
    assert np.all(np.diff(ns) == 4_000_000)
    # the session lasted 0.3 s of its own time (75 active cycles), though it took more than twice as long here
    active = run.where(CA)
    assert abs(len(active) - 75) <= 2
    assert active[-1].t - active[0].t > 2.5 * 0.3
    # every command was followed: A7 ramps without a step
    dq = np.diff([r.msr_q[6] for r in active[len(active) // 3 :]])
    assert np.all(dq > 0.5 * 2e-4)
    assert abs(np.median(dq) - 2e-4) < 0.2e-4


@pytest.mark.heavy
def test_the_same_client_in_real_time_never_gets_past_monitoring_wait():
    client = ScriptedClient()
    config = SimConfig(client_port=client.port, **{**TEST_DEFAULTS, "max_runtime_s": 0.6})
    try:
        with SimulatorProcess(config) as sim:
            client.run(None, timeout=3.0, answer_monitoring=_late)
            stats = sim.wait(10.0) or sim.stop()
    finally:
        client.close()
    assert stats.states_seen == (MW, IDLE) and stats.late_replies > 0.8 * stats.replies


@pytest.mark.heavy
def test_a_client_that_stops_answering_is_waited_for_once():
    silent: list[int] = []

    def policy(k, q0):
        if k >= 40:
            silent.append(k)
            return None
        return q0

    run, stats = _session(answer=lambda r: not silent, policy=policy)
    elapsed = run.received[-1].t - run.received[0].t  # [s] first to last message (not the processes' start-up)
    states = run.states
    assert states[states.index(CA) + 1 :] == [MW, IDLE] and stats.end_reason == "quality"
    # the quality rule needed ≥ 13 unanswered cycles; waiting 0.5 s for each would have taken ≥ 6.5 s
    assert stats.missed_replies >= 3 and elapsed < 6.0, elapsed


def test_a_bad_reply_wait_is_refused():
    import pytest

    from trajectories.errors import OptionError

    for bad in (0.0, -1.0, float("nan"), 61.0):
        with pytest.raises(OptionError, match="SimConfig.lockstep_timeout_s"):
            SimConfig(client_port=1, lockstep_timeout_s=bad).validate()


@pytest.mark.heavy
def test_fast_lock_step_runs_the_same_session_as_paced_lock_step():
    """``lockstep_free`` (--sim-fast) starts each cycle when the reply is in, not on the period's grid: the session the
    client sees — stamps one period apart, every command followed, the measured joints — is the paced one's."""

    def policy(k, q0):
        q = q0.copy()
        q[6] += 2e-4 * k  # [rad] a slow ramp on A7
        return q

    sessions = {}
    for free in (False, True):
        run, stats = _session(policy=policy, session_duration_s=0.3, lockstep_free=free)
        assert_sequence(run.states)
        assert stats.end_reason == "duration" and stats.untimely_active_cycles == 0, stats
        ns = np.array([s * 1_000_000_000 + n for s, n in (r.stamp for r in run.received)], dtype=np.int64)
        assert np.all(np.diff(ns) == 4_000_000)
        active = run.where(CA)
        assert abs(len(active) - 75) <= 2
        sessions[free] = np.array([r.msr_q for r in active])
    paced, fast = sessions[False], sessions[True]
    n = min(len(paced), len(fast))
    assert n >= 70 and np.array_equal(paced[:n], fast[:n])  # joint for joint, cycle for cycle


def test_fast_lock_step_needs_lock_step():
    import pytest

    from trajectories.errors import OptionError

    with pytest.raises(OptionError, match="SimConfig.lockstep_free"):
        SimConfig(client_port=1, lockstep_free=True).validate()
