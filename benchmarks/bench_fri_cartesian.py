"""FRI 2.7 CARTESIAN_POSE on `lbr sim`, judged by an independent forward kinematics (issue #40).

Every commanded pose is compared with the flange of the joints the simulator executed for it (the next monitoring
message's measured joints), through the thesis's DH table in plain numpy (lbrcli/fri/testing/dh.py) — not the
pinocchio model the simulator's IK and our client use. A deliberately wrong DH (d3 and d5 10 % long) judges the same
runs, to show the judge is sensitive (its error must be large).

- Our client (``LBRCommand.set_cartesian_pose``), simulator in lock-step (independent of the machine's speed): a
  circle of radius R in the base xy plane at 0.25 Hz, E1 swept ±0.3 rad at 0.2 Hz, over send periods, radii and two
  start poses (the thesis's and a bent one). Per run: ended by the application's duration, min tracking performance,
  the largest DH position / rotation error.
- KUKA's LBRCartesianOverlay (C++, SDK 2.7; skipped without a build, lbrcli/fri/testing/kuka_sdk.py) in real time at
  several periods and amplitudes: the measured flange's peak x offset against the amplitude and against the peak of
  its source's filtered sine (the filter coefficient 0.99 is per command, so it damps more at longer periods); the
  DH error over the commands executed on time (tracking performance 1). Its E1 sweep is 0.1° per command: 100°/s at
  1 ms, A3's velocity limit, which A1, A5 and A7 cannot follow at their limits — the simulator clips it as the
  controller's interpolator does (tracking performance ≈ 0), so at 1 ms the flange leaves the commanded path.

Run: `python benchmarks/run_all.py fri_cartesian [--quick]` (writes benchmarks/results/fri_cartesian.json).
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
from trajectories.start_poses import THESIS_START

HERE = Path(__file__).resolve().parent
BENT_Q0 = (0.4, 0.6, -0.3, -1.4, 0.3, 0.9, 0.2)  # [rad] a second start pose
THESIS_Q0 = THESIS_START  # [rad]


def _helpers():
    from lbrcli.fri.testing import dh as dh_fk
    from lbrcli.fri.testing import relay as fri_relay

    return dh_fk, fri_relay


def _wrong_dh_error(dh_fk, q, wire) -> float:
    """Position error [m] of a DH table with d3 and d5 10 % long (the insensitive-judge check)."""
    saved = dh_fk.D
    try:
        dh_fk.D = (0.340, 0.0, 0.440, 0.0, 0.440, 0.0, 0.152)
        return dh_fk.pose_error(q, wire)[0]
    finally:
        dh_fk.D = saved


def judge(mons, cmds, dh_fk, steady: bool) -> tuple[float, float, float, int, float]:
    """(max DH position error [m], rotation error [rad], least wrong-DH position error [m], pairs, peak |measured x − ipo
    x| [mm]) over the commands answering a COMMANDING_ACTIVE message whose next message reflects them (``steady``:
    and tracks with 1)."""
    by_seq = {m.header.sequenceCounter: m for m in mons}
    errs, wrong, peak = [], [], 0.0
    for c in cmds:
        pose = c.commandData.cartesianPose.element
        n = c.header.reflectedSequenceCounter
        m0, m1 = by_seq.get(n), by_seq.get(n + 1)
        if len(pose) != 7 or m0 is None or m1 is None or m0.connectionInfo.sessionState != 4:
            continue
        if m1.connectionInfo.sessionState != 4 or m1.header.reflectedSequenceCounter != c.header.sequenceCounter:
            continue
        if steady and m1.ipoData.trackingPerformance != 1.0:
            continue
        q = m1.monitorData.measuredJointPosition.value
        errs.append(dh_fk.pose_error(q, pose))
        wrong.append(_wrong_dh_error(dh_fk, q, pose))
        peak = max(peak, abs(m1.monitorData.measuredCartesianPose.element[0] - m1.ipoData.cartesianPose.element[0]))
    if not errs:
        return math.nan, math.nan, math.nan, 0, math.nan
    e = np.array(errs)
    return float(e[:, 0].max()), float(e[:, 1].max()), float(np.min(wrong)), len(errs), peak


def our_client(period_ms: int, radius: float, q0, seconds: float):
    """One lock-step session of a circle client; (stats, result, monitoring messages, commands)."""
    from lbrcli.fri import ClientApplication, LBRClient
    from lbrcli.fri.codec import FriCodec
    from lbrcli.fri.sim import SimConfig, SimulatorProcess, lenient_quality

    _, fri_relay = _helpers()

    class Circle(LBRClient):
        n = 0

        def command(self, state):
            p = np.array(state.ipo_cartesian_pose)
            t = self.n * state.sample_time
            self.n += 1
            w = 2 * math.pi * 0.25
            ramp = (1 - math.cos(math.pi * min(t, 1.0))) / 2  # grows smoothly to 1 over 1 s
            p[0] += radius * ramp * math.sin(w * t)  # [m]
            p[1] += radius * ramp * (1 - math.cos(w * t))
            e1 = state.ipo_redundancy_value + 0.3 * ramp * math.sin(2 * math.pi * 0.2 * t)
            self.robot_command.set_cartesian_pose(p, redundancy=e1)

    codec = FriCodec("2.7")
    app = ClientApplication(
        Circle(), "127.0.0.1", 0, version="2.7", paced_by_replies=True
    )  # the simulator in lock-step
    app.connect()
    with fri_relay.Relay(app.port) as relay:
        cfg = SimConfig(client_port=relay.port, version="2.7", command_mode="cartesian", period_ms=period_ms,
                        session_duration_s=seconds, commanding_after_s=0.05, lockstep_timeout_s=0.5, q0=tuple(q0),
                        **lenient_quality(period_ms))  # fmt: skip
        with SimulatorProcess(cfg) as sim:
            result = app.run()
            stats = sim.wait(30.0) or sim.stop()
    app.close()
    return (stats, result, [codec.decode_monitoring(d) for d in relay.to_client],
            [codec.decode_command(d) for d in relay.to_sim])  # fmt: skip


def kuka_overlay(exe: str, period_ms: int, amplitude_mm: float, seconds: float):
    """KUKA's LBRCartesianOverlay in real time; (stats, monitoring messages, commands)."""
    from lbrcli.fri.codec import FriCodec
    from lbrcli.fri.sim import SimConfig, SimulatorProcess, lenient_quality

    _, fri_relay = _helpers()
    codec = FriCodec("2.7")
    port = fri_relay.free_udp_port()
    proc = subprocess.Popen([exe, "", str(port), "0.15", str(amplitude_mm), "0.99"], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)  # fmt: skip
    try:
        with fri_relay.Relay(port) as relay:
            cfg = SimConfig(client_port=relay.port, version="2.7", command_mode="cartesian", period_ms=period_ms,
                            session_duration_s=seconds, commanding_after_s=0.05, max_runtime_s=seconds + 20,
                            **lenient_quality(period_ms))  # fmt: skip
            with SimulatorProcess(cfg) as sim:
                stats = sim.wait(seconds + 30) or sim.stop()
    finally:
        proc.kill()  # its main loop has no IDLE exit (unlike KUKA's other examples)
        proc.wait()
    return stats, [codec.decode_monitoring(d) for d in relay.to_client], [codec.decode_command(d) for d in relay.to_sim]


def run(quick: bool = False) -> list[tuple[str, float, str]]:
    dh_fk, _ = _helpers()
    rows: list[tuple[str, float, str]] = []
    periods = (2,) if quick else (1, 2, 5)
    radii = (0.03,) if quick else (0.01, 0.03, 0.06)
    poses = (("thesis", THESIS_Q0),) if quick else (("thesis", THESIS_Q0), ("bent", BENT_Q0))
    seconds = 1.5 if quick else 4.0
    worst = dict(pos=0.0, rot=0.0, wrong=math.inf, track=1.0)
    runs = ok = 0
    for period in periods:
        for radius in radii:
            for name, q0 in poses:
                stats, result, mons, cmds = our_client(period, radius, q0, seconds)
                pos, rot, wrong, n, _ = judge(mons, cmds, dh_fk, steady=False)
                runs += 1
                ok += stats.end_reason == "duration" and not stats.command_problem
                if stats.end_reason != "duration":
                    print(
                        f"ours {period} ms R {radius} m {name}: simulator ended by {stats.end_reason!r} "
                        f"{stats.command_problem}; client: {result.detail}",
                        file=sys.stderr,
                    )
                tag = f"ours {period} ms R {radius * 1e3:g} mm {name}"
                rows += [
                    (f"{tag}: ended by duration", float(stats.end_reason == "duration"), "bool"),
                    (f"{tag}: DH position error max", pos * 1e3, "mm"),
                    (f"{tag}: DH rotation error max", math.degrees(rot), "deg"),
                    (f"{tag}: min tracking performance", stats.min_tracking_performance, "-"),
                ]
                worst["pos"], worst["rot"] = max(worst["pos"], pos), max(worst["rot"], rot)
                worst["wrong"] = min(worst["wrong"], wrong)
                worst["track"] = min(worst["track"], stats.min_tracking_performance)
    rows += [
        ("ours: runs ended by the application's duration", float(ok), f"of {runs}"),
        ("ours: DH position error, worst run", worst["pos"] * 1e3, "mm"),
        ("ours: DH rotation error, worst run", math.degrees(worst["rot"]), "deg"),
        ("ours: wrong DH (d3, d5 +10 %) position error, least over all poses", worst["wrong"] * 1e3, "mm"),
        ("ours: min tracking performance, worst run", worst["track"], "-"),
    ]
    from lbrcli.fri.testing.kuka_sdk import kuka_app

    exe, why = kuka_app("LBRCartesianOverlay")
    if exe is None:
        print(f"KUKA's LBRCartesianOverlay skipped: {why}")
        rows.append(("KUKA LBRCartesianOverlay: skipped (no build)", 1.0, "bool"))
        return rows
    for period in (2,) if quick else (1, 2, 5):
        for amp in (30.0,) if quick else (10.0, 30.0, 60.0):
            stats, mons, cmds = kuka_overlay(exe, period, amp, 2.0 if quick else 5.0)
            pos, rot, wrong, n, peak = judge(mons, cmds, dh_fk, steady=True)
            pos_all = judge(mons, cmds, dh_fk, steady=False)[0]
            active = [m for m in mons if m.connectionInfo.sessionState == 4]
            # the source's filtered sine on x (one step per command answered in COMMANDING_ACTIVE): its peak
            off, phi, formula = 0.0, 0.0, 0.0
            for _ in active:
                off = off * 0.99 + amp * math.sin(phi) * 0.01
                phi = (phi + 2 * math.pi * 0.15 * period * 1e-3) % (2 * math.pi)
                formula = max(formula, abs(off))
            tag = f"KUKA {period} ms A {amp:g} mm"
            rows += [
                (
                    f"{tag}: session ended on IDLE by duration",
                    float(stats.end_reason == "duration" and stats.states_seen[-1] == 0),
                    "bool",
                ),
                (f"{tag}: measured peak x offset (on time) / amplitude", peak / amp, "-"),
                (f"{tag}: measured peak x offset (on time) / its source's filtered peak", peak / formula, "-"),
                (f"{tag}: commands executed on time (tracking 1)", n / max(1, len(active)), "share"),
                (f"{tag}: DH position error max (on time)", pos * 1e3, "mm"),
                (f"{tag}: DH rotation error max (on time)", math.degrees(rot), "deg"),
                (f"{tag}: DH position error max (all, clipped included)", pos_all * 1e3, "mm"),
                (f"{tag}: poses refused by the controller", float(bool(stats.command_problem)), "bool"),
            ]
    return rows


if __name__ == "__main__":
    for k, v, u in run(quick="--quick" in sys.argv):
        print(f"{k:<60} {v:>12.4g} {u}")
