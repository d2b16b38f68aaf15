"""A fault campaign for any FRI client: run it against the scripted controller case by case and judge what it sent.

A :class:`Case` is a controller script (states, faults per cycle), a factory for a fresh client, the session ends it
may have, and hooks that play the client's world (a sensor read as analog inputs, a source sending targets, a signal
at a given cycle, a disk that fills). :func:`run_case` runs it and returns a :class:`CaseResult` with what a judge
of the robot would see: every command's velocity, acceleration and jerk relative to what the robot executed (the
controller's extrapolation included), whether the client left the robot moving when it ended the session itself (a
stop that was not a braking stop), how it left a torque or wrench, tracebacks, and whether its log reads back.
"""

from __future__ import annotations

import contextlib
import resource
import signal
import tempfile
import traceback as tb
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator, Sequence

from trajectories.csvio import read_table
from trajectories.limits import JointLimits, default_limits
from trajectories.start_poses import THESIS_START

from ..application import ClientApplication
from ..client import LBRClient
from ..log import LOG_COLUMNS, ExecutionLog, LogObserver
from ..outcome import EndReason, SessionResult
from .scripted import Cycle, ScriptedController

# ends the client side initiates: the robot must be left at rest (a braking stop), and a torque or wrench ramped out
CLIENT_ENDS = frozenset({EndReason.FINISHED, EndReason.GUARD, EndReason.CLIENT_REFUSED, EndReason.CLIENT_ERROR,
                         EndReason.BAD_INPUT, EndReason.SIGINT, EndReason.SIGTERM, EndReason.OBSERVER_FAILED,
                         EndReason.DURATION})  # fmt: skip
REST = 1e-6  # fraction of the velocity limit below which the last command left the robot at rest
EFFORT_REST = 1e-3  # [Nm or N] the effort a stop may leave


@dataclass
class Run:
    """What a case's hooks see while it runs."""

    app: ClientApplication
    controller: ScriptedController
    client: LBRClient
    state: dict[str, Any] = field(default_factory=dict)  # free for the hooks


@dataclass
class Case:
    """One session of one client against the scripted controller."""

    name: str
    category: str
    script: list[Cycle]
    client: Callable[[], LBRClient]  # a fresh client
    expect: tuple[EndReason, ...]  # acceptable ends
    surface: str = "client"
    q_start: tuple[float, ...] = THESIS_START  # [rad] where the robot stands
    period_s: float = 1e-3
    limits: JointLimits | None = None
    # the controller waits 1 s for each reply (a loaded machine is slow, a message that must not be answered costs that)
    controller: dict[str, Any] = field(default_factory=lambda: dict(tolerate_unanswered=1000, reply_timeout=1.0))
    on_cycle: Callable[[int, Run], None] | None = None  # before the controller sends script cycle i
    inputs: Callable[[int, Run], dict[str, float]] | None = None  # analog inputs of script cycle i (a sensor)
    around: Callable[[Run], Any] | None = None  # a context manager around the session (a source's thread, …)
    full_disk_at: int | None = None  # the log's file system fills at this script cycle
    log: bool = True
    log_extra: Callable[[LBRClient], tuple[tuple[str, ...], Callable | None]] | None = None  # (names, values(state))
    version: str = "1.15"
    jerk_judged: bool = True  # its commands must keep the jerk limit too (not a user's own client: the core holds
    # what it asks for to the velocity and acceleration limits, not to the jerk limit)


@dataclass(frozen=True)
class CaseResult:
    name: str
    category: str
    surface: str
    outcome: str
    reason: str
    detail: str
    velocity_ratio: float  # largest |step| / (velocity limit × period) against the executed positions
    acceleration_ratio: float  # largest |second difference| / (acceleration limit × period²)
    jerk_ratio: float  # largest |third difference| / (jerk limit × period³)
    end_velocity: float  # the last command's speed / velocity limit
    non_braking_stop: bool  # the client ended the session itself and left the robot moving (or an effort on)
    effort_step: float  # [Nm or N] largest change of the commanded torque or wrench between two replies
    clamped_cycles: int
    traceback: str | None
    log_readable: bool
    log_rows: int
    expected: bool
    jerk_judged: bool = True  # the case's jerk ratio counts (Case.jerk_judged)

    @property
    def within_limits(self) -> bool:
        return (self.velocity_ratio <= 1.0 + 1e-9 and self.acceleration_ratio <= 1.0 + 1e-9
                and (not self.jerk_judged or self.jerk_ratio <= 1.0 + 1e-6))  # fmt: skip

    @property
    def ok(self) -> bool:
        return (self.traceback is None and self.within_limits and not self.non_braking_stop and self.log_readable
                and self.expected)  # fmt: skip


@contextlib.contextmanager
def _disk_full(path: Path, at: int | None, ctl: ScriptedController) -> Iterator[None]:
    """From script cycle ``at`` on, writes beyond the log's size + 50 bytes fail (EFBIG through RLIMIT_FSIZE, with
    SIGXFSZ ignored): a file system that fills in the middle of a row."""
    if at is None:
        yield
        return
    old_sig = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    before = ctl.on_cycle

    def fill(i: int) -> None:
        if before is not None:
            before(i)
        if i == at:
            resource.setrlimit(resource.RLIMIT_FSIZE, (path.stat().st_size + 50, hard))

    ctl.on_cycle = fill
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
        signal.signal(signal.SIGXFSZ, old_sig)


def run_case(case: Case, folder: Path | None = None) -> CaseResult:
    """Run one case (its log goes to ``folder``, a temporary one by default) and judge it."""
    if folder is None:
        with tempfile.TemporaryDirectory() as tmp:
            return run_case(case, Path(tmp))
    lim = case.limits or default_limits()
    client = case.client()
    app = ClientApplication(client, "127.0.0.1", 0, bind_host="127.0.0.1", version=case.version, limits=lim,
                            first_message_timeout_s=10, silence_timeout_s=3, paced_by_replies=True,
                            catch_up=False)  # fmt: skip  # the scripted controller waits for each reply
    app.connect()
    ctl = ScriptedController(app.port, case.script, tuple(case.q_start), version=case.version, **case.controller)
    run = Run(app, ctl, client)
    if case.on_cycle is not None:
        ctl.on_cycle = lambda i: case.on_cycle(i, run)  # type: ignore[misc]
    if case.inputs is not None:
        ctl.inputs = lambda i: case.inputs(i, run)  # type: ignore[misc]
    path = folder / f"log_{abs(hash(case.name)) % 10**12}.csv"
    log = ExecutionLog(path) if case.log else None
    if log is not None:
        names, extra = case.log_extra(client) if case.log_extra is not None else ((), None)
        app.observers.append(LogObserver(log, names, extra))
    if hasattr(client, "figures"):
        app.observers.append(client)  # type: ignore[arg-type]
    error = None
    res: SessionResult | None = None
    try:
        with contextlib.ExitStack() as stack:
            if case.around is not None:
                stack.enter_context(case.around(run))
            stack.enter_context(_disk_full(path, case.full_disk_at, ctl))
            ctl.start()
            res = app.run()
    except Exception as exc:  # noqa: BLE001 - a traceback is a finding
        error = f"{type(exc).__name__}: {exc}\n" + "".join(tb.format_tb(exc.__traceback__)[-3:])
    finally:
        ctl.finish(app)
        if log is not None:
            log.close()
    readable, rows = True, 0
    if path.exists():
        try:
            rows = len(read_table(path, LOG_COLUMNS, time="increasing").column("t"))
        except Exception:  # noqa: BLE001
            readable = False
        path.unlink()
    v, a, j = ctl.motion_ratios(lim.velocity, lim.acceleration, lim.jerk)
    end_v = ctl.end_velocity(lim.velocity)
    effort_step, effort_end = ctl.efforts()
    client_end = res is not None and res.reason in CLIENT_ENDS and res.active_cycles > 0
    non_braking = client_end and (end_v > REST or effort_end > EFFORT_REST)
    return CaseResult(case.name, case.category, case.surface, res.outcome.value if res else "traceback",
                      res.reason.value if res else "-", res.detail if res else "", v, a, j, end_v, non_braking,
                      effort_step, res.clamped_cycles if res else 0, error, readable, rows,
                      res is not None and res.reason in case.expect, case.jerk_judged)  # fmt: skip


def summarize(results: Sequence[CaseResult]) -> dict[str, dict[str, Any]]:
    """Per surface: cases, ok, worst ratios, non-braking stops, tracebacks, unreadable logs, unexpected ends."""
    out: dict[str, dict[str, Any]] = {}
    for surface in sorted({r.surface for r in results}):
        rs = [r for r in results if r.surface == surface]
        out[surface] = {
            "cases": len(rs),
            "ok": sum(r.ok for r in rs),
            "worst_velocity_ratio": max(r.velocity_ratio for r in rs),
            "worst_acceleration_ratio": max(r.acceleration_ratio for r in rs),
            "worst_jerk_ratio": max(r.jerk_ratio for r in rs),
            "beyond_limits": sum(not r.within_limits for r in rs),
            "non_braking_stops": sum(r.non_braking_stop for r in rs),
            "tracebacks": sum(r.traceback is not None for r in rs),
            "unreadable_logs": sum(not r.log_readable for r in rs),
            "unexpected_ends": sum(not r.expected for r in rs),
            "clamped_cycles": sum(r.clamped_cycles for r in rs),
            "largest_effort_step": max(r.effort_step for r in rs),
        }
    return out
