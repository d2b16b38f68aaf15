"""The command bridge (`lbr serve`, issue #18) on the simulator at a 1 ms FRI period, sources in other processes.

1. UDP, 1 kHz joint targets: added latency from a target's send (a conservative stand-in for its arrival: loopback
   transit included) to the FRI command that first carries it (the reply on the wire: an application observer,
   which runs after the send), split into the wait for the next FRI cycle (the controller asks once per period;
   nothing can answer sooner) and the bridge's own work from the FRI message to the reply; the commands' peak
   ratios to the limits.
2. MQTT over a real Mosquitto broker, 30 Hz ± 10 ms TCP-pose targets (a 6 cm circle, teleoperation): the jerk of
   the 1 kHz stream, the TCP's distance from the drawn path, the state rate back at the source, latency.
3. Source loss mid-motion: from the last target to the braking stop (dead-man 0.1 s), how long the stop takes and
   its peak ratios.

The real-time sessions' ratios to the limits are of the commands the controller received in time. A late reply
(the PC busy: the simulator's message said our previous reply had not arrived) makes the controller bridge the
period by extrapolation, as KUKA's does: it holds the velocity, so its executed acceleration steps to 0 within one
period (the controller's own step, which no client can prevent). The "executed" rows judge the motion the simulator
executed (its measured positions: in position mode its interpolator's, which lands on every command it can reach),
split into the steps that executed our commands ("ours": measured against the history the controller really
executed) and the controller's bridging steps. The share of late replies is reported beside them. The lock-step
bands report the same split for the motion the scripted controller executed with replies lost (a session the lost
replies took too far off the client's path ends with a braking stop: reported).
"""

from __future__ import annotations

import math
import multiprocessing as mp
import struct
import tempfile
import time
from pathlib import Path

import numpy as np

Q0 = (0.0, 0.5, 0.0, -1.2, 0.0, 0.8, 0.0)  # [rad] away from the wrist singularity of the thesis start


def _wave(t: float) -> list[float]:
    q = list(Q0)
    q[0] += 0.3 * math.sin(2 * math.pi * 0.5 * t)
    q[3] += 0.2 * (1 - math.cos(2 * math.pi * 0.5 * t))
    return q


def _pace(next_t: float) -> None:
    """Sleep until time.monotonic() reaches next_t (no spinning: the machine has 2 cores for the simulator, the
    bridge and the source; late wake-ups catch up, as a Simulink model's UDP block does)."""
    left = next_t - time.monotonic()
    if left > 0:
        time.sleep(left)


def _udp_source(port: int, delay_s: float, seconds: float, rate_hz: float, end: bool) -> None:
    from lbrcli.bridge import BridgeClient

    c = BridgeClient("127.0.0.1", port)
    time.sleep(delay_s)
    t0 = time.monotonic()
    k = 0
    while (now := time.monotonic()) - t0 < seconds:
        c.send_joint(_wave(now - t0), t=time.monotonic())
        k += 1
        _pace(t0 + k / rate_hz)
    if end:
        c.end()
    c.close()


def _mqtt_source(url: str, delay_s: float, seconds: float, out) -> None:
    from lbrcli.bridge import MqttBridgeClient
    from trajectories.robot import Robot

    home = Robot().fk(np.array(Q0))
    r = home.rotation
    angles = (math.atan2(r[1, 0], r[0, 0]), -math.asin(r[2, 0]), math.atan2(r[2, 1], r[2, 2]))
    c = MqttBridgeClient(url, source_id=3)
    rng = np.random.default_rng(0)
    time.sleep(delay_s)
    t0 = time.monotonic()
    path = []
    while (now := time.monotonic()) - t0 < seconds:
        phi = 2 * math.pi * 0.25 * (now - t0)
        p = home.translation + 0.06 * np.array([math.cos(phi) - 1, math.sin(phi), 0.0])
        c.send_pose_zyx(p, angles, t=time.monotonic())
        path.append(p)
        time.sleep(max(0.0, 1 / 30 + rng.uniform(-0.01, 0.01)))
    n_states = len(c.states)
    c.end()
    time.sleep(0.3)
    c.close()
    out.put((np.array(path), n_states, seconds))


class _Stamped:
    """Wraps a transport; notes the source time of every binary target it delivers."""

    def __init__(self, inner, stamps: list) -> None:
        self.inner, self.stamps, self.name = inner, stamps, inner.name

    def receive(self):
        for data, sender in self.inner.receive():
            if data[:4] == b"LBRT":
                self.stamps.append(struct.unpack_from("<d", data, 16)[0])
            yield data, sender

    def __getattr__(self, name):
        return getattr(self.inner, name)


class _Latency:
    """Application observer (runs after the reply went out): the age of every target taken in this cycle."""

    name = "latency"

    def __init__(self, stamps: list) -> None:
        self.stamps = stamps
        self.latency: list[float] = []  # [s] source send → reply sent
        self.work: list[float] = []  # [s] FRI message in → reply sent (the bridge's own part)

    def on_cycle(self, app) -> None:
        now = time.monotonic()
        if app.cycle.state == 4 and not app.cycle.braking:
            self.latency.extend(now - t for t in self.stamps)
            if self.stamps and app.latencies:  # a cycle that took a target: FRI message in → reply out [ns]
                self.work.append(app.latencies[-1] * 1e-9)
        self.stamps.clear()


def _session(transport, source_proc, duration_s: float, tmp: Path, timeout_s: float = 0.1):
    """Run the follower on ``transport`` against the simulator; (result, latency observer, log table)."""
    from lbrcli.bridge import TargetFollower, TargetInbox
    from lbrcli.fri import ClientApplication, ExecutionLog, LogObserver
    from lbrcli.fri.log import LOG_COLUMNS
    from lbrcli.fri.sim import SimConfig, SimulatorProcess, lenient_quality
    from trajectories.csvio import read_table
    from trajectories.limits import default_limits

    lim = default_limits()
    stamps: list[float] = []
    inbox = TargetInbox([_Stamped(transport, stamps)])
    follower = TargetFollower(inbox, lim, timeout_s=timeout_s, first_target_s=30.0, speed_scale=0.5)
    lat = _Latency(stamps)
    log_path = tmp / f"bridge-{time.monotonic_ns()}.csv"
    with ExecutionLog(log_path) as log:
        with ClientApplication(follower, "127.0.0.1", 0, bind_host="127.0.0.1", limits=lim, first_message_timeout_s=20,
                               observers=[lat, LogObserver(log)]) as app:  # fmt: skip
            config = SimConfig(client_port=app.port, period_ms=1, q0=Q0, **lenient_quality(1))
            with SimulatorProcess(config):
                source_proc.start()
                result = app.run(duration_s)
    source_proc.join(30)
    inbox.close()
    return result, lat, read_table(log_path, LOG_COLUMNS, time="increasing"), lim


def _on_time(tab) -> np.ndarray:
    """Rows whose message says our previous reply reached the controller in time (its reflected counter is the counter
    of our reply to the message just before): the controller executed that command, not its extrapolation of the two
    before it. (Our counter counts our replies, not the controller's messages: after a message we never answered it
    lags the message counter for good — comparing those two read every reply of such a session as late.)"""
    seq, refl = tab.column("seq"), tab.column("reflected_seq")
    ours, answered = tab.column("client_seq"), tab.column("answered")
    ok = np.zeros(len(seq), dtype=bool)
    ok[1:] = (np.diff(seq) == 1) & (refl[1:] == ours[:-1]) & (answered[:-1] == 1)
    return ok


def _consecutive(tab, keep, k: int) -> np.ndarray:
    """Per k-th difference of the rows kept: True where its k + 1 rows are consecutive messages (a client that caught
    up with the newest message logs none of those it skipped: a difference across them spans several periods)."""
    gap = np.diff(tab.column("seq")[keep]) != 1
    return np.convolve(gap.astype(float), np.ones(k), "valid") == 0 if len(gap) >= k else np.zeros(0, dtype=bool)


def _step_ratios(tab, lim, keep, in_time: bool = False) -> list[np.ndarray]:
    """|first, second, third differences| of the commands kept, per cycle and joint, over the velocity,
    acceleration and jerk limits. ``in_time``: NaN where a command of the difference did not reach the controller in
    time (a late reply makes it extrapolate: the motion it executes is then not the one we sent)."""
    q = np.column_stack([tab.column(f"cmd_q{j}") for j in range(1, 8)])[keep]
    late = (~_on_time(tab)[keep]).astype(float)
    out = []
    for k, lim_k in ((1, lim.velocity), (2, lim.acceleration), (3, lim.jerk)):
        r = np.abs(np.diff(q, k, axis=0)) / 1e-3**k / lim_k
        r[~_consecutive(tab, keep, k)] = np.nan
        if in_time and len(r):  # the commands i..i+k, each confirmed by the next row's counter (rows i..i+k+1)
            confirmed = np.append(np.convolve(late, np.ones(k + 2), "valid") == 0, False)[: len(r)]
            r[~confirmed] = np.nan
        out.append(r)
    return out


def _ratios(tab, lim, keep, in_time: bool = False) -> tuple[float, float, float]:
    return tuple(float(np.nanmax(r)) if np.isfinite(r).any() else float("nan")
                 for r in _step_ratios(tab, lim, keep, in_time))  # type: ignore[return-value]  # fmt: skip


def _over(tab, lim, keep, in_time: bool = False) -> int:
    """Commands whose step, second or third difference exceeds its limit."""
    ratios = _step_ratios(tab, lim, keep, in_time)
    over = np.zeros(len(ratios[0]) + 1, dtype=bool)
    for k, r in enumerate(ratios, start=1):
        over[k:] |= (r > 1 + 1e-6).any(axis=1)
    return int(over.sum())


def _late_share(tab, keep) -> float:
    """[%] of the rows kept whose previous reply was late (the controller extrapolated instead)."""
    ok = _on_time(tab)[keep]
    return float(100.0 * np.mean(~ok)) if ok.size else float("nan")


def _executed(tab, lim, keep) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """Peak velocity, acceleration and jerk over the limits of the motion the simulator executed (its measured
    positions; row i: after the step that executed the reply to message i − 1), (ours, the controller's bridging
    steps): a step is ours when the next message reflects the reply it executed (in time), else the controller's."""
    m = np.column_stack([tab.column(f"msr_q{j}") for j in range(1, 8)])[keep]
    ours = _on_time(tab)[keep]
    out = []
    for mask in (ours, ~ours):
        peaks = []
        for k, lim_k in ((1, lim.velocity), (2, lim.acceleration), (3, lim.jerk)):
            r = np.abs(np.diff(m, k, axis=0)) / 1e-3**k / lim_k
            sel = mask[k:] & _consecutive(tab, keep, k)  # the difference ending at row i + k is the step into it
            peaks.append(float(r[sel].max()) if sel.any() else 0.0)
        out.append(tuple(peaks))
    return out[0], out[1]  # type: ignore[return-value]


def _reported_judge(tab, lim, keep) -> tuple[np.ndarray, np.ndarray]:
    """(n, 3) ratios to the velocity, acceleration and jerk limits of every command kept, as the next step after the
    history the controller had executed when it sent the message answered (FRI 1.15's commanded positions,
    :func:`lbrcli.fri.testing.holding.reference_histories`: the held state after a step of its own beyond the
    limits); and (m, 3) those of the controller's own steps (the ones that did not execute our previous reply in
    time: bridged, or a late reply carried forward) over its commanded positions."""
    from lbrcli.fri.testing.holding import reference_histories, step_ratios

    ctl = np.column_stack([tab.column(f"ctl_q{j}") for j in range(1, 8)])[keep]
    cmd = np.column_stack([tab.column(f"cmd_q{j}") for j in range(1, 8)])[keep]
    seq = tab.column("seq")[keep]
    ours = _on_time(tab)[keep]
    follows = np.append(False, np.diff(seq) == 1)
    last3 = [(ctl[i], ctl[i - 1], ctl[i - 2]) if i >= 2 and follows[i] and follows[i - 1] else None
             for i in range(len(ctl))]  # fmt: skip
    hist = reference_histories(last3, ours, follows, 1e-3, lim)
    own = []
    for i in range(3, len(ctl)):
        if not ours[i] and follows[i] and follows[i - 1] and follows[i - 2]:
            d = (ctl[i] - ctl[i - 1], ctl[i] - 2 * ctl[i - 1] + ctl[i - 2],
                 ctl[i] - 3 * ctl[i - 1] + 3 * ctl[i - 2] - ctl[i - 3])  # fmt: skip
            own.append([np.max(np.abs(x) / (lk * 1e-3 ** (k + 1)))
                        for k, (x, lk) in enumerate(zip(d, (lim.velocity, lim.acceleration, lim.jerk)))])  # fmt: skip
    return step_ratios(cmd, hist, lim), np.array(own).reshape(-1, 3)


def _executed_rows(name: str, tab, lim, keep) -> list[tuple[str, float, str]]:
    ours, bridging = _executed(tab, lim, keep)
    rows = [(f"{name}: executed peak {what} / limit ({who})", x, "")
            for who, peaks in (("ours", ours), ("the controller's bridging steps", bridging))
            for what, x in zip(("velocity", "acceleration", "jerk"), peaks)]  # fmt: skip
    if "ctl_q1" not in tab.names:
        return rows
    mine, own = _reported_judge(tab, lim, keep)
    for who, r in (("our commands after the executed history", mine), ("the controller's own steps", own)):
        for k, what in enumerate(("velocity", "acceleration", "jerk")):
            x = r[:, k] if len(r) else np.zeros(0)
            rows.append((f"{name}: {who}: peak {what} / limit", float(np.nanmax(x)) if np.isfinite(x).any() else 0.0,
                         ""))  # fmt: skip
    x = mine[:, 2] if len(mine) else np.zeros(0)
    rows.append((f"{name}: our commands over the jerk limit", float(np.sum(x > 1.0 + 1e-6)), ""))
    return rows


def _online_ik(n: int) -> list[tuple[str, float, str]]:
    """The pose follower's IK per call: poses within 0.05 rad of a posture, seeded 0.01 rad off (a streamed pose)."""
    from trajectories.ik_online import OnlineIk
    from trajectories.limits import default_limits
    from trajectories.robot import Robot

    robot = Robot()
    ik = OnlineIk(robot, default_limits())
    rng = np.random.default_rng(1)
    times, converged = [], 0
    for _ in range(n):
        q = np.array(Q0) + rng.normal(0, 0.05, 7)
        m = robot.fk(q)
        seed = q + rng.normal(0, 0.01, 7)
        t0 = time.perf_counter()
        res = ik.solve(seed, m.translation, m.rotation)
        times.append(time.perf_counter() - t0)
        converged += res.converged
    us = np.array(times) * 1e6
    return [("online IK per pose p50", float(np.percentile(us, 50)), "µs"),
            ("online IK per pose p99", float(np.percentile(us, 99)), "µs"),
            ("online IK converged in one call", 100.0 * converged / n, "%")]  # fmt: skip


def _bands(quick: bool) -> list[tuple[str, float, str]]:
    """The follower in lock step (a scripted controller at 1 ms, a fake clock: the same on any machine): the largest
    error against the wave delayed by the bridge's final delay (after 1.5 s, once the delay settled from its first
    guess), and the executed motion's peak ratios to the limits — per source rate, feed-forward, lost replies and
    lateness (the targets' exponential mean lateness; 1 % of them 30 ms more)."""
    from lbrcli.bridge.testing import LockStepSource, follow_in_lock_step, wave
    from trajectories.limits import default_limits

    lim = default_limits()
    rows = []
    cases = [(1000.0, True), (250.0, True), (100.0, True), (100.0, False), (30.0, False)]
    for rate, ff in cases[:2] if quick else cases:
        for drop in (0.0, 0.01, 0.05) if quick else (0.0, 0.01, 0.05, 0.2):
            for late_ms in (2.0,) if quick else (1.0, 5.0):
                worst, delays, ours, bridging, stopped = math.nan, [], [], [], 0
                for seed in (0,) if quick else (0, 1):
                    r = follow_in_lock_step(LockStepSource(rate, ff, seed=seed, lateness_s=late_ms * 1e-3), lim,
                                            drop=drop, seed=seed)  # fmt: skip
                    d = r.follower.timeline.delay
                    keep = r.t > 1.5
                    ended = r.t[-1] < 2.9  # ended early: the braking stop after too many bridged commands
                    stopped += int(ended)
                    ref = np.array([wave(x - d)[0] for x in r.t[keep]])
                    if keep.any() and not ended:  # (the error of a session that kept following)
                        err = float(np.degrees(np.abs(r.q[keep, 0] - r.q0[0] - ref).max()))
                        worst = err if math.isnan(worst) else max(worst, err)
                    delays.append(d * 1e3)
                    ours.append(r.controller.motion_ratios(lim.velocity, lim.acceleration, lim.jerk))
                    bridging.append(r.controller.motion_ratios(lim.velocity, lim.acceleration, lim.jerk, bridged=True))
                name = (
                    f"lock step {rate:g} Hz {'ff' if ff else 'positions'}, {drop:.0%} replies lost, {late_ms:g} ms late"
                )
                if not math.isnan(worst):  # (none when every session of the case ended early)
                    rows.append((f"{name}: max error behind the delay", worst, "deg"))
                rows += [(f"{name}: delay", max(delays), "ms"),
                         (f"{name}: sessions ended by the lost replies (braking stop)", float(stopped), "")]  # fmt: skip
                for who, ratios in (("ours", ours), ("the controller's bridging steps", bridging)):
                    for i, what in enumerate(("velocity", "acceleration", "jerk")):
                        rows.append((f"{name}: peak {what} / limit ({who})", max(x[i] for x in ratios), ""))
    return rows


def _pct(values, q: float) -> float:
    """The q-th percentile of ``values``; NaN when there are none (a session the loaded PC cut short)."""
    return float(np.percentile(values, q)) if len(values) else float("nan")


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    from bench_lab import _broker  # a Mosquitto on a free loopback port (benchmarks/ is on the path)

    from lbrcli.bridge import MqttTransport, UdpTransport
    from lbrcli.fri.log import PHASE_BRAKE
    from lbrcli.lab.telemetry import parse_mqtt_url
    from trajectories.robot import Robot

    ctx = mp.get_context("spawn")
    seconds = 4.0 if quick else 20.0
    rows = _bands(quick) + _online_ik(500 if quick else 5000)
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        # 1. UDP at 1 kHz, ended by the source
        udp = UdpTransport(0)
        src = ctx.Process(target=_udp_source, args=(udp.port, 2.0, seconds, 1000.0, True), daemon=True)
        result, lat, tab, lim = _session(udp, src, seconds + 30, tmp)
        ms = np.array(lat.latency) * 1e3
        active = (tab.column("state") == 4) & (np.cumsum(tab.column("phase") == PHASE_BRAKE) == 0)
        act = tab.column("state") == 4
        v, a, j = _ratios(tab, lim, act, in_time=True)
        rows += [
            ("udp 1 kHz: targets measured", len(ms), ""),
            ("udp 1 kHz: send -> FRI command p50", _pct(ms, 50), "ms"),
            ("udp 1 kHz: send -> FRI command p99", _pct(ms, 99), "ms"),
            ("udp 1 kHz: send -> FRI command max", _pct(ms, 100), "ms"),
            ("udp 1 kHz: share under 1 ms", float(np.mean(ms < 1.0) * 100) if len(ms) else float("nan"), "%"),
            ("udp 1 kHz: bridge work (FRI message -> reply) p50", _pct(np.array(lat.work) * 1e3, 50), "ms"),
            ("udp 1 kHz: bridge work (FRI message -> reply) p99", _pct(np.array(lat.work) * 1e3, 99), "ms"),
            ("udp 1 kHz: replies late (the controller extrapolated)", _late_share(tab, act), "%"),
            ("udp 1 kHz: commands over the limits (replies in time)", float(_over(tab, lim, act, in_time=True)), ""),
            ("udp 1 kHz: peak velocity / limit (replies in time)", v, ""),
            ("udp 1 kHz: peak acceleration / limit (replies in time)", a, ""),
            ("udp 1 kHz: peak jerk / limit (replies in time)", j, ""),
            ("udp 1 kHz: following cycles", float(active.sum()), ""),
            ("udp 1 kHz: session ended", 1.0 if result.ok else 0.0, "(1 = by the source's end message)"),
        ] + _executed_rows("udp 1 kHz", tab, lim, act)
        # 2. MQTT over Mosquitto, 30 Hz poses
        broker, port = _broker(tmp)
        if broker is None:
            rows.append(("mqtt: not measured (no mosquitto)", 0.0, ""))
        else:
            try:
                url = f"mqtt://127.0.0.1:{port}/bench/iiwa/cmd"
                mq = MqttTransport(parse_mqtt_url(url), state_rate_hz=50.0).start()
                out = ctx.Queue()
                src = ctx.Process(target=_mqtt_source, args=(url, 2.0, seconds, out), daemon=True)
                result, lat, tab, lim = _session(mq, src, seconds + 30, tmp)
                path, n_states, dur = out.get(timeout=30)
                keep = (tab.column("state") == 4) & (np.cumsum(tab.column("phase") == PHASE_BRAKE) == 0)
                v, a, j = _ratios(tab, lim, keep, in_time=True)
                q = np.column_stack([tab.column(f"cmd_q{k}") for k in range(1, 8)])[keep]
                tcp, _ = Robot().fk_path(q[::10])
                dist = np.linalg.norm(tcp[:, None, :] - path[None, :, :], axis=2).min(axis=1) * 1e3
                ms = np.array(lat.latency) * 1e3
                rows += [
                    ("mqtt 30 Hz poses: targets", float(len(path)), ""),
                    ("mqtt 30 Hz poses: replies late (the controller extrapolated)", _late_share(tab, keep), "%"),
                    ("mqtt 30 Hz poses: peak jerk / limit (following, replies in time)", j, ""),
                    ("mqtt 30 Hz poses: peak acceleration / limit (following, replies in time)", a, ""),
                    ("mqtt 30 Hz poses: TCP distance from the drawn path max", float(dist.max()), "mm"),
                    ("mqtt 30 Hz poses: TCP distance from the drawn path p50", float(np.median(dist)), "mm"),
                    ("mqtt 30 Hz poses: send -> FRI command p50 (via broker)", _pct(ms, 50), "ms"),
                    ("mqtt 30 Hz poses: send -> FRI command p99 (via broker)", _pct(ms, 99), "ms"),
                    ("mqtt 30 Hz poses: states received per second", n_states / dur, "Hz"),
                ] + _executed_rows("mqtt 30 Hz poses", tab, lim, keep)
            finally:
                broker.terminate()
                broker.wait(5)
        # 3. source loss mid-motion: the dead-man (0.1 s)
        udp = UdpTransport(0)
        src = ctx.Process(target=_udp_source, args=(udp.port, 2.0, 1.6, 1000.0, False), daemon=True)
        result, lat, tab, lim = _session(udp, src, 30.0, tmp)
        brake = tab.column("phase") == PHASE_BRAKE
        act = tab.column("state") == 4
        v, a, j = _ratios(tab, lim, act, in_time=True)
        q = np.column_stack([tab.column(f"cmd_q{k}") for k in range(1, 8)])
        b0, b1 = np.flatnonzero(brake)[[0, -1]] if brake.any() else (0, -1)  # no stop: a zero-length one, reported
        speed0 = np.abs(q[b0] - q[b0 - 1]).max() / 1e-3 if b0 > 0 else 0.0
        rows += [
            ("source loss: ended by the dead-man", 1.0 if "dead-man" in result.detail else 0.0, ""),
            ("source loss: braking stop", (b1 - b0 + 1) * 1.0, "ms"),
            ("source loss: joint speed at the loss (fastest joint)", speed0, "rad/s"),
            ("source loss: replies late (the controller extrapolated)", _late_share(tab, act), "%"),
            ("source loss: peak velocity / limit (replies in time)", v, ""),
            ("source loss: peak acceleration / limit (replies in time)", a, ""),
            ("source loss: peak jerk / limit (replies in time)", j, ""),
            ("source loss: braking stop's peak jerk / limit (replies in time)", _ratios(tab, lim, brake, True)[2], ""),
        ] + _executed_rows("source loss", tab, lim, act)
    return rows
