"""How a session ended: outcome and reason enums and the figures of a session."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import Enum
from typing import Any

from .constants import SessionState


class Outcome(str, Enum):
    """How a session ended, as a whole (the value is what the commands' JSON reports as `outcome`)."""

    COMPLETED = "completed"  # the client finished (or the monitoring duration elapsed)
    INTERRUPTED = "interrupted"  # Ctrl-C or SIGTERM
    STOPPED = "stopped"  # the robot side ended or broke the session
    REFUSED = "refused"  # the guard or the client refused to go on
    FAILED = "failed"  # the client side failed (log not writable, observer error)


class EndReason(str, Enum):
    """Why a session ended (the value is what the commands' JSON reports as `reason`)."""

    FINISHED = "finished"  # the client said it is done
    DURATION = "duration"  # run(duration_s) elapsed
    SIGINT = "sigint"
    SIGTERM = "sigterm"
    CLIENT_REFUSED = "client_refused"  # the client raised StopSession(completed=False)
    BAD_INPUT = "bad_input"  # ... because its input does not fit this controller (e.g. another period)
    GUARD = "guard"  # a command failed the guard
    CLIENT_ERROR = "client_error"  # a client callback raised
    OBSERVER_FAILED = "observer_failed"  # e.g. the log could not be written
    SUPERVISION = "supervision"  # measured vs commanded, timing, counters
    SAFETY_STOP = "safety_stop"
    DRIVES_OFF = "drives_off"
    QUALITY_POOR = "quality_poor"
    LEFT_COMMANDING = "left_commanding"
    IDLE = "idle"  # the robot application closed the session
    PERIOD_CHANGED = "period_changed"
    SILENT = "silent"  # no message for silence_timeout_s
    NO_COMMANDING = "no_commanding"  # the application did not start commanding in time


@dataclass(frozen=True)
class SessionResult:
    """What happened in a session (latencies in ms, CPU in µs)."""

    outcome: Outcome
    reason: EndReason
    detail: str  # one line for people
    version: str  # FRI wire format used
    cycles: int  # monitoring messages accepted
    answered: int  # command messages sent
    position_commands: int  # of which carried a joint position
    missed: int  # gaps in the controller's sequence counter
    stale: int  # not newer than the last accepted (duplicates, reordering): ignored
    foreign: int  # from another address: ignored
    malformed: int  # undecodable or not self-consistent: never answered
    states_seen: tuple[int, ...]
    period_s: float | None  # command period (send period × receive multiplier) [s]
    active_cycles: int  # cycles in COMMANDING_ACTIVE
    braking_cycles: int  # cycles of the client-initiated braking stop (0: none)
    unanswered_at_start: int  # messages of the session start (before the first reply) left unanswered
    latency_p50_ms: float | None  # receive → reply, inside the client
    latency_p99_ms: float | None
    latency_max_ms: float | None
    cpu_us_per_cycle: float | None
    extrapolated_cycles: int = 0  # command periods the controller bridged because its messages were lost
    largest_tracking_error_rad: float | None = None  # max |measured − commanded| in COMMANDING_ACTIVE (position)
    largest_reply_gap: int | None = None  # most controller messages between two replies of ours it received
    prepared_replies: int = 0  # answered with the reply prepared after the previous cycle (LBRClient.prepare_command)
    lost_replies: int = 0  # our commands the controller reported not received while moving (it extrapolated)
    clamped_cycles: int = 0  # commands the motion-safety core clamped into the braking envelope
    largest_clamp_rad: float = 0.0  # [rad] the largest change such a clamp made
    figures: dict[str, Any] = field(default_factory=dict)  # from the observers

    @property
    def ok(self) -> bool:
        return self.outcome is Outcome.COMPLETED

    @property
    def end_reason(self) -> str:
        return self.detail

    def to_dict(self) -> dict[str, Any]:
        d = {k: getattr(self, k) for k in self.__dataclass_fields__ if k != "figures"}
        d["outcome"] = self.outcome.value
        d["reason"] = self.reason.value
        d["end_reason"] = self.detail
        d["states_seen"] = [SessionState(s).name for s in self.states_seen]
        d["ok"] = self.ok
        d.update(self.figures)
        return d


def cost_figures_us(cost_ns: list[int]) -> dict[str, float | None]:
    """``controller_us_p50``, ``_p99``, ``_max`` [µs] of per-cycle costs [ns] (Nones when empty)."""
    c = sorted(cost_ns)

    def pick(p: float) -> float | None:
        return None if not c else _percentile_ms(c, p) * 1e3

    return {"controller_us_p50": pick(50), "controller_us_p99": pick(99), "controller_us_max": pick(100)}


def _percentile_ms(sorted_ns: list[int], p: float) -> float | None:
    if not sorted_ns:
        return None
    k = min(len(sorted_ns) - 1, max(0, int(math.ceil(p / 100.0 * len(sorted_ns))) - 1))
    return sorted_ns[k] * 1e-6


def session_result(app: Any, outcome: Outcome, reason: EndReason, text: str, figures: dict[str, Any], *,
                   cpu_s: float, cpu_cycles: int) -> SessionResult:  # fmt: skip
    """The result of ``app``'s session (a ClientApplication: its counters, latencies [ns] and supervisor)."""
    lat = sorted(app.latencies)
    sup = app._sup
    return SessionResult(
        outcome=outcome,
        reason=reason,
        detail=text,
        version=app.version.value if app.version else "",
        cycles=app.cycles,
        answered=app.answered,
        position_commands=app.position_commands,
        missed=app.missed,
        stale=app.stale,
        foreign=app.transport.foreign if app.transport is not None else 0,
        malformed=app.malformed,
        states_seen=tuple(app.states_seen),
        period_s=app.period_s,
        active_cycles=app.active_cycles,
        braking_cycles=app.braking_cycles,
        unanswered_at_start=app.unanswered_at_start,
        latency_p50_ms=_percentile_ms(lat, 50),
        latency_p99_ms=_percentile_ms(lat, 99),
        latency_max_ms=lat[-1] * 1e-6 if lat else None,
        cpu_us_per_cycle=cpu_s / cpu_cycles * 1e6 if cpu_cycles > 0 else None,
        extrapolated_cycles=app.extrapolated_cycles,
        largest_tracking_error_rad=sup.largest_tracking_error if sup is not None else None,
        largest_reply_gap=sup.largest_reply_gap if sup is not None else None,
        prepared_replies=app.prepared_replies,
        lost_replies=app.lost_replies,
        clamped_cycles=app._motion.clamped_cycles if app._motion is not None else 0,
        largest_clamp_rad=app._motion.largest_clamp if app._motion is not None else 0.0,
        figures=figures,
    )
