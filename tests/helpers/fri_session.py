"""A client application against the scripted controller over loopback, as the FRI tests run it: the preamble of
states, the run, the positions sent, minimum-jerk and ramp moves from the thesis start pose within the limits."""

from __future__ import annotations

import numpy as np
from lbrcli.fri.testing import CA, CW, IDLE, MR, MW, Cycle, ScriptedController
from lbrcli.fri import (
    ClientApplication,
    ExecutionLog,
    LogObserver,
    SessionFigures,
)
from tests.helpers.cli import Q_START
from trajectories.limits import default_limits


Q0 = tuple(Q_START.tolist())  # [rad]


LIM = default_limits()


DIRECTION = np.array([1, 0.5, -0.5, 1, 0.3, -1, 1])


def min_jerk(n: int, amp: float | None = None) -> np.ndarray:
    """(n, 7) rest-to-rest minimum-jerk move from Q0 [rad] at 1 ms rows; the default amplitude keeps the peak
    acceleration (5.77·amp/T²) near 3 rad/s², inside every joint's limit."""
    if amp is None:
        amp = 0.5 * ((n - 1) * 1e-3) ** 2
    s = np.linspace(0.0, 1.0, n)
    p = 10 * s**3 - 15 * s**4 + 6 * s**5
    return np.array(Q0) + amp * p[:, None] * DIRECTION


def preamble(k: int = 1, **kw) -> list[Cycle]:
    return (
        [Cycle(state=IDLE, **kw)]
        + [Cycle(state=MW, quality=1, receive_multiplier=k, **kw)] * 3
        + [Cycle(state=MR, receive_multiplier=k, **kw)] * 3
        + [Cycle(state=CW, receive_multiplier=k, **kw)] * 4
    )


def run(script, client, *, version="1.15", detect=False, tmp_path=None, on_cycle=None, q_start=Q0, duration=None,
        observers=(), prepare=True, controller_type=ScriptedController, **controller):  # fmt: skip
    # the scripted controller sends its unanswered datagrams (stale, garbage, not due) in bursts, not once a period:
    # the client reads each in turn (catch_up off) for the counts to be exact on a loaded machine
    fig = SessionFigures()
    app = ClientApplication(client, "127.0.0.1", 0, bind_host="127.0.0.1", version=None if detect else version,
                            limits=LIM, first_message_timeout_s=10, silence_timeout_s=3, paced_by_replies=True,
                            observers=[fig, *observers], prepare=prepare, catch_up=False)  # fmt: skip
    app.connect()
    ctl = controller_type(app.port, script, q_start, version=version, **controller)
    if on_cycle is not None:
        ctl.on_cycle = lambda i: on_cycle(i, app)
    log_path = tmp_path / "log.csv" if tmp_path is not None else None
    log = ExecutionLog(log_path) if log_path is not None else None
    if log is not None:
        app.observers.insert(0, LogObserver(log))
    ctl.start()
    error = None
    try:
        try:
            res = app.run(duration)
        except Exception as exc:  # noqa: BLE001 - returned to the test
            res, error = None, exc
    finally:
        ctl.finish(app)
        if log is not None:
            log.close()
    return res, ctl, log_path, error


def sent_positions(ctl, state=CA) -> np.ndarray:
    return np.array([r.position for r in ctl.replies if r.state == state and r.position is not None])


def assert_within_limits(q: np.ndarray, dt: float, before: np.ndarray | None = None) -> None:
    """Every step within the velocity limit and every second difference within the acceleration limit."""
    if before is not None:
        q = np.vstack([before, q])
    v = np.abs(np.diff(q, axis=0)) / dt
    assert np.all(v <= LIM.velocity * (1 + 1e-9)), (v / LIM.velocity).max()
    if len(q) > 2:
        a = np.abs(np.diff(q, 2, axis=0)) / dt**2
        assert np.all(a <= LIM.acceleration * (1 + 1e-6)), (a / LIM.acceleration).max()


# -- stops initiated by the client brake within the limits ----------------------------------------------------
def fast_ramp(n: int, speed: float = 0.73, ramp_s: float = 0.4) -> np.ndarray:
    """(n, 7) rows from rest at Q0 that reach ``speed`` × the velocity limit on every joint with a smooth
    acceleration (≤ 0.73 of its limit) and keep that speed (they never end at rest) [rad]."""
    t = np.arange(n) * 1e-3
    w = 2 * np.pi / ramp_s
    s = np.where(t < ramp_s, t**2 / (2 * ramp_s) + (np.cos(w * t) - 1) / (w**2 * ramp_s), ramp_s / 2 + (t - ramp_s))
    return np.array(Q0) + s[:, None] * speed * LIM.velocity
