"""The session's time base and time-outs: controller time from the sequence counter × send period (or the local
clock when the controller sends no period), the command period, and the waits that end a session."""

from __future__ import annotations

import time
from typing import Any


class SessionClock:
    """Times of one session [s]; ``t`` is the controller time of the current message since the first one."""

    __slots__ = ("first_message_timeout_s", "silence_timeout_s", "duration_s", "t_open", "t_first", "t_last_rx",
                 "tick", "t_per_tick", "local_clock", "period_key", "period_s", "quiet_from")  # fmt: skip

    def __init__(self, first_message_timeout_s: float, silence_timeout_s: float, duration_s: float | None) -> None:
        self.first_message_timeout_s = first_message_timeout_s
        self.silence_timeout_s = silence_timeout_s
        self.duration_s = duration_s
        self.t_open = time.monotonic()
        self.t_first: float | None = None  # time.monotonic() of the first message
        self.t_last_rx = self.t_open
        # [s] when the first wait without a message since the last one began: silence counts from there, so time
        # this process spent in its own cycle (a stall, a long callback) is not taken for the controller's silence
        self.quiet_from: float | None = None
        self.tick = 0  # sequence steps since the first message
        self.t_per_tick = 0.0  # [s] the send period
        self.local_clock: float | None = None  # perf_counter() at the first message when there is no send period
        self.period_key: tuple[int, int] | None = None  # (send period [ms], receive multiplier) of the session
        self.period_s: float | None = None  # [s] command period: send period × receive multiplier

    def received(self, now: float, steps: int, send_period_ms: int) -> None:
        """A message ``steps`` sequence steps after the previous one (0 for the first) arrived at ``now``."""
        if self.t_first is None:
            self.t_first = now
            if send_period_ms:
                self.t_per_tick = send_period_ms * 1e-3
            else:
                self.local_clock = time.perf_counter()
        self.tick += steps
        self.t_last_rx = now
        self.quiet_from = None

    @property
    def t(self) -> float:
        """[s] controller time of the current message since the first."""
        if self.local_clock is not None:
            return time.perf_counter() - self.local_clock
        return self.tick * self.t_per_tick

    def learn_period(self, ci: Any) -> bool:
        """Take the session's period from its first message outside IDLE; True when it became known now."""
        if self.period_key is not None:
            return False
        k = ci.receiveMultiplier or 1
        self.period_key = (ci.sendPeriod, k)
        if ci.sendPeriod:
            self.period_s = ci.sendPeriod * 1e-3 * k
            return True
        return False

    def expired(self, now: float, stopping: bool) -> tuple[str, float] | None:
        """Which wait ran out at ``now``: ("first", waited), ("silent", for how long) or ("duration", s); None."""
        if self.t_first is None:
            waited = now - self.t_open
            return ("first", waited) if waited > self.first_message_timeout_s else None
        last = self.t_last_rx if self.quiet_from is None else max(self.t_last_rx, self.quiet_from)
        if now - last > self.silence_timeout_s:
            return ("silent", now - last)
        if self.duration_s is not None and not stopping and now - self.t_first >= self.duration_s:
            return ("duration", self.duration_s)
        return None
