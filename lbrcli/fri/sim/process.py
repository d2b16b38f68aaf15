"""The simulator in its own process, so that its real-time loop does not share the caller's GIL."""

from __future__ import annotations

import multiprocessing as mp
import signal
from dataclasses import dataclass, field

from trajectories.errors import FriError

from .config import SimConfig
from .stats import SimStats


_PRELOAD = ["lbrcli.fri.sim.simulator"]  # what a simulator process imports (pinocchio, the plants): ≈ 0.8 s of CPU


def child_context():
    """The multiprocessing context for simulator processes: a fork server that has imported the simulator once, so
    that a process running many sessions (a sweep, a campaign, a test worker) starts each in milliseconds instead of
    importing anew; a fresh interpreter (spawn) where there is no fork server. Never a fork of the caller (its
    threads and sockets stay its own)."""
    if "forkserver" not in mp.get_all_start_methods():
        return mp.get_context("spawn")
    ctx = mp.get_context("forkserver")
    ctx.set_forkserver_preload(_PRELOAD)  # takes effect when the server starts (the first child)
    return ctx


def _child_main(config: SimConfig, conn, stop_event) -> None:
    from .simulator import Simulator

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent decides when the simulator stops
    try:
        sim = Simulator(config, stop=stop_event.is_set)
    except BaseException as exc:  # noqa: BLE001 - reported to the parent as one line
        conn.send(("error", f"{exc}"))
        return
    conn.send(("bound", (sim.address, sim.plant_info)))
    try:
        stats = sim.run()
    except BaseException as exc:  # noqa: BLE001
        _send(conn, ("error", f"simulator failed: {type(exc).__name__}: {exc}"))
        return
    _send(conn, ("stats", stats))


def _send(conn, message: tuple) -> None:
    """Report to the parent; nothing if it is gone (the loop ended as ``parent_exited``)."""
    try:
        conn.send(message)
    except OSError:
        pass


@dataclass
class SimulatorProcess:
    """The simulator in a process of its own; context manager (``with SimulatorProcess(cfg) as sim: ...``).
    The simulator ends its loop by itself when this (parent) process is gone."""

    config: SimConfig
    address: tuple[str, int] | None = None
    plant_info: dict = field(default_factory=dict)  # what the plants reported at start (e.g. pendulum_path)
    stats: SimStats | None = None
    _proc: object = field(default=None, repr=False)
    _conn: object = field(default=None, repr=False)
    _stop: object = field(default=None, repr=False)

    @property
    def pendulum_path(self) -> str | None:
        """The emulated pendulum module's serial device (a PendulumModule plant), else None."""
        return self.plant_info.get("pendulum_path")

    def start(self, timeout: float = 60.0) -> "SimulatorProcess":
        """Start the process; returns once its socket is bound (``.address``). FriError if it cannot start."""
        self.config.validate()
        ctx = child_context()
        parent, child = ctx.Pipe(duplex=False)
        self._stop = ctx.Event()
        self._proc = ctx.Process(
            target=_child_main, args=(self.config, child, self._stop), daemon=True, name="lbr-fri-sim"
        )
        self._proc.start()
        child.close()
        self._conn = parent
        if not parent.poll(timeout):
            self._kill()
            raise FriError(f"FRI simulator did not start within {timeout:g} s")
        try:
            kind, payload = parent.recv()
        except EOFError:
            self._kill()
            raise FriError("FRI simulator process exited during start-up") from None
        if kind != "bound":
            self._proc.join(5)
            raise FriError(f"FRI simulator: {payload}")
        address, self.plant_info = payload
        self.address = tuple(address)
        return self

    def _receive_stats(self, timeout: float | None) -> SimStats | None:
        if self.stats is not None:
            return self.stats
        if self._conn is None:
            return None
        try:
            if not self._conn.poll(timeout):
                return None
            kind, payload = self._conn.recv()
        except (EOFError, OSError):
            self._proc.join(1)
            raise FriError("FRI simulator process ended without statistics") from None
        self._proc.join(5)
        if kind != "stats":
            raise FriError(f"FRI simulator: {payload}")
        self.stats = payload
        return payload

    def wait(self, timeout: float | None = None) -> SimStats | None:
        """Wait for the session to end by itself (IDLE or max_runtime_s); None on timeout."""
        return self._receive_stats(timeout)

    def stop(self, timeout: float = 5.0) -> SimStats:
        """End the loop, join the process and return the statistics."""
        if self.stats is not None:
            return self.stats
        if self._stop is not None:
            self._stop.set()
        stats = self._receive_stats(timeout)
        if stats is None:
            self._kill()
            raise FriError(f"FRI simulator did not stop within {timeout:g} s")
        return stats

    def _kill(self) -> None:
        if self._proc is not None and self._proc.is_alive():
            self._proc.terminate()
            self._proc.join(2)

    @property
    def running(self) -> bool:
        return self._proc is not None and self._proc.is_alive()

    def __enter__(self) -> "SimulatorProcess":
        return self if self.address is not None else self.start()

    def __exit__(self, *exc) -> None:
        if self.stats is None and self._proc is not None:
            try:
                self.stop()
            except FriError:
                pass
