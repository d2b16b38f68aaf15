"""CPU per cycle of ``ClientApplication.step`` alone, in lock-step and without the network or the machine's timing.

A session of ``lbr execute``'s client (a trajectory player with the figures and the execution log as observers, the
log's rows handed to its writer process as ``lbr execute`` does: :class:`~lbrcli.fri.logwriter.LogProcess`) is
recorded against the scripted controller (``lbrcli.fri.testing``) over loopback; the monitoring datagrams it
received are then replayed to a new application whose transport hands them over from memory and swallows the
replies. Figures: the best of ``REPEATS`` timed replays [µs per step] (the best, as timeit: other work on a shared
machine only ever slows a run) and their median, with the reply prepared a cycle ahead and built in step, and the
best of the replays with a sleep of ``GAP_S`` before each step, as between the messages of a session (the code and
data of a cycle are then out of the CPU's caches: what a session's cycle costs, system calls apart). The same for a
user's LBRClient (KUKA's sine overlay, built in step, no observers), with its Python function calls per cycle (the
work, independent of the machine's speed and load); with
``--profile`` the cProfile of one replay (top functions by own time). It measures the code of a cycle (decode,
checks, client callback, guard, encode, observers), not the system calls.

Run: `python benchmarks/run_all.py fri_step` or `python benchmarks/bench_fri_step.py [--quick] [--profile]`.
"""

from __future__ import annotations

import cProfile
import pstats
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import math

import numpy as np

from lbrcli.fri import ClientApplication, ExecutionLog, LBRClient, LogObserver, SessionFigures, TrajectoryPlayer
from lbrcli.fri.logwriter import LogProcess
from lbrcli.fri.testing import CA, CW, IDLE, MR, MW, Cycle, ScriptedController
from trajectories.limits import default_limits

Q0 = (0.0, 0.071, 0.0, -1.3523, 0.0, 0.1301, 0.0)  # [rad]
ROWS = 3000  # 3 s at 1 ms
REPEATS = 7
GAP_S = 9e-4  # [s] the sleep before each step in the replays "as in a session" (a 1 ms period less the step)
LIM = default_limits()
LOG_IN_PROCESS = False  # the player's log as lbr execute writes it (a child process); True: LogObserver in the loop
_WRITERS: list[Any] = []


def trajectory(n: int) -> np.ndarray:
    """(n, 7) rest-to-rest minimum-jerk move from Q0 [rad] at 1 ms rows."""
    s = np.linspace(0.0, 1.0, n)
    p = 10 * s**3 - 15 * s**4 + 6 * s**5
    return np.array(Q0) + 0.3 * p[:, None] * np.array([1, 0.5, -0.5, 1, 0.3, -1, 1])


class SineOverlay(LBRClient):
    """A user's LBRClient as KUKA's LBRJointSineOverlay example (examples/joint_sine_overlay.py): a filtered sine on
    A4 over where the session started (the scripted controller's ipo echoes the command; a controller's would not),
    built in ``command`` (nothing prepared), no observers."""

    def __init__(self) -> None:
        self.offset = self.phi = 0.0
        self.base: tuple[float, ...] | None = None

    def command(self, state):
        return self._next(state)

    def _next(self, state):
        if self.base is None:
            self.base = tuple(state.ipo_joint_position)
        self.offset = self.offset * 0.99 + 0.04 * math.sin(self.phi) * 0.01
        self.phi = (self.phi + 2 * math.pi * 0.25e-3) % (2 * math.pi)
        return [x + self.offset if j == 3 else x for j, x in enumerate(self.base)]


class PreparedSineOverlay(SineOverlay):
    """The same with its next command prepared after each reply, as examples/joint_sine_overlay.py does (the
    application then sends the reply prepared for the message at once and confirms it with ``command``)."""

    next_q: list[float] | None = None

    def command(self, state):
        q, self.next_q = self.next_q or self._next(state), None
        return q

    def prepare_command(self):
        self.next_q = self._next(self.robot_state)
        return self.next_q


def _app(folder: Path, tag: str, prepare: bool = True, client: str = "player") -> ClientApplication:
    if client.startswith("overlay"):
        user = PreparedSineOverlay() if client == "overlay prepared" else SineOverlay()
        return ClientApplication(user, "127.0.0.1", 0, bind_host="127.0.0.1", version="1.15", limits=LIM,
                                 paced_by_replies=True)  # fmt: skip
    if LOG_IN_PROCESS:
        log: Any = LogObserver(ExecutionLog(folder / f"{tag}.csv"))
    else:  # as lbr execute: the rows formatted by a child process, the loop hands each message over
        log = LogProcess(folder / f"{tag}.csv")
        _WRITERS.append(log)
    player = TrajectoryPlayer(trajectory(ROWS), LIM, period_s=1e-3, settle_cycles=4)
    return ClientApplication(player, "127.0.0.1", 0, bind_host="127.0.0.1", version="1.15", limits=LIM,
                             observers=[log, SessionFigures()], prepare=prepare, paced_by_replies=True)  # fmt: skip


def close_writers() -> None:
    """Wait for the log writer processes of the sessions so far."""
    while _WRITERS:
        _WRITERS.pop().close()


def scripted_session(app: ClientApplication, version: str = "1.15") -> None:
    """Run ``app`` (connected) against the scripted controller: the states to COMMANDING_ACTIVE, ROWS + 20 cycles of
    it, IDLE; unpaced (each message as soon as the last reply arrived)."""
    script = ([Cycle(state=IDLE)] + [Cycle(state=MW, quality=1)] * 3 + [Cycle(state=MR)] * 3 + [Cycle(state=CW)] * 4
              + [Cycle(state=CA)] * (ROWS + 20) + [Cycle(state=IDLE)])  # fmt: skip
    ctl = ScriptedController(app.port, script, Q0, pace_s=0.0, version=version).start()
    try:
        app.run()
    finally:
        ctl.finish(app)


def record(folder: Path, client: str = "player") -> list[bytes]:
    """The monitoring datagrams of one scripted session, as the client received them (its log writer closed)."""
    app = _app(folder, "record", client=client).connect()
    got: list[bytes] = []
    receive = app.transport.receive  # type: ignore[union-attr]

    def recording() -> bytes | None:
        data = receive()
        if data is not None:
            got.append(data)
        return data

    app.transport.receive = recording  # type: ignore[union-attr]
    scripted_session(app)
    close_writers()
    return got


class ReplayTransport:
    """Hands the recorded datagrams over in order (then None: a silent controller); replies are dropped."""

    def __init__(self, datagrams: list[bytes]) -> None:
        self._it = iter(datagrams)
        self.sent = self.foreign = self.polled = 0
        self.port, self.robot_ip, self.warm = 0, "127.0.0.1", None

    def expect_period(self, period_s: float | None) -> None:
        pass

    def receive(self) -> bytes | None:
        return next(self._it, None)

    def send(self, data: bytes) -> None:
        self.sent += 1

    def close(self) -> None:
        pass


def replay(folder: Path, datagrams: list[bytes], prepare: bool, profile: cProfile.Profile | None = None,
           gap_s: float = 0.0, client: str = "player") -> tuple[float, int, str]:  # fmt: skip
    """[µs] per step over one replay, the steps, and how the session ended. ``gap_s`` [s]: a sleep before each step
    (as between two messages of a session; only the steps' CPU time is counted)."""
    app = _app(folder, "replay", prepare, client)
    app.transport = ReplayTransport(datagrams)  # type: ignore[assignment]
    app.start()
    step, n, cpu, clock = app.step, 0, 0, time.thread_time_ns
    if profile is not None:
        profile.enable()
    while n < len(datagrams):
        if gap_s:
            time.sleep(gap_s)
        t0 = clock()
        going_on = step()
        cpu += clock() - t0
        if not going_on:
            break
        n += 1
    if profile is not None:
        profile.disable()
    reason = app.result.reason.value if app.result is not None else "running"
    close_writers()
    return cpu * 1e-3 / max(n, 1), n, reason


def run(quick: bool = False, profile: bool = False) -> list[tuple[str, float, str]]:
    """The figures (name, value, unit): µs per step, best and median of the replays, prepared and built in step."""
    repeats = 3 if quick else REPEATS
    rows: list[tuple[str, float, str]] = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        datagrams = record(folder)
        for prepare in (True, False):  # the reply prepared a cycle ahead (lbr execute's default), or built in step
            tag = "prepared a cycle ahead" if prepare else "built in step"
            runs = [replay(folder, datagrams, prepare) for _ in range(repeats)]
            us = [r[0] for r in runs]
            rows += [(f"step, reply {tag}: CPU per cycle, best of {repeats}", round(min(us), 2), "µs"),
                     (f"step, reply {tag}: CPU per cycle, median", round(float(np.median(us)), 2), "µs")]  # fmt: skip
            # the same with a sleep between steps, as in a session (the code and data out of the CPU's caches)
            runs = [replay(folder, datagrams, prepare, gap_s=GAP_S) for _ in range(repeats)]
            us = [r[0] for r in runs]
            rows.append((f"step, reply {tag}, {GAP_S * 1e3:g} ms sleep before each: CPU per cycle, best of {repeats}",
                         round(min(us), 2), "µs"))  # fmt: skip
            if profile:
                prof = cProfile.Profile()
                replay(folder, datagrams, prepare, prof)
                pstats.Stats(prof).sort_stats("tottime").print_stats(12)
        # a user's LBRClient (the sine overlay): its command built in step, no observers — the library's own cycle;
        # then prepared a cycle ahead as the example does
        for client, tag in (("overlay", "sine overlay"), ("overlay prepared", "sine overlay, prepared a cycle ahead")):
            datagrams = record(folder, client)
            for gap in (0.0, GAP_S):
                us = [replay(folder, datagrams, False, gap_s=gap, client=client)[0]
                      for _ in range(repeats)]  # fmt: skip
                when = f", {GAP_S * 1e3:g} ms sleep before each" if gap else ""
                rows.append((f"step, a user's LBRClient ({tag}){when}: CPU per cycle, best of {repeats}",
                             round(min(us), 2), "µs"))  # fmt: skip
            prof = cProfile.Profile()
            n = replay(folder, datagrams, False, prof, client=client)[1]
            calls = sum(v[1] for v in pstats.Stats(prof).stats.values())  # the work, whatever the machine's speed
            rows.append((f"step, a user's LBRClient ({tag}): Python function calls per cycle", round(calls / n, 1), ""))
    return rows


def main(argv: list[str], name: str = "fri_step", run_fn=None) -> int:
    """Print the figures of ``run_fn`` (``run``) and, unless ``--quick``, save them as benchmark ``name``."""
    from run_all import save_results

    t0 = time.perf_counter()
    rows = (run_fn or run)(quick="--quick" in argv, profile="--profile" in argv)
    for label, value, unit in rows:
        print(f"  {label:<80} {value:>8.2f} {unit}")
    if "--quick" not in argv:
        save_results(name, rows, time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
