"""The reference tracker's hold: at rest it stays without planning; moving, it stops as ruckig plans the stop."""

from __future__ import annotations

import numpy as np

from lbrcli.bridge.tracker import ReferenceTracker
from trajectories.limits import default_limits

LIM = default_limits()
Q0 = np.array([0.1, 0.5, -0.2, -1.2, 0.3, 0.4, -0.1])  # [rad]


def test_hold_at_rest_stays_put_and_counts_the_cycle_on_the_reference() -> None:
    tr = ReferenceTracker(LIM, 1e-3, Q0)
    for _ in range(3):
        q = tr.hold()
    np.testing.assert_array_equal(q, Q0)
    assert not tr.v.any() and not tr.a.any() and tr.on_reference == 3 and tr.intercept_s == 1e-3


def test_hold_while_moving_is_the_planned_stop_at_the_held_position() -> None:
    v = 0.3 * np.asarray(LIM.velocity)  # [rad/s] moving, no acceleration
    a, b = ReferenceTracker(LIM, 1e-3, Q0), ReferenceTracker(LIM, 1e-3, Q0)
    a.reset(Q0, v, np.zeros(7))
    b.reset(Q0, v, np.zeros(7))
    for _ in range(200):  # against the same reference through step: the commanded state at rest where it stopped
        q_hold = a.hold()
        here = b.q.copy()
        q_step = b.step(lambda t: (here, np.zeros(7), np.zeros(7)))
        np.testing.assert_allclose(q_hold, q_step, rtol=0, atol=1e-12)
    assert np.all(np.abs(a.q - Q0) > 0) and not np.abs(a.v).max() > 1e-9  # it went on and came to rest
    assert a.catching_up > 0


# a state the follower reached (a pose target through the online IK, the reference computed after the reply) for
# which ruckig's step 2 fails to synchronise A2 ("error in step 2 in dof: 1 for t sync"): exactly these floats
EDGE = dict(
    current_position=[-0.16009237092641143, 0.27678432361499233, -0.009637894799277985, -0.9278241869847264,
                      0.3297407417615096, 0.5701387967586599, -0.2059558886692544],
    current_velocity=[-0.1368766748723939, 0.10465201591692083, -0.012659331754213039, 0.1308656140426462,
                      0.22967170570265982, 0.3274102291477995, -0.27829351620956755],
    current_acceleration=[4.164640260065369, -3.7640846287259913, 0.0, -4.706925505432068, -6.1173790282401255,
                          -7.862708280234455, 2.4051470412096085],
    target_position=[-0.16268029564685746, 0.27872406825026214, -0.010189286441801493, -0.9253985684024042,
                     0.33438475140290813, 0.5772111781129571, -0.21279712891243097],
    target_velocity=[0.0] * 7,
    target_acceleration=[0.0] * 7,
)  # fmt: skip


def test_a_state_on_ruckigs_numerical_edge_is_planned_not_refused() -> None:
    """The tracker retries such a state with its velocity (then acceleration) smaller by a relative 1e-9 (1e-7):
    the plan it gets starts within 1e-9 rad/s of the state and takes the time-optimal duration (a refusal would end
    `lbr serve`'s session)."""
    from lbrcli.bridge.tracker import _OK

    tr = ReferenceTracker(LIM.scaled(0.5), 1e-3, EDGE["current_position"])
    for name, value in EDGE.items():
        setattr(tr._inp, name, value)
    assert tr._calculate() in _OK
    assert abs(tr._traj.duration - 0.0556089) < 1e-6  # [s] as for the neighbouring states
    _, v0, a0 = tr._traj.at_time(0.0)
    assert np.abs(np.subtract(v0, EDGE["current_velocity"])).max() < 1e-9
    assert np.abs(np.subtract(a0, EDGE["current_acceleration"])).max() < 1e-6
