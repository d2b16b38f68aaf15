"""Application observers that compute a session's figures (after each reply; cheap, allocation-free)."""

from __future__ import annotations

import math
from operator import sub as _sub
from typing import Any

from .constants import Phase

from .constants import STATE_COMMANDING_ACTIVE as _ACTIVE


class SessionFigures:
    """Tracking and ball figures: lowest tracking performance and largest |measured − commanded| [rad] in
    COMMANDING_ACTIVE, largest simulated (or measured) ball tilt from the ``ball_theta`` IO value [rad], and its
    largest value while the last row is held (residual sway)."""

    name = "the session figures"

    def __init__(self, ball_io: str = "ball_theta") -> None:
        self.ball_io = ball_io
        self.active = 0
        self.min_tracking = math.inf
        self.max_err = 0.0  # same cycle
        self.max_err_prev = 0.0  # against the command of the cycle before (one cycle of lag)
        self.max_ball = -math.inf
        self.residual_ball = -math.inf
        self._prev_cmd: Any = None
        self._has_ball: bool | None = None

    def on_cycle(self, app: Any) -> None:
        cyc = app.cycle
        mon = app.state.message
        if self._has_ball is None:
            self._has_ball = any(io.name == self.ball_io for io in mon.monitorData.readIORequest)
        if cyc.state == _ACTIVE:
            self.active += 1
            tp = mon.ipoData.trackingPerformance
            if tp < self.min_tracking:
                self.min_tracking = tp
            msr = mon.monitorData.measuredJointPosition.value
            e = max(map(abs, map(_sub, msr, cyc.command)))
            if e > self.max_err:
                self.max_err = e
            if self._prev_cmd is not None:
                e = max(map(abs, map(_sub, msr, self._prev_cmd)))
                if e > self.max_err_prev:
                    self.max_err_prev = e
            self._prev_cmd = cyc.command
        else:
            self._prev_cmd = None
        if self._has_ball:
            for io in mon.monitorData.readIORequest:
                if io.name == self.ball_io:
                    b = io.analogValue
                    if b > self.max_ball:
                        self.max_ball = b
                    if cyc.phase == Phase.SETTLE and b > self.residual_ball:
                        self.residual_ball = b
                    break

    def figures(self) -> dict[str, Any]:
        ball = self.max_ball if self._has_ball and self.max_ball > -math.inf else None
        resid = self.residual_ball if self._has_ball and self.residual_ball > -math.inf else None
        return {
            "min_tracking": self.min_tracking if self.active else None,
            "max_tracking_error": self.max_err if self.active else None,
            "max_tracking_error_prev": self.max_err_prev if self.active > 1 else None,
            "max_ball_theta": ball,
            "residual_ball_theta": resid,
            "max_ball_theta_deg": math.degrees(ball) if ball is not None else None,
            "residual_ball_theta_deg": math.degrees(resid) if resid is not None else None,
        }
