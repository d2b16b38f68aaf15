import numpy as np

from lbrcli.fri.testing.holding import reference_histories, step_ratios
from trajectories.limits import default_limits


def test_after_a_hold_the_reference_is_the_robot_at_rest_and_after_our_steps_the_history_itself():
    """A robot moving at 0.5 rad/s on every joint that the controller held for one period: the next command is judged
    from rest there (continuing the old velocity is ~2,700× the jerk limit, a step of J·dt³ is exactly at it); on
    the steps it applied in time, against the three positions before."""
    lim, dt = default_limits(), 1e-3
    v = 0.5 * dt * np.ones(7)
    x = [k * v for k in range(5)] + [4 * v]  # messages 0..5 report these; message 5 reports the hold
    ours = [True] * 5 + [False]
    follows = [False] + [True] * 5
    hist = reference_histories([(x[i], x[i - 1], x[i - 2]) if i >= 2 else None for i in range(6)], ours, follows,
                               dt, lim)  # fmt: skip
    assert hist[1] is None and np.allclose(hist[4][2], 2 * v)
    assert all(np.array_equal(h, 4 * v) for h in hist[5])  # held: at rest
    on = step_ratios(np.array([x[5] + v, x[5] + lim.jerk * dt**3]), [hist[5], hist[5]], lim)
    assert on[0, 2] > 1000 and abs(on[1, 2] - 1.0) < 1e-9
    steady = step_ratios(np.array([5 * v]), [hist[4]], lim)  # the next step of the steady motion
    assert np.allclose(steady[0], [0.5 / lim.velocity.min(), 0.0, 0.0], atol=1e-9)
