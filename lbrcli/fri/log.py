"""Execution log: one CSV row per monitoring message, written row by row with one ``os.write`` each.

Columns (DESIGN.md): ``t,state,quality,cmd_q1..7,msr_q1..7,ipo_q1..7,msr_tau1..7,ext_tau1..7,tracking``, then
everything else FRI monitors: controller timestamp (``stamp_sec,stamp_nsec``), header counters
(``seq,reflected_seq``), the client's answer (``client_seq`` (−1: not answered), ``answered``, ``sent`` (1: a joint
position was sent), ``phase``, ``row``), robot info (``safety,operation_mode,control_mode,drive_state`` (the lowest
of the 7 drives), ``client_command_mode,overlay_type,send_period_ms,receive_multiplier``), monitored commanded torque
``cmd_tau1..7``; FRI 1.15: the controller's commanded position ``ctl_q1..7``; FRI 2.7 when monitored: external force
``ext_fx..ext_tz`` [N, Nm], measured Cartesian pose ``pose_x..pose_qz`` [mm, quaternion], redundancy value; extra
columns of the command (e.g. ``flange_x,flange_y,flange_z`` [m]); and one column per IO value of the first message,
named as the IO (analog: analogValue, boolean/digital: digitalValue), e.g. ``ball_theta`` [rad] from the simulator.

Units: t [s] controller time since the first message (sequence counter × send period), positions [rad],
torques [Nm]. A value the controller did not send is written as 0; an IO value missing from a message keeps its
last value; no cell is ever empty or nan (the clients' extra columns say with a flag when they hold nothing yet, e.g.
``pend_age`` −1 before the pendulum module's first reading), and the first row writes every float with a decimal
point, so pandas, polars and PlotJuggler read the file with their defaults. Each row reaches the file in one ``write`` call, so any ending (SIGINT, exception, kill) leaves complete
rows that ``trajectories.csvio.read_table(path, LOG_COLUMNS, time="increasing")`` reads.
"""

from __future__ import annotations

import contextlib
import os
import re
from pathlib import Path
from typing import Any, Sequence

from trajectories.csvio import float_first_row
from trajectories.errors import InputError

from .constants import Phase
from .messages import FriVersion

J = range(1, 8)
LOG_COLUMNS: tuple[str, ...] = (
    ("t", "state", "quality")
    + tuple(f"cmd_q{i}" for i in J)
    + tuple(f"msr_q{i}" for i in J)
    + tuple(f"ipo_q{i}" for i in J)
    + tuple(f"msr_tau{i}" for i in J)
    + tuple(f"ext_tau{i}" for i in J)
    + ("tracking",)
)
CONTROL_COLUMNS: tuple[str, ...] = (
    "stamp_sec", "stamp_nsec", "seq", "reflected_seq", "client_seq", "answered", "sent", "phase", "row",
    "safety", "operation_mode", "control_mode", "drive_state", "client_command_mode", "overlay_type",
    "send_period_ms", "receive_multiplier",
) + tuple(f"cmd_tau{i}" for i in J)  # fmt: skip
CTL_Q_COLUMNS = tuple(f"ctl_q{i}" for i in J)
EXT_FORCE_COLUMNS = ("ext_fx", "ext_fy", "ext_fz", "ext_tx", "ext_ty", "ext_tz")
POSE_COLUMNS = ("pose_x", "pose_y", "pose_z", "pose_qw", "pose_qx", "pose_qy", "pose_qz")

# extra columns that may hold nan (the pendulum module before its first reading): readers pass them as nan_columns
NAN_COLUMNS = ("pend_theta", "pend_omega", "pend_age")
# phase column values (constants.Phase)
PHASE_NONE = int(Phase.NONE)
PHASE_MOVE = int(Phase.MOVE)
PHASE_TRAJECTORY = int(Phase.TRAJECTORY)
PHASE_SETTLE = int(Phase.SETTLE)
PHASE_BRAKE = PHASE_HOLD = int(Phase.BRAKE)
PHASE_WAIT = int(Phase.WAIT)

_ZERO7 = (0.0,) * 7
_ZERO6 = (0.0,) * 6
_CMD = "%s"  # the commanded position exactly as sent: the shortest text that round-trips the double, also for a
# numpy scalar (whose %r is "np.float64(…)" under numpy 2: a client's numpy commands made the log unreadable)
_Q = "%.12g"
_F = "%.9g"
_I = "%d"
_NAME_OK = re.compile(r"[^A-Za-z0-9_.\-]")


def _io_column(name: str, taken: set[str]) -> str:
    col = _NAME_OK.sub("_", name.strip()) or "io"
    if col in taken:
        col = "io_" + col
    while col in taken:
        col += "_"
    return col


class LogLayout:
    """Columns of one session, fixed by the first monitoring message, and the row formatter."""

    def __init__(self, first: Any, version: FriVersion | str, extra: Sequence[str] = ()) -> None:
        self.version = FriVersion(version)
        md = first.monitorData
        names = list(LOG_COLUMNS + CONTROL_COLUMNS)
        fmts = ["%.6f", _I, _I] + [_CMD] * 7 + [_Q] * 14 + [_F] * 14 + [_F] + [_I] * 9 + [_I] * 8 + [_F] * 7
        self.ctl_q = self.version is FriVersion.V1_15
        if self.ctl_q:
            names += CTL_Q_COLUMNS
            fmts += [_Q] * 7
        self.ext_force = self.version is FriVersion.V2_7 and md.HasField("externalForce")
        if self.ext_force:
            names += EXT_FORCE_COLUMNS
            fmts += [_F] * 6
        self.pose = self.version is FriVersion.V2_7 and md.HasField("measuredCartesianPose")
        if self.pose:
            names += POSE_COLUMNS
            fmts += [_F] * 7
        self.redundancy = self.version is FriVersion.V2_7 and md.HasField("measuredRedundancyInformation")
        if self.redundancy:
            names.append("redundancy")
            fmts.append(_F)
        self.n_extra = len(extra)
        names += list(extra)
        fmts += [_F] * len(extra)
        taken = set(names)
        self.io_names: list[str] = []  # FRI names, in column order
        self.io_index: dict[str, int] = {}
        io_cols: list[str] = []
        for io in md.readIORequest:
            if io.name in self.io_index:
                continue
            col = _io_column(io.name, taken)
            taken.add(col)
            self.io_index[io.name] = len(self.io_names)
            self.io_names.append(io.name)
            io_cols.append(col)
        names += io_cols
        fmts += [_F] * len(io_cols)
        self.io_values = [0.0] * len(io_cols)
        self.update_io(first)
        self.names: tuple[str, ...] = tuple(names)
        self.template = ",".join(fmts) + "\n"
        # the first row in the alternate form (always a decimal point): readers that type columns from their first
        # rows (polars, DuckDB) take every float column as float although later rows may write 0 as "0"
        self._next = float_first_row(self.template)

    def io_column(self, fri_name: str) -> int | None:
        """Index into ``io_values`` of an IO value by its FRI name (None if not logged)."""
        return self.io_index.get(fri_name)

    def update_io(self, mon: Any) -> None:
        """Take the IO values of a message (values missing from it keep their last value)."""
        if not self.io_names:
            return
        vals = self.io_values
        index = self.io_index
        for io in mon.monitorData.readIORequest:
            k = index.get(io.name)
            if k is not None:
                vals[k] = io.analogValue if io.type == 2 else float(io.digitalValue)

    def format(
        self,
        t: float,
        mon: Any,
        cmd: Sequence[float],
        client_seq: int,
        answered: int,
        sent: int,
        phase: int,
        row: int,
        extra: Sequence[float] = (),
    ) -> str:
        """One CSV line (with newline) for a monitoring message ``mon`` and the command ``cmd`` [rad] in force."""
        # (repeated fields copied out with [:], a third of what iterating them costs; the values are the same)
        md = mon.monitorData
        ipo = mon.ipoData
        ci = mon.connectionInfo
        ri = mon.robotInfo
        msr = md.measuredJointPosition.value[:]
        if len(msr) != 7:
            msr = _ZERO7
        ipq = ipo.jointPosition.value[:]
        if len(ipq) != 7:
            ipq = _ZERO7
        tau = md.measuredTorque.value[:]
        if len(tau) != 7:
            tau = _ZERO7
        ext = md.externalTorque.value[:]
        if len(ext) != 7:
            ext = _ZERO7
        ctau = md.commandedTorque.value[:]
        if len(ctau) != 7:
            ctau = _ZERO7
        drives = ri.driveState[:]
        ts = md.timestamp
        vals = (
            t, ci.sessionState, ci.quality, *cmd, *msr, *ipq, *tau, *ext, ipo.trackingPerformance,
            ts.sec, ts.nanosec, mon.header.sequenceCounter, mon.header.reflectedSequenceCounter,
            client_seq, answered, sent, phase, row,
            ri.safetyState, ri.operationMode, ri.controlMode, min(drives) if drives else 0,
            ipo.clientCommandMode, ipo.overlayType, ci.sendPeriod, ci.receiveMultiplier, *ctau,
        )  # fmt: skip
        if self.ctl_q:
            cq = md.commandedJointPosition.value[:]
            vals += tuple(cq) if len(cq) == 7 else _ZERO7
        if self.ext_force:
            ef = md.externalForce.element[:]
            vals += tuple(ef) if len(ef) == 6 else _ZERO6
        if self.pose:
            pe = md.measuredCartesianPose.element[:]
            vals += tuple(pe) if len(pe) == 7 else _ZERO7
        if self.redundancy:
            vals += (md.measuredRedundancyInformation.value,)
        if self.n_extra:
            vals += tuple(extra)
        if self.io_names:
            self.update_io(mon)
            vals += tuple(self.io_values)
        line = self._next % vals
        self._next = self.template
        return line


class ExecutionLog:
    """A log file written one complete row per ``os.write`` (no buffered partial rows)."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        try:
            self._fd: int | None = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        except OSError as exc:
            raise InputError(f"cannot write the log: {exc.strerror}", file=self.path) from None
        self.layout: LogLayout | None = None
        self.rows = 0
        self._size = 0  # [bytes] written in complete rows

    @classmethod
    def from_fd(cls, fd: int, path: str | Path) -> "ExecutionLog":
        """A log on a file already open for writing as ``fd`` (e.g. handed to a writer process)."""
        log = cls.__new__(cls)
        log.path, log._fd, log.layout, log.rows, log._size = Path(path), fd, None, 0, 0
        return log

    def start(self, layout: LogLayout) -> None:
        """Fix the columns and write the header."""
        self.layout = layout
        self._write(",".join(layout.names) + "\n")

    def write(self, line: str) -> None:
        self._write(line)
        self.rows += 1

    def write_rows(self, text: str, n: int) -> None:
        """``n`` complete rows in one write."""
        self._write(text)
        self.rows += n

    def _write(self, text: str) -> None:
        if self._fd is None:
            return
        data = encoded = text.encode()
        try:
            n = os.write(self._fd, data)
            while n < len(data):  # a regular file takes it all at once; be correct anyway
                data = data[n:]
                n = os.write(self._fd, data)
        except OSError as exc:
            # never leave a cut row: back to the last complete one, then report (the session brakes and ends)
            with contextlib.suppress(OSError):
                os.ftruncate(self._fd, self._size)
                os.lseek(self._fd, self._size, os.SEEK_SET)
            raise InputError(f"cannot write the log: {exc.strerror}", file=self.path) from None
        self._size += len(encoded)

    def close(self) -> None:
        """Close the file; a log that never got its header (no FRI message arrived) is removed."""
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None
            if self.layout is None:
                with contextlib.suppress(OSError):
                    self.path.unlink()

    def __enter__(self) -> "ExecutionLog":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class LogObserver:
    """Writes one log row per accepted monitoring message, after the reply went out (an application observer)."""

    name = "the execution log"

    def __init__(self, log: ExecutionLog, extra_names: Sequence[str] = (), extra: Any = None) -> None:
        self.log = log
        self.extra_names = tuple(extra_names)
        self.extra = extra  # callable(LBRState) -> extra values, or None

    def on_cycle(self, app: Any) -> None:
        log = self.log
        layout = log.layout
        state = app.state
        if layout is None:
            layout = LogLayout(state.message, app.version, self.extra_names)
            log.start(layout)
        cyc = app.cycle
        phase = int(Phase.BRAKE) if cyc.braking else (cyc.phase if cyc.answered or cyc.state >= 3 else 0)
        log.write(
            layout.format(
                cyc.t, state.message, cyc.command, app.client_sequence if cyc.answered else -1,
                1 if cyc.answered else 0, 1 if cyc.sent_position else 0, phase, cyc.row if not cyc.braking else -1,
                self.extra(state) if self.extra is not None else (),
            )
        )  # fmt: skip

    def figures(self) -> dict[str, Any]:
        return {"log_rows": self.log.rows}
