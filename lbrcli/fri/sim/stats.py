"""What happened in a simulated session: counts of cycles and datagrams, timing [ms], [µs], the robot's end state."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from ..constants import SessionState


@dataclass(frozen=True)
class SimStats:
    """Statistics of one simulated FRI session (picklable; ``to_dict`` for JSON)."""

    cycles: int  # monitoring cycles run
    replies: int  # valid command messages received
    late_replies: int  # replies to an earlier message than the last one sent
    missed_replies: int  # reply slots (k cycles) without a timely reply, counted from the first reply on
    malformed_received: int  # undecodable datagrams (ignored)
    foreign_received: int  # datagrams from another host or with a foreign message identifier (ignored)
    states_seen: tuple[int, ...]  # sequence of distinct session states in order
    safety_stop: bool
    min_tracking_performance: float  # over COMMANDING_ACTIVE cycles (1.0 if never active)
    commanded_rows: int  # commands executed in COMMANDING_ACTIVE
    max_ball_theta: float | None  # [rad] (from a ball plant, None without one)
    end_reason: str = ""  # duration, quality, safety_stop, stopped, max_runtime, parent_exited or ""
    lost_sent: int = 0  # monitoring messages dropped by the loss injection
    malformed_sent: int = 0  # corrupted datagrams sent by the malformed injection
    client_sequence_gaps: int = 0  # client sequenceCounter not incremented by one
    overruns: int = 0  # cycles that started more than one period late (schedule re-synchronised)
    active_cycles: int = 0  # cycles in COMMANDING_ACTIVE
    period_ms_p50: float | None = None  # actual send period statistics [ms]
    period_ms_p99: float | None = None
    period_ms_max: float | None = None
    reply_latency_ms_p50: float | None = None  # send of a message → arrival of the reply reflecting it [ms]
    reply_latency_ms_p99: float | None = None
    reply_latency_ms_p999: float | None = None
    reply_latency_ms_max: float | None = None
    final_q: tuple[float, ...] = ()  # [rad] measured robot position at the end
    work_us_p50: float | None = None  # per-cycle computation (state, control, dynamics, plants, encode) [µs]
    work_us_p99: float | None = None
    cpu_fraction: float = 0.0  # CPU time of the loop / wall time (1.0 = a whole core)
    realtime: bool = False  # the loop ran with real-time scheduling
    command_mode: str = "position"  # the overlay's client command mode
    io_writes: int = 0  # accepted writeIORequest values
    io_refused: int = 0  # writes to an input, an unknown channel, or with the wrong type (ignored)
    untimely_active_cycles: int = 0  # COMMANDING_ACTIVE cycles without a timely reply (late or missing)
    commands_without_position: int = 0  # replies to COMMANDING_ACTIVE messages without joint positions (an error)
    incomplete_commands: int = 0  # commands without the torque (TORQUE) or wrench (WRENCH) the mode needs
    plants: dict = field(default_factory=dict)  # figures of the plants, by plant name
    cartesian_poses: int = 0  # CARTESIAN_POSE commands turned into joints (FRI 2.7)
    command_problem: str = ""  # why a Cartesian pose could not be executed (end reason cartesian_refused)
    transformations: dict = field(default_factory=dict)  # FRI 2.7 requested frames: name -> received, last, stamp
    transformations_refused: int = 0  # values for frames not requested, or malformed (ignored)

    def to_dict(self) -> dict:
        d = asdict(self)
        d["states_seen"] = [SessionState(s).name for s in self.states_seen]
        return d


def percentiles(values: np.ndarray) -> tuple[float | None, float | None, float | None]:
    """(p50, p99, max) of a sample, Nones when empty."""
    if len(values) == 0:
        return None, None, None
    p50, p99 = np.percentile(values, [50, 99])
    return float(p50), float(p99), float(values.max())
