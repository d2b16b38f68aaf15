"""The FRI client that follows targets from a source: ruckig online between targets, the dead-man rule.

Every cycle it drains the source, retargets ruckig (position interface, at ``speed_scale`` of the velocity,
acceleration and jerk limits) on the newest target [rad] with its velocity feed-forward [rad/s], and commands
ruckig's next position — so a 30 Hz or jittery source still gives a smooth stream at the FRI period, and the
application's guard checks every command. It ends with :class:`~lbrcli.fri.StopSession` (the application brakes
within the limits): when no target arrived for ``timeout_s`` after the first (or none within ``first_target_s``),
when the owning source sends something that is not a target, or when it sends the end message (completed).
"""

from __future__ import annotations

import time
from typing import Sequence

from ruckig import InputParameter, OutputParameter, Result, Ruckig

from lbrcli.fri import LBRClient, LBRState, StopSession
from trajectories.limits import JointLimits

from .protocol import encode_state
from .udp import UdpTargets

_ZERO7 = [0.0] * 7


class TargetFollower(LBRClient):
    """Follows ``source``'s targets; sends the state back every ``state_every`` messages (0: never)."""

    def __init__(self, source: UdpTargets, limits: JointLimits, *, timeout_s: float = 0.1, first_target_s: float = 30.0,
                 speed_scale: float = 0.5, state_every: int = 1) -> None:  # fmt: skip
        if not (0 < speed_scale <= 1):
            raise ValueError(f"speed_scale must be in (0, 1], got {speed_scale}")
        self.source = source
        self.limits = limits
        self.timeout_s = timeout_s
        self.first_target_s = first_target_s
        self.state_every = state_every
        lim = limits.scaled(speed_scale)
        self._vmax = [0.99 * v for v in lim.velocity.tolist()]  # feed-forward within what ruckig may reach
        self._upper = limits.position.tolist()  # [rad] symmetric: |q| ≤ position
        self._lower = [-x for x in self._upper]
        self._otg: Ruckig | None = None
        self._inp = InputParameter(7)
        self._out = OutputParameter(7)
        self._inp.max_velocity = lim.velocity.tolist()
        self._inp.max_acceleration = lim.acceleration.tolist()
        self._inp.max_jerk = lim.jerk.tolist()
        self._t_start = 0.0  # [s] time.monotonic() at activation
        self._count = 0
        self._seq = 0
        self._q: Sequence[float] | None = None
        # figures
        self.targets_followed = 0

    def _check_source(self, now: float) -> None:
        src = self.source
        src.poll()
        if src.error is not None:
            raise StopSession(f"the source sent something that is not a target: {src.error}", completed=False)
        if src.ended:
            raise StopSession("the source ended the session", completed=True)
        if src.latest is None:
            if now - self._t_start > self.first_target_s:
                raise StopSession(f"no target arrived within {self.first_target_s:g} s of commanding", completed=False)
        elif now - src.latest_time > self.timeout_s:
            raise StopSession(f"dead-man: no target for {(now - src.latest_time) * 1e3:.0f} ms "
                              f"(more than {self.timeout_s * 1e3:g} ms)", completed=False)  # fmt: skip

    def _send_state(self, state: LBRState, q: Sequence[float], braking: bool = False) -> None:
        self._count += 1
        if not self.state_every or self._count % self.state_every:
            return
        src = self.source
        if src.owner is None:
            return
        msg = state.message
        tgt = src.latest
        self._seq += 1
        src.send(encode_state(msg.connectionInfo.sessionState, braking, self._otg is not None, self._seq,
                              (tgt.seq or 0) if tgt else 0, tgt.t if tgt else 0.0, state.timestamp,
                              msg.monitorData.measuredJointPosition.value, q, msg.monitorData.externalTorque.value))  # fmt: skip

    def monitor(self, state: LBRState) -> None:
        self.source.poll()
        self._send_state(state, state.measured_joint_position)

    def wait_for_command(self, state: LBRState) -> None:
        self.source.poll()
        self.hold_ipo(state)
        self._send_state(state, state.ipo_joint_position)

    def command(self, state: LBRState) -> Sequence[float]:
        now = time.monotonic()
        inp = self._inp
        if self._otg is None:  # activation: start from where the controller holds the robot, at rest
            self._t_start = now
            self._otg = Ruckig(7, state.sample_time * state.receive_multiplier)
            inp.current_position = list(state.ipo_joint_position)
            inp.current_velocity = list(_ZERO7)
            inp.current_acceleration = list(_ZERO7)
            inp.target_position = list(state.ipo_joint_position)
            inp.target_velocity = list(_ZERO7)
            self._q = state.ipo_joint_position
        self._check_source(now)
        if not self.reply_due:
            return self._q  # type: ignore[return-value]
        if self.skipped:  # the controller extrapolated our last command at its velocity: continue from there
            dt = self._otg.delta_time
            inp.current_position = [p + self.skipped * v * dt for p, v in zip(inp.current_position, inp.current_velocity)]
            inp.current_acceleration = list(_ZERO7)
        src = self.source
        if src.fresh:
            src.fresh = False
            tgt = src.latest
            q = tgt.q  # type: ignore[union-attr]
            for j in range(7):
                if not self._lower[j] <= q[j] <= self._upper[j]:
                    raise StopSession(f"the target for A{j + 1} ({q[j]:.4f} rad) is outside its position limits "
                                      f"[{self._lower[j]:g}, {self._upper[j]:g}]", completed=False)  # fmt: skip
            inp.target_position = list(q)
            v = tgt.v  # type: ignore[union-attr]
            inp.target_velocity = [max(-m, min(m, x)) for x, m in zip(v, self._vmax)] if v is not None else list(_ZERO7)
            self.targets_followed += 1
        res = self._otg.update(inp, self._out)
        if res not in (Result.Working, Result.Finished):
            raise StopSession(f"ruckig could not follow the target ({res.name})", completed=False)
        self._out.pass_to_input(inp)
        q = self._out.new_position
        self._q = q
        self._send_state(state, q)
        return q

    def figures(self) -> dict:
        f = dict(self.source.figures())
        f["targets_followed"] = self.targets_followed
        return f
