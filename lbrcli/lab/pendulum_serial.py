"""The thesis's pendulum module (ch. 6) over USB serial: an AS5600 encoder read through an nRF24 radio link.

The receiving Arduino writes one reading per line: the raw 12-bit encoder count x (θ = 2π·x/4096, eq. 6.1)
and the angular velocity [rad/s], separated by a comma, semicolon, tab or space. A background thread reads
the port (pyserial) and publishes the latest reading by swapping one tuple, so the FRI loop only ever reads an
attribute and is never blocked by the serial port. Malformed lines are counted, never fatal.
"""

from __future__ import annotations

import math
import re
import threading
import time
from dataclasses import dataclass

COUNTS_PER_TURN = 4096  # AS5600, 12 bit
_SPLIT = re.compile(r"[,;\t ]+")


@dataclass(frozen=True)
class PendulumReading:
    """One encoder reading: host time [s] (time.monotonic), angle [rad] wrapped to (−π, π], velocity [rad/s]."""

    host_time: float
    theta: float
    omega: float


def parse_line(line: bytes | str, zero_count: int = 0) -> tuple[float, float]:
    """Parse 'x,omega' → (θ [rad] relative to ``zero_count`` wrapped to (−π, π], ω [rad/s]); ValueError if malformed."""
    text = line.decode("ascii", errors="strict") if isinstance(line, bytes) else line
    parts = [p for p in _SPLIT.split(text.strip()) if p]
    if len(parts) != 2:
        raise ValueError(f"expected 2 values, got {len(parts)}")
    count = int(parts[0])
    if not 0 <= count < COUNTS_PER_TURN:
        raise ValueError(f"encoder count {count} outside 0..{COUNTS_PER_TURN - 1}")
    omega = float(parts[1])
    if not math.isfinite(omega):
        raise ValueError("velocity not finite")
    theta = 2.0 * math.pi * ((count - zero_count) % COUNTS_PER_TURN) / COUNTS_PER_TURN
    if theta > math.pi:
        theta -= 2.0 * math.pi
    return theta, omega


def format_line(theta: float, omega: float, zero_count: int = 0) -> bytes:
    """The line the module's Arduino sends for angle θ [rad] and velocity ω [rad/s] (inverse of parse_line)."""
    count = (int(round(theta / (2.0 * math.pi) * COUNTS_PER_TURN)) + zero_count) % COUNTS_PER_TURN
    return f"{count},{omega:.4f}\n".encode("ascii")


class PendulumReader:
    """Reads the pendulum module's serial port; ``latest`` is the newest reading (or None).

    ``threaded`` (default): a daemon thread reads the port as lines arrive. Otherwise every access to ``latest``
    first takes what the port holds (one non-blocking read) — for the lock-step simulator, whose lines are on the port
    before the message that follows them, so the session sees them in the same cycle however busy the machine is.
    """

    def __init__(self, port: str, baud: int = 115200, zero_count: int = 0, threaded: bool = True) -> None:
        self.port = port
        self.baud = baud
        self.zero_count = zero_count
        self.threaded = threaded
        self._latest: PendulumReading | None = None
        self.lines = 0
        self.malformed = 0
        self.error: str | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._serial = None
        self._pending = b""

    @property
    def latest(self) -> PendulumReading | None:
        if not self.threaded:
            self.poll()
        return self._latest

    @latest.setter
    def latest(self, reading: PendulumReading | None) -> None:
        self._latest = reading

    @property
    def seen(self) -> PendulumReading | None:
        """The newest reading taken so far, without reading the port (for the log, written after the reply: the
        unthreaded reader must not take the next cycle's line while the lock-step simulator waits to see it on the
        reader's side)."""
        return self._latest

    def start(self) -> "PendulumReader":
        """Open the port (raises OptionError if it cannot be opened) and start reading."""
        import serial

        from trajectories.errors import SettingError

        try:
            self._serial = serial.serial_for_url(self.port, baudrate=self.baud, timeout=0.05)
        except (serial.SerialException, OSError, ValueError) as exc:
            raise SettingError(PendulumReader, "port", f"cannot open serial port {self.port}: {exc}") from None
        if self.threaded:
            self._thread = threading.Thread(target=self._run, name="pendulum-serial", daemon=True)
            self._thread.start()
        return self

    def poll(self) -> None:
        """Take what the port holds now, without waiting (the unthreaded reader)."""
        ser = self._serial
        if ser is None or self.error is not None or self._stop.is_set():
            return
        try:
            n = ser.in_waiting
            if n:
                self._feed(ser.read(n))
        except Exception as exc:  # the device went away: keep the session running, report it at the end
            self.error = str(exc)

    def _run(self) -> None:
        # Read whatever has arrived in one call and split lines here: pyserial's readline() reads byte by byte,
        # which would take the GIL from the FRI loop a dozen times per reading.
        ser = self._serial
        while not self._stop.is_set():
            try:
                chunk = ser.read(max(1, ser.in_waiting))
            except Exception as exc:  # the device went away: keep the session running, report it at the end
                self.error = str(exc)
                return
            if chunk:
                self._feed(chunk)

    def _feed(self, chunk: bytes) -> None:
        """Split what arrived into lines; the newest good one becomes ``latest``."""
        pending = self._pending + chunk
        if b"\n" not in chunk:
            if len(pending) > 256:  # no line end in sight: garbage
                self.malformed += 1
                pending = b""
            self._pending = pending
            return
        *lines, self._pending = pending.split(b"\n")
        latest = None
        for line in lines:
            self.lines += 1
            try:
                latest = parse_line(line, self.zero_count)
            except (ValueError, UnicodeDecodeError):
                self.malformed += 1
        if latest is not None:
            self._latest = PendulumReading(time.monotonic(), latest[0], latest[1])

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=1.0)
        if self._serial is not None:
            self._serial.close()

    def __enter__(self) -> "PendulumReader":
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()


LOCKSTEP_SETTLE_S = 0.05  # [s] the longest a line written in a lock-step cycle is waited for on the reader's side


def _readable(fd: int) -> int:
    """Bytes the terminal ``fd`` holds for its readers (FIONREAD)."""
    import array
    import fcntl
    import termios

    buf = array.array("i", [0])
    fcntl.ioctl(fd, termios.FIONREAD, buf, True)
    return buf[0]


class PendulumEmulator:
    """The module's radio receiver emulated on a pseudo-terminal: ``path`` is the device a reader opens.

    ``feed(t, θ, ω)`` writes a line at most every 1/rate_hz seconds, non-blocking (a full buffer drops lines,
    as a radio link would). With ``settle_s`` > 0 (a simulator in lock-step) ``send`` returns once the line can be
    read on the reader's side (at most that long): the kernel hands a pty's bytes over asynchronously, so a line
    written in a cycle could otherwise reach the reader a cycle or more later on a busy machine.
    """

    def __init__(self, rate_hz: float = 200.0, zero_count: int = 0, delay_s: float = 0.0, jitter_s: float = 0.0,
                 seed: int = 0) -> None:  # fmt: skip
        import os
        import random
        import tty
        from collections import deque

        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        os.set_blocking(self.master, False)
        self.path = os.ttyname(self.slave)
        self.period = 1.0 / rate_hz
        self.zero_count = zero_count
        self._next = -math.inf
        self.sent = 0
        self.dropped = 0
        self.delay_s, self.jitter_s = delay_s, jitter_s  # [s] sample → line on the port, + uniform [0, jitter]
        self._rng = random.Random(seed)
        self._queue: deque[tuple[float, bytes]] = deque()
        self._last_due = -math.inf
        self.settle_s = 0.0  # [s] see the class docstring

    def feed(self, t: float, theta: float, omega: float) -> None:
        """The angle θ [rad] and rate ω [rad/s] at time t [s]: a line every 1/rate_hz, on the port after the delay
        (call every cycle: it also delivers the lines that are due)."""
        if t >= self._next:
            self._next = t + self.period
            self.queue(t, format_line(theta, omega, self.zero_count))
        self.deliver(t)

    def queue(self, t: float, line: bytes) -> None:
        """A line sampled at t [s], written once ``deliver`` reaches t + delay (+ jitter); the order is kept."""
        if self.delay_s <= 0.0 and self.jitter_s <= 0.0:
            self.send(line)
            return
        due = max(t + self.delay_s + self._rng.uniform(0.0, self.jitter_s), self._last_due)
        self._last_due = due
        self._queue.append((due, line))

    def deliver(self, t: float) -> None:
        """Write the queued lines due by t [s]."""
        q = self._queue
        while q and q[0][0] <= t + 1e-9:
            self.send(q.popleft()[1])

    def send(self, line: bytes) -> bool:
        """Write one line now, non-blocking; False (counted in ``dropped``) if the buffer is full."""
        import os

        try:
            before = _readable(self.slave) if self.settle_s > 0.0 else 0
            os.write(self.master, line)
            self.sent += 1
        except (BlockingIOError, OSError):
            self.dropped += 1
            return False
        if self.settle_s > 0.0:  # the reader does not read meanwhile: in lock-step it waits for this cycle's message
            import time

            deadline = time.perf_counter() + self.settle_s
            while _readable(self.slave) < before + len(line) and time.perf_counter() < deadline:
                time.sleep(0)
        return True

    def write_raw(self, data: bytes) -> None:
        import os

        os.write(self.master, data)

    def close(self) -> None:
        import os

        for fd in (self.master, self.slave):
            try:
                os.close(fd)
            except OSError:
                pass
