"""The bridge's follower in lock step with a scripted controller: a fake clock (cycle × period) and a source whose
targets arrive late and in bursts — deterministic on any machine, for tests and the benchmark's bands.

    run = follow_in_lock_step(LockStepSource(1000.0, feed_forward=True), limits, drop=0.05)
    run.t, run.q  # [s] from activation, [rad] what the controller received each cycle
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from lbrcli.fri import ClientApplication
from lbrcli.fri.testing import CA, Cycle, ScriptedController, preamble
from trajectories.limits import JointLimits

from .protocol import Target
from .follower import TargetFollower
from .timeline import TimelineOptions

Q0 = (0.0, 0.5, 0.0, -1.2, 0.0, 0.8, 0.0)  # [rad] away from the wrist singularity
AMP = 0.15  # [rad] the wave on A1: AMP · (1 − cos πt), 0.47 rad/s and 1.48 rad/s² at most


def wave(t: float) -> tuple[float, float]:
    """[rad], [rad/s] of the test motion at ``t`` [s] (at rest before 0)."""
    if t <= 0.0:
        return 0.0, 0.0
    return AMP * (1 - math.cos(math.pi * t)), AMP * math.pi * math.sin(math.pi * t)


class LockStepSource:
    """A :class:`~lbrcli.bridge.inbox.TargetInbox` stand-in: ``wave`` on A1 sampled at ``rate_hz`` (spacing
    uniform in [0.5, 1.5] periods), each target ``lateness_s`` (exponential mean) late, 1 % of them ``burst_s``
    more; with ``feed_forward`` the velocity too. Targets become visible at their arrival on ``clock``."""

    def __init__(self, rate_hz: float, feed_forward: bool = True, seed: int = 0, seconds: float = 3.0,
                 lateness_s: float = 0.002, burst_s: float = 0.03, motion: Callable = wave,
                 q0: Sequence[float] = Q0) -> None:  # fmt: skip
        rng = np.random.default_rng(seed)
        sends, t = [], 0.0
        while t < seconds:
            late = rng.exponential(lateness_s) + (burst_s if rng.random() < 0.01 else 0.0)
            sends.append((t, t + late))
            t += rng.uniform(0.5, 1.5) / rate_hz
        sends.sort(key=lambda s: s[1])
        self.sends = sends
        self.feed_forward, self.motion, self.q0 = feed_forward, motion, np.asarray(q0, dtype=float)
        self.now = 0.0  # [s] the fake clock
        self.i, self.last_t = 0, -1.0
        self.latest: Target | None = None
        self.latest_time, self.fresh = 0.0, False
        self.error, self.ended, self.owner = None, False, None

    def poll(self) -> None:
        while self.i < len(self.sends) and self.sends[self.i][1] <= self.now:
            ts, arrival = self.sends[self.i]
            self.i += 1
            if ts <= self.last_t:
                continue  # overtaken by a newer one: stale
            self.last_t = ts
            q, v = self.motion(ts)
            dq = np.zeros(7)
            dq[0] = v
            self.latest = Target(
                tuple(self.q0 + np.eye(7)[0] * q), tuple(dq) if self.feed_forward else None, seq=self.i, t=ts + 100.0
            )  # (the source's clock need not start at 0)
            self.latest_time, self.fresh = arrival, True

    def send(self, data: bytes) -> None:
        pass

    def figures(self) -> dict:
        return {}


@dataclass(frozen=True)
class LockStepRun:
    follower: TargetFollower
    controller: ScriptedController
    t: np.ndarray  # [s] from activation, per command the controller received
    q: np.ndarray  # (n, 7) [rad] those commands
    q0: np.ndarray  # [rad]


def follow_in_lock_step(source: LockStepSource, limits: JointLimits, *, drop: float = 0.0, seed: int = 0,
                        cycles: int = 3000, speed_scale: float = 0.5,
                        timeline: TimelineOptions = TimelineOptions(), controller: Callable = ScriptedController,
                        at: dict[int, Cycle] | None = None, version: str = "1.15") -> LockStepRun:  # fmt: skip
    """``cycles`` COMMANDING_ACTIVE cycles at 1 ms, a share ``drop`` of the replies lost on the way; ``at``: cycles
    that replace those COMMANDING_ACTIVE cycles (by index); ``controller(port, script, q0, tolerate_unanswered)``
    (e.g. a :class:`~lbrcli.fri.testing.holding.BurstController` partial)."""
    rng = np.random.default_rng(seed)
    follower = TargetFollower(source, limits, timeout_s=0.5, speed_scale=speed_scale, timeline=timeline,  # type: ignore[arg-type]
                              clock=lambda: source.now)  # fmt: skip
    script = preamble() + [Cycle(state=CA, drop_reply=bool(d)) for d in rng.random(cycles) < drop]
    start = len(preamble())
    for i, c in (at or {}).items():
        script[start + i] = c
    app = ClientApplication(follower, "127.0.0.1", 0, bind_host="127.0.0.1", version=version, limits=limits,
                            first_message_timeout_s=10, silence_timeout_s=3, paced_by_replies=True,
                            catch_up=False)  # fmt: skip  # the scripted controller waits for each reply
    app.connect()
    ctl = controller(app.port, script, tuple(source.q0), tolerate_unanswered=10**6, version=version)
    ctl.on_cycle = lambda i: setattr(source, "now", max(0, i - start) * 1e-3)
    ctl.start()
    try:
        app.run()
    finally:
        ctl.finish(app)
    sent = [(r.cycle, r.position) for r in ctl.replies if r.state == CA and r.position is not None]
    t = (np.array([c for c, _ in sent]) - start) * 1e-3
    return LockStepRun(follower, ctl, t, np.array([p for _, p in sent]), source.q0)
