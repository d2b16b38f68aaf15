"""The execution log written by a child process, so that formatting its rows costs the FRI loop nothing.

:class:`LogProcess` is an application observer like :class:`~lbrcli.fri.log.LogObserver` and writes the same file
(``LogLayout.format``, complete rows per write, valid after any ending), but the FRI loop only hands each accepted
monitoring datagram and the cycle's own figures (time, command, counters, phase, row, the client's extra columns) to
a pipe — a few µs — and a child process (``python -m lbrcli.fri.logwriter``, :class:`RowWriter`) parses and formats
them under SCHED_IDLE (nice 19 where it is missing), waking every ``BATCH_S`` and formatting ``SLICE_ROWS`` rows between yields of the CPU. A row costs
≈ 20–35 µs of CPU to decode and format in Python; see docs/explanations/fri-timing.md and benchmarks/bench_fri_log.py.

The reply path never waits for the log: rows go to the pipe ``FLUSH_ROWS`` at a time (a kill -9 of the loop loses
at most that many; any other ending writes them all), the pipe is non-blocking (1 MiB where the system allows); records it cannot
take at once wait in memory and go with the next cycle's. A writer that fails (a full disk) exits with its reason;
the loop learns it from the broken pipe at its next hand-over and stops as for a failing in-process log (braking when
commanding). Rows handed over when the session ends are written before :meth:`LogProcess.close` returns.
"""

from __future__ import annotations

import fcntl
import os
import select
import struct
import subprocess
import sys
import time
from pathlib import Path
from typing import Any, Sequence

from trajectories.errors import InputError

from .codec import FriCodec
from .constants import Phase
from .log import ExecutionLog, LogLayout
from .messages import FriVersion

# a row's frame: this head, the command [rad] and the client's extra values (7 + n_extra doubles), the datagram
_HEAD = struct.Struct("<IBHdqBBbq")  # frame length, kind, n_extra, t, client_seq, answered, sent, phase, row
_LEN = struct.Struct("<I")
_START, _ROW = 0, 1
_BRAKE = int(Phase.BRAKE)
PIPE_SIZE = 1 << 20  # [bytes] asked for the pipe (Linux F_SETPIPE_SZ; the default is 64 KiB)
MAX_PENDING = 64 << 20  # [bytes] held in memory while the writer is behind, then the log fails
_F_SETPIPE_SZ = 1031
READY_TIMEOUT_S = 60.0  # [s] for the writer process to start
FLUSH_ROWS = 16  # rows handed to the pipe in one write (one system call per 16 ms at 1 kHz; all at the end)
BATCH_S = 0.048  # [s] the writer sleeps this long between reads: three hand-overs' rows per wake-up (its code and
# data stay in the CPU's caches over the batch: ≈ 25 against ≈ 35 µs per row when it woke for every hand-over)
SLICE_ROWS = 16  # rows formatted between two yields of the CPU: ≈ 0.3 ms of work, so that a slice that runs on the
# loop's CPU cannot make a reply late (20 ms batches of ≈ 1 ms each in one piece did: a late reply every 20 ms)


class LogProcess:
    """Execution log at ``path`` written by a child process (an application observer, as ``LogObserver``).

    ``extra_names``/``extra``: the client's extra columns and the callable giving their values from the state (run in
    the loop). ``InputError`` at once when the file cannot be created; ``close()`` waits for the writer."""

    name = "the execution log"

    def __init__(self, path: str | Path, extra_names: Sequence[str] = (), extra: Any = None) -> None:
        self.path = Path(path)
        self.extra_names = tuple(extra_names)
        self.extra = extra  # callable(LBRState) -> extra values, or None
        try:
            fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        except OSError as exc:
            raise InputError(f"cannot write the log: {exc.strerror}", file=self.path) from None
        try:
            self._proc = subprocess.Popen(
                [sys.executable, "-m", "lbrcli.fri.logwriter", str(fd), str(self.path)], stdin=subprocess.PIPE,
                stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, pass_fds=(fd,), close_fds=True,
            )  # fmt: skip
        finally:
            os.close(fd)
        # the writer's start (imports: ≈ 0.5 s of CPU) is over before the session begins
        out = self._proc.stdout  # type: ignore[union-attr]
        if not select.select([out], [], [], READY_TIMEOUT_S)[0] or out.readline().strip() != b"ready":
            self._proc.kill()
            self._proc.wait()
            raise InputError("cannot write the log: its writer process did not start", file=self.path)
        self._pipe = self._proc.stdin.fileno()  # type: ignore[union-attr]
        try:
            fcntl.fcntl(self._pipe, _F_SETPIPE_SZ, PIPE_SIZE)
        except OSError:
            pass  # the default size: the pending buffer takes what does not fit
        os.set_blocking(self._pipe, False)
        self._pending = bytearray()
        self._batch = bytearray()  # rows not yet handed to the pipe
        self._in_batch = 0
        self._packs: dict[int, Any] = {}  # a row's head, command and extra values, by extra count
        self._started = False
        self._closed = False
        self.rows = 0  # rows handed to the writer
        self.written: int | None = None  # rows the writer wrote (known after close)
        self.error: str | None = None  # why the writer failed, if it did

    # -- the observer --------------------------------------------------------------------------------------------
    def on_cycle(self, app: Any) -> None:
        if not self._started:
            names = "\x1f".join(self.extra_names).encode()
            version = app.version.value.encode()
            body = bytes([len(version)]) + version + names
            self._send(_LEN.pack(len(body) + 5) + bytes([_START]) + body)
            self._started = True
        cyc = app.cycle
        braking = cyc.braking
        answered = cyc.answered
        extra = self.extra(app.state) if self.extra is not None else ()
        data = app._last_data
        n = len(extra)
        pack = self._packs.get(n) or self._packs.setdefault(n, struct.Struct(_HEAD.format + f"{7 + n}d").pack)
        self._batch += pack(
            _HEAD.size + 8 * (7 + n) + len(data), _ROW, n, cyc.t, app.client_sequence if answered else -1, answered,
            cyc.sent_position, _BRAKE if braking else (cyc.phase if answered or cyc.state >= 3 else 0),
            -1 if braking else cyc.row, *cyc.command, *extra,
        )  # fmt: skip
        self._batch += data
        self.rows += 1
        self._in_batch += 1
        if self._in_batch >= FLUSH_ROWS:
            self._hand_over()

    def _hand_over(self) -> None:
        """The batched rows to the pipe."""
        if self._batch:
            frames = bytes(self._batch)
            self._batch.clear()
            self._in_batch = 0
            self._send(frames)

    def on_end(self, app: Any, result: Any) -> None:
        self.close()

    def figures(self) -> dict[str, Any]:
        return {"log_rows": self.rows}

    # -- the pipe ------------------------------------------------------------------------------------------------
    def _send(self, frame: bytes) -> None:
        if self._pending:
            self._pending += frame
            self._flush()
            return
        try:
            n = os.write(self._pipe, frame)
        except BlockingIOError:
            n = 0
        except BrokenPipeError:
            self._failed()
        if n < len(frame):
            self._pending += frame[n:]
            if len(self._pending) > MAX_PENDING:
                raise InputError("cannot write the log: its writer process fell behind by 64 MiB", file=self.path)

    def _flush(self) -> None:
        try:
            n = os.write(self._pipe, self._pending)
        except BlockingIOError:
            return
        except BrokenPipeError:
            self._failed()
        del self._pending[:n]

    def _failed(self) -> None:
        """The writer ended early: raise its reason."""
        self._closed = True
        out = self._finish_child()
        raise InputError(self.error or f"cannot write the log: the writer process ended ({out})", file=self.path)

    def _finish_child(self, timeout_s: float = 60.0) -> str:
        """Close the pipe, wait for the writer, read its last word (``rows N`` or ``error TEXT``)."""
        proc = self._proc
        try:
            proc.stdin.close()  # type: ignore[union-attr]
        except OSError:
            pass
        try:
            out = proc.stdout.read().decode(errors="replace").strip()  # type: ignore[union-attr]
            proc.wait(timeout_s)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
            out = "error cannot write the log: its writer process did not finish"
        if out.startswith("rows "):
            self.written = int(out.split()[1])
        elif out.startswith("error "):
            self.error = out[6:]
        else:
            self.error = f"cannot write the log: the writer process ended with code {proc.returncode}"
        return out

    def close(self) -> None:
        """Hand over what is pending, wait until the writer wrote every row; a writer failure sets ``error``."""
        if self._closed:
            return
        try:
            self._hand_over()
        except InputError:
            return  # the writer had failed: ``error`` says why
        self._closed = True
        if self._pending:
            os.set_blocking(self._pipe, True)
            try:
                os.write(self._pipe, bytes(self._pending))
            except OSError:
                pass
            self._pending.clear()
        self._finish_child()
        if self.error is None and self.written is not None and self.written < self.rows:
            self.error = f"cannot write the log: {self.rows - self.written} rows were not written"

    def __enter__(self) -> "LogProcess":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class RowWriter:
    """The writer's side: frames to rows, formatted by the in-process log's ``LogLayout`` (the same bytes).

    The loop checked every datagram before it handed it over (framing, CRC-32, required fields, identifier), so the
    writer parses the protobuf payload directly; :meth:`take` converts the complete frames of what the pipe held and
    writes their rows in one write."""

    def __init__(self, log: ExecutionLog) -> None:
        self.log = log
        self.layout: LogLayout | None = None
        self.mon: Any = None
        self.version = FriVersion.V1_15
        self.extra_names: tuple[str, ...] = ()
        self._pre = self._post = 0  # [bytes] framing around the protobuf payload (FRI 2.7: length, CRC-32)
        self._floats: dict[int, struct.Struct] = {}  # the command and extra values of a row, by extra count

    def _start(self, body: bytes) -> None:
        k = body[0]
        version = FriVersion(body[1 : 1 + k].decode())
        names = body[1 + k :].decode()
        self.extra_names = tuple(names.split("\x1f")) if names else ()
        codec = FriCodec(version)
        self.mon, self.version = codec.new_monitoring(), version
        self._pre, self._post = (4, 4) if codec.framed else (0, 0)

    def take(self, data: bytes, max_rows: int = 1 << 30) -> int:
        """Write the rows of the complete frames at the start of ``data``, at most ``max_rows`` (one write); the
        bytes they took."""
        i, end = 0, len(data)
        lines: list[str] = []
        head, hs, size_of = _HEAD.unpack_from, _HEAD.size, _LEN.unpack_from
        while end - i >= 4 and len(lines) < max_rows:
            size = size_of(data, i)[0]
            if end - i < size:
                break
            if data[i + 4] == _START:
                self._start(data[i + 5 : i + size])
            else:
                _, _, n, t, cseq, answered, sent, phase, row = head(data, i)
                floats = self._floats.get(n) or self._floats.setdefault(n, struct.Struct(f"<{7 + n}d"))
                values = floats.unpack_from(data, i + hs)
                at = i + hs + floats.size + self._pre
                mon = self.mon
                mon.ParseFromString(data[at : i + size - self._post])
                layout = self.layout
                if layout is None:
                    layout = self.layout = LogLayout(mon, self.version, self.extra_names)
                    self.log.start(layout)
                lines.append(layout.format(t, mon, values[:7], cseq, answered, sent, phase, row, values[7:]))
            i += size
        if lines:
            self.log.write_rows("".join(lines), len(lines))  # complete rows in one write
        return i


def _idle_policy() -> None:
    """The writer under SCHED_IDLE where the system has it.

    At nice 19 alone a woken FRI loop still waited for the writer's running slice (the scheduler protects a running
    task's slice): a late reply at every wake-up, every ≈ 50 ms, which ended 1 ms sessions under KUKA's quality rule.
    A SCHED_IDLE task is preempted at once by any normal task that wakes."""
    policy = getattr(os, "SCHED_IDLE", None)
    if policy is not None:
        with __import__("contextlib").suppress(OSError):
            os.sched_setscheduler(0, policy, os.sched_param(0))


def _serve(fd_out: int, path: str) -> int:
    """The writer: frames from stdin to rows in the file (fd ``fd_out``); prints ``rows N`` or ``error TEXT``."""
    log = ExecutionLog.from_fd(fd_out, path)
    print("ready", flush=True)
    writer = RowWriter(log)
    fd_in = sys.stdin.fileno()
    rest = b""
    try:
        while True:
            chunk = os.read(fd_in, PIPE_SIZE)  # blocks until the loop hands rows over (or closes the pipe)
            if not chunk:
                break
            rest = rest + chunk if rest else chunk
            while True:  # rows in slices: the CPU goes back to the scheduler between them
                used = writer.take(rest, SLICE_ROWS)
                rest = rest[used:]
                if not used or len(rest) < 4 or len(rest) < _LEN.unpack_from(rest, 0)[0]:
                    break
                os.sched_yield()
            time.sleep(BATCH_S)
    except InputError as exc:
        print(f"error {exc.message}", flush=True)
        return 1
    except Exception as exc:  # noqa: BLE001 - reported to the loop, which stops the session
        print(f"error cannot write the log: {type(exc).__name__}: {exc}", flush=True)
        return 1
    rows = log.rows
    log.close()  # removes a file that never got its header
    print(f"rows {rows}", flush=True)
    return 0


if __name__ == "__main__":  # the child side of LogProcess
    import signal

    # Ctrl-C and a SIGTERM to the process group reach the writer too: it writes on until the loop, which brakes and
    # logs the braking stop, closes the pipe (end of input)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    with __import__("contextlib").suppress(OSError):
        os.nice(19)  # far below the FRI loop (same user, nothing asked of the system): rows wait in the pipe (1 MiB)
        # and the loop's memory (MAX_PENDING, minutes at 1 kHz) while other work takes the CPU
    _idle_policy()
    sys.exit(_serve(int(sys.argv[1]), sys.argv[2]))
