"""The simulator loop: one simulated controller (``Controller``) on a UDP link (``Link``), in real time.

Every send period the loop sends a monitoring message and collects the client's command messages until the next
send. A cycle counts as timely when a reply to the message just sent arrives before the next send (with
receiveMultiplier k: one such reply within k cycles). The loop sleeps in select and busy-waits the last
``spin_us`` before each send (steadier than a sleep-only rate limiter at 1 ms), re-synchronises after an overrun,
and can run with SCHED_FIFO (``realtime``). A real controller sends strictly periodically; when this process
started a cycle late (its own scheduling), the next cycle still starts ``MIN_SPACING`` periods after it (and at
least ``MIN_SEND_SPACING`` after a send delayed within its cycle), so the client keeps (almost) a whole period to
answer and is not judged late for the simulator's delay; the cycles return to their grid over the following
periods. In lock-step (``lockstep_timeout_s``) the loop also waits for each reply the client owes before the next
cycle, and the session's time advances one period per cycle: a closed loop on a busy machine runs slower than real
time but exactly as on an idle one (the controller's timestamps, the plants and the sensors they feed all run on
that time). However the loop stops (session end, stop(), timeout, parent gone), the last messages carry IDLE, as when
a robot application ends and its FRI session closes.
"""

from __future__ import annotations

import gc
import os
import time
from typing import Callable

import numpy as np

from ..constants import ConnectionQuality, SessionState
from .config import SimConfig
from .controller import Controller
from .link import RING, Faults, Link
from .stats import SimStats, percentiles


MIN_SPACING = 0.9  # [periods] least time between the starts of two cycles (a late start is followed by a full one)
MIN_SEND_SPACING = 0.5  # [periods] least time from a send to the next cycle's start (a send delayed inside a cycle)
CLOSE_BUDGET_S = 0.5  # [s] at most this long sending the closing IDLE messages after a stop or timeout


def _parent_watch() -> Callable[[], bool]:
    """A test that is true once the process that started this simulator has ended: the sentinel multiprocessing
    gives its children (closed when the starter ends, also from a fork server, which outlives the starter and is the
    simulator's parent), else a change of the parent process id (a simulator run directly by a command)."""
    import multiprocessing

    parent = multiprocessing.parent_process()
    if parent is not None:
        return lambda: not parent.is_alive()
    ppid = os.getppid()
    return lambda: os.getppid() != ppid


class Simulator:
    """One simulated controller bound to a UDP socket; ``run()`` drives the session until it ends."""

    def __init__(
        self,
        config: SimConfig,
        stop: Callable[[], bool] | None = None,
        on_state: Callable[[SessionState, ConnectionQuality, float], None] | None = None,
    ) -> None:
        config.validate()
        self.cfg = config
        self._stop = stop or (lambda: False)
        self._on_state = on_state
        self.period = config.period_ms * 1e-3  # [s]
        framed = config.version == "2.7"
        self.link = Link(
            config.host,
            config.port,
            config.client_host,
            config.client_port,
            Faults(config.loss, config.delay_ms, config.jitter_ms, config.malformed, config.seed),
            framed,
        )
        try:
            self.controller = Controller(config, sent_at=self.link.sent_at)
        except BaseException:
            self.link.close()
            raise
        self._cycle_time = np.empty(RING)  # send instant of each cycle (perf_counter) [s]
        self._work = np.empty(RING)  # computation time of each cycle [s]
        self.overruns = 0
        self._sent_by = 0.0  # [s] perf_counter right after the last send
        self._n_states = 0  # states reported to on_state so far
        self._parent_gone = _parent_watch()  # taken here: a parent may exit right after start-up, before run()

    @property
    def address(self) -> tuple[str, int]:
        return self.link.address

    @property
    def plant_info(self) -> dict:
        """What the plants report right after start (e.g. ``pendulum_path``), merged."""
        info: dict = {}
        for plant in self.controller.plants:
            info.update(plant.info())
        return info

    @property
    def pendulum_path(self) -> str | None:
        """Device path of an emulated pendulum module's serial port (None without one)."""
        return self.plant_info.get("pendulum_path")

    @staticmethod
    def _enter_realtime() -> bool:
        """SCHED_FIFO for this process (Linux, needs the privilege); False if not granted."""
        try:
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(10))
            return True
        except (AttributeError, OSError):
            return False

    def run(self) -> SimStats:
        """Drive the session until it ends (IDLE sent), ``stop()`` says so, max_runtime_s elapses or the parent
        process is gone; the last three close the FRI session first (``_close_session``). A KeyboardInterrupt
        closes it too and is raised again (a second one during the close ends at once)."""
        period, cfg, ctl, link = self.period, self.cfg, self.controller, self.link
        on_datagram = ctl.on_datagram
        spin = cfg.spin_us * 1e-6
        realtime = self._enter_realtime() if cfg.realtime else False
        gc.collect()
        gc.freeze()  # the objects built so far are never collected again: short collections in the loop
        t0 = time.perf_counter()
        cpu0 = time.process_time()
        grid = send_at = t0  # [s] the cycle's nominal time, and when its message may go out (≥ grid)
        end_reason = ""
        forced = interrupted = False  # the simulator stops before the session ended by itself
        k = 0
        lockstep = cfg.lockstep_timeout_s or 0.0  # [s] the reply wait of lock-step (0: real time)
        free = bool(lockstep and cfg.lockstep_free)  # lock-step off the period's grid: the next cycle at once
        suspended = -1  # lock-step: replies counted when the client last failed to answer in time (-1: it answers)
        try:
            try:
                while True:
                    now = time.perf_counter()
                    if free:
                        grid = now
                    elif now - grid > period:  # fell behind by more than a cycle: re-synchronise
                        self.overruns += 1
                        grid = now
                    rel = k * period if lockstep else grid - t0
                    gone = link.lost + link.malformed_sent
                    state = self._cycle(k, rel, now)
                    if lockstep and link.lost + link.malformed_sent == gone and ctl.awaits_reply():
                        if suspended < 0 or ctl.counts["replies"] > suspended:
                            answered = link.wait_for(ctl.answered, time.perf_counter() + lockstep, on_datagram)
                            # a client that stopped answering is not waited for again until it answers
                            suspended = -1 if answered else ctl.counts["replies"]
                    if state is SessionState.IDLE:
                        ctl.machine.note_idle_sent()
                        if ctl.machine.finished:
                            end_reason = ctl.machine.end_reason or "idle"
                            break
                    if self._stop():  # the session's own end (quality, safety stop, …) if it had one first
                        end_reason = ctl.machine.end_reason or "stopped"
                    elif cfg.max_runtime_s is not None and rel >= cfg.max_runtime_s:
                        end_reason = "max_runtime"
                    elif k % 512 == 0 and self._parent_gone():
                        end_reason = "parent_exited"
                    grid += period
                    # the client gets (almost) its whole period even when this message went out late; the sends
                    # return to the grid over the following cycles
                    send_at = max(grid, self._earliest_start(now))
                    k += 1
                    if end_reason:
                        forced = True
                        break
                    if not (free and ctl.answered()):  # free lock-step paces in real time until the client answers
                        link.wait_until(send_at, on_datagram, spin)
            except KeyboardInterrupt:
                end_reason, forced, interrupted = "stopped", True, True  # slot k is free or reused
                send_at = max(send_at, time.perf_counter())
            if forced:
                k = self._close_session(k, send_at, t0)
            link.flush(on_datagram)  # let in-flight delayed datagrams go out
        finally:
            link.close()
            ctl.close()
            gc.unfreeze()
        if interrupted:
            raise KeyboardInterrupt
        wall = time.perf_counter() - t0
        cpu = (time.process_time() - cpu0) / wall if wall > 0 else 0.0
        return self._stats(k + 1, end_reason, cpu, realtime)

    def _cycle(self, k: int, rel: float, now: float) -> SessionState:
        """Cycle ``k`` at ``rel`` [s] since the start (``now``: perf_counter [s]): take the replies that arrived,
        advance the controller, send its message; the state sent."""
        ctl = self.controller
        self.link.drain(ctl.on_datagram)  # replies waiting now arrived before the next send, even if we are late
        data = ctl.cycle(rel)
        self._cycle_time[k % RING] = time.perf_counter()  # the send instant of this cycle
        self.link.send(data, ctl.seq)
        self._sent_by = t = time.perf_counter()  # the datagram is out by now (even if this process was preempted)
        self._work[k % RING] = t - now
        if len(ctl.states_seen) != self._n_states:
            self._n_states = len(ctl.states_seen)
            if self._on_state is not None:
                self._on_state(ctl.state, ctl.quality, rel)
        return ctl.state

    def _earliest_start(self, started: float) -> float:
        """perf_counter [s] before which the next cycle must not start, the current one having started at
        ``started``: the client keeps (almost) its period after a late start or a send delayed within the cycle."""
        return max(started + MIN_SPACING * self.period, self._sent_by + MIN_SEND_SPACING * self.period)

    def _close_session(self, k: int, next_t: float, t0: float) -> int:
        """The robot application ends early (stop, timeout, parent gone): send the IDLE messages of a normal ending,
        one per period from ``next_t`` (perf_counter [s]), within ``CLOSE_BUDGET_S`` [s] — KUKA's clients leave
        their loop only on IDLE. ``k``: the first free cycle index; returns the last one used."""
        ctl, link = self.controller, self.link
        machine = ctl.machine
        if machine.finished:
            return k - 1
        machine.close()
        deadline = time.perf_counter() + CLOSE_BUDGET_S
        spin = self.cfg.spin_us * 1e-6
        while True:
            link.wait_until(next_t, ctl.on_datagram, spin)
            now = time.perf_counter()
            self._cycle(k, k * self.period if self.cfg.lockstep_timeout_s else next_t - t0, now)
            machine.note_idle_sent()
            if machine.finished or now + self.period > deadline:
                return k
            k += 1
            next_t = max(next_t + self.period, self._earliest_start(now))

    def _stats(self, ncycles: int, end_reason: str, cpu_fraction: float, realtime: bool) -> SimStats:
        ctl, link = self.controller, self.link
        c = ctl.counts
        n = min(ncycles, RING)
        times = self._cycle_time[:n] if ncycles <= RING else np.roll(self._cycle_time, -(ncycles % RING))
        pp = percentiles(np.diff(times) * 1e3)
        lat = ctl.latency[: min(ctl.n_latency, RING)] * 1e3
        lp = percentiles(lat)
        wp = percentiles(self._work[:n] * 1e6)
        plants = {p.name: p.figures() for p in ctl.plants}
        ball = next((f["max_ball_theta"] for f in plants.values() if "max_ball_theta" in f), None)
        return SimStats(
            cycles=ncycles,
            replies=c["replies"],
            late_replies=c["late"],
            missed_replies=c["missed"],
            malformed_received=c["malformed_rx"],
            foreign_received=c["foreign_rx"] + link.foreign,
            states_seen=tuple(ctl.states_seen),
            safety_stop=ctl.safety,
            min_tracking_performance=ctl.min_tracking,
            commanded_rows=c["commanded"],
            max_ball_theta=ball,
            end_reason=end_reason,
            lost_sent=link.lost,
            malformed_sent=link.malformed_sent,
            client_sequence_gaps=c["gaps"],
            overruns=self.overruns,
            active_cycles=c["active"],
            period_ms_p50=pp[0],
            period_ms_p99=pp[1],
            period_ms_max=pp[2],
            reply_latency_ms_p50=lp[0],
            reply_latency_ms_p99=lp[1],
            reply_latency_ms_max=lp[2],
            reply_latency_ms_p999=float(np.percentile(lat, 99.9)) if len(lat) else None,
            final_q=tuple(float(x) for x in ctl.arm.q),
            work_us_p50=wp[0],
            work_us_p99=wp[1],
            cpu_fraction=cpu_fraction,
            realtime=realtime,
            command_mode=self.cfg.command_mode,
            io_writes=ctl.io.writes,
            io_refused=ctl.io.refused,
            incomplete_commands=c["incomplete"],
            commands_without_position=c["no_position"],
            untimely_active_cycles=c["untimely_active"],
            plants=plants,
            cartesian_poses=c["poses"],
            command_problem=ctl.command_problem,
            transformations=ctl.transforms.figures() if ctl.transforms is not None else {},
            transformations_refused=ctl.transforms.refused if ctl.transforms is not None else 0,
        )
