"""The CSV player (``lbr execute``) against the scripted controller: loss, bursts, duplicates, reordering, delay,
lost replies, malformed and wrong-but-decodable messages, foreign senders, robot-side stops, state and period changes,
lying clocks, a pushed robot, signals, a full disk and bad files."""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from lbrcli.fri import ClientApplication, EndReason, TrajectoryPlayer
from lbrcli.fri.testing import CA, CW, IDLE, MR, Cycle, active, preamble
from lbrcli.fri.testing.campaign import Case
from trajectories.limits import default_limits
from trajectories.start_poses import THESIS_START

from .faults import PREAMBLE, _flip, _mutate

LIM = default_limits()
Q0 = np.array(THESIS_START)  # [rad]
DIRECTION = np.array([1, 0.5, -0.5, 1, 0.3, -1, 1])


def ramp(n: int = 700, speed: float = 0.73, ramp_s: float = 0.4, dt: float = 1e-3) -> np.ndarray:
    """From rest to ``speed`` × the velocity limit on every joint, smoothly, and on at that speed [rad]."""
    t = np.arange(n) * dt
    w = 2 * np.pi / ramp_s
    s = np.where(t < ramp_s, t**2 / (2 * ramp_s) + (np.cos(w * t) - 1) / (w**2 * ramp_s), ramp_s / 2 + (t - ramp_s))
    return Q0 + s[:, None] * speed * LIM.velocity


def swing(n: int = 800, amp: float = 0.3, dt: float = 1e-3) -> np.ndarray:
    """A rest-to-rest minimum-jerk move of ``amp`` [rad] (scaled per joint) over n rows."""
    s = np.linspace(0.0, 1.0, n)
    p = 10 * s**3 - 15 * s**4 + 6 * s**5
    return Q0 + amp * p[:, None] * DIRECTION


def _interrupt(at: int, reason: EndReason) -> Callable[[int, ClientApplication], None]:
    def f(i: int, app: ClientApplication) -> None:
        if i == at:
            app.interrupt(reason)

    return f


FIN = (EndReason.FINISHED,)
STOP = (EndReason.FINISHED, EndReason.SUPERVISION, EndReason.GUARD)  # a fault at speed may end it braking


class _Cases:
    """The cases collected so far and how one is added: the CSV player over ``rows`` (the fast ramp ``R`` unless
    told), the scripted controller playing ``script``."""

    def __init__(self) -> None:
        self.R = ramp()  # fast, never at rest at its end
        self.S = swing()  # rest to rest
        self.out: list[Case] = []

    def full(self, rows, at=None, **kw) -> list[Cycle]:
        """A whole session for ``rows``: the preamble, then enough COMMANDING_ACTIVE cycles (``at``: see ``active``)."""
        return preamble() + active(len(rows) + 300, at, **kw)

    def add(
        self,
        name,
        category,
        script,
        rows=None,
        expect=FIN,
        period_s=1e-3,
        move_to_start=False,
        on_cycle=None,
        q_start=None,
        **kw,
    ) -> None:
        rows = np.asarray(self.R if rows is None else rows, dtype=float)

        def client(rows=rows, period_s=period_s, move_to_start=move_to_start):
            return TrajectoryPlayer(rows, LIM, period_s=period_s, move_to_start=move_to_start)

        hook = (lambda i, run, f=on_cycle: f(i, run.app)) if on_cycle is not None else None
        start = tuple(float(x) for x in (q_start if q_start is not None else Q0))
        case = Case(
            name,
            category,
            script,
            client,
            expect,
            surface="execute",
            period_s=period_s,
            on_cycle=hook,
            q_start=start,
            **kw,
        )
        self.out.append(case)


def _loss_cases(c: _Cases) -> None:
    """Lost monitoring messages, single and in bursts (the controller bridges by extrapolation; the client rejoins
    in step)."""
    add, full, R, S = c.add, c.full, c.R, c.S
    for lost in (1, 2, 5, 10, 30):
        add(f"loss {lost} at speed", "loss", full(R, {500: Cycle(state=CA, seq_jump=lost)}), R, STOP)
    for lost in (1, 3):
        add(f"loss {lost} accelerating", "loss", full(S, {150: Cycle(state=CA, seq_jump=lost)}), S, FIN)
    add("loss during the move to start", "loss", preamble() + active(len(S) + 2000, {20: Cycle(state=CA, seq_jump=3)}), S, FIN,
        move_to_start=True, q_start=Q0 + 0.05)  # fmt: skip
    add("loss 1 at the last row", "loss", full(S, {len(S) - 2: Cycle(state=CA, seq_jump=1)}), S, FIN)
    # bursts of loss
    add("burst: 3 × loss 3", "bursts", full(R, {400: Cycle(state=CA, seq_jump=3), 402: Cycle(state=CA, seq_jump=3),
                                             404: Cycle(state=CA, seq_jump=3)}), R, STOP)  # fmt: skip
    add("burst: every other lost", "bursts", full(S, {k: Cycle(state=CA, seq_jump=1) for k in range(200, 240, 2)}),
        S, STOP)  # fmt: skip
    add("burst: 100 lost at once", "bursts", full(R, {450: Cycle(state=CA, seq_jump=100)}), R, STOP)


def _order_cases(c: _Cases) -> None:
    """Duplicated, reordered and delayed messages, and replies the controller never sees."""
    add, full, R, S = c.add, c.full, c.R, c.S
    # duplicates and reordering (stale: ignored)
    add(
        "duplicate at speed", "duplicates", full(R, {500: [Cycle(state=CA), Cycle(state=CA, repeat_seq=True)]}), R, STOP
    )
    add("5 duplicates", "duplicates", full(S, {300: [Cycle(state=CA)] + [Cycle(state=CA, repeat_seq=True)] * 5}), S)
    add("reordered by 1", "reordering", full(R, {500: [Cycle(state=CA), Cycle(state=CA, stale_by=1)]}), R, STOP)
    add("reordered by 3", "reordering", full(S, {300: [Cycle(state=CA), Cycle(state=CA, stale_by=3)]}), S)
    add("old message after a gap", "reordering", full(S, {300: [Cycle(state=CA, seq_jump=2),
                                                                Cycle(state=CA, stale_by=2)]}), S)  # fmt: skip
    # delay (the controller pauses; lock-step)
    add("controller pauses 50 ms", "delay", full(S, {300: Cycle(state=CA, pause_s=0.05)}), S)
    add("controller pauses in COMMANDING_WAIT", "delay", preamble()[:-1] + [Cycle(state=CW, pause_s=0.2)]
        + active(len(S) + 300), S)  # fmt: skip
    # replies lost (the controller never sees them)
    for n in (1, 2):
        add(
            f"{n} replies lost at speed",
            "replies lost",
            full(R, {500: [Cycle(state=CA, drop_reply=True)] * n}),
            R,
            STOP,
        )
    add("replies lost: the controller falls back", "replies lost",
        full(R, {500: [Cycle(state=CA, drop_reply=True)] * 10}), R, (EndReason.QUALITY_POOR,),
        controller=dict(max_bridge=2, tolerate_unanswered=1000, reply_timeout=0.3))  # fmt: skip


def _malformed_cases(c: _Cases) -> None:
    """Malformed datagrams, wrong-but-decodable messages and foreign senders (never answered)."""
    add, full, R, S = c.add, c.full, c.R, c.S
    # malformed datagrams and wrong-but-decodable messages (never answered)
    add("garbage datagram", "malformed", full(R, {500: [Cycle(raw=b"\x00\x01garbage"), Cycle(state=CA)]}), R, STOP)
    add("empty datagram", "malformed", full(S, {300: [Cycle(raw=b""), Cycle(state=CA)]}), S)
    add(
        "6 ipo values",
        "wrong but decodable",
        full(R, {500: _mutate(lambda m: m.ipoData.jointPosition.value.__delitem__(slice(6, 7)))}),
        R,
        STOP,
    )
    add(
        "no ipo values",
        "wrong but decodable",
        full(S, {300: _mutate(lambda m: m.ipoData.ClearField("jointPosition"))}),
        S,
        STOP,
    )
    add(
        "ipo 1e6",
        "wrong but decodable",
        full(R, {500: _mutate(lambda m: m.ipoData.jointPosition.value.__setitem__(3, 1e6))}),
        R,
        STOP,
    )
    add(
        "measured NaN",
        "wrong but decodable",
        full(R, {500: _mutate(lambda m: m.monitorData.measuredJointPosition.value.__setitem__(0, math.nan))}),
        R,
        STOP,
    )
    add(
        "measured inf",
        "wrong but decodable",
        full(S, {300: _mutate(lambda m: m.monitorData.measuredJointPosition.value.__setitem__(2, math.inf))}),
        S,
        STOP,
    )
    add(
        "no connection info",
        "wrong but decodable",
        full(R, {500: _mutate(lambda m: m.ClearField("connectionInfo"))}),
        R,
        STOP,
    )
    add(
        "6 measured values",
        "wrong but decodable",
        full(S, {300: _mutate(lambda m: m.monitorData.measuredJointPosition.value.__delitem__(slice(0, 1)))}),
        S,
        STOP,
    )
    for bit in (63, 62, 55, 52, 40):
        add(f"measured A1 bit {bit} flipped", "wrong but decodable", full(R, {500: _mutate(_flip(bit))}), R, STOP)
    add("6 values in COMMANDING_WAIT", "wrong but decodable",
        preamble()[:-1] + [Cycle(state=CW, mutate=lambda m: m.ipoData.jointPosition.value.__delitem__(slice(6, 7)))]
        + active(len(S) + 300), S)  # fmt: skip
    add("ipo 10 rad in COMMANDING_WAIT", "wrong but decodable",
        preamble()[:-1] + [Cycle(state=CW, mutate=lambda m: m.ipoData.jointPosition.value.__setitem__(0, 10.0))]
        + active(len(S) + 300), S)  # fmt: skip
    # foreign senders (ignored)
    add("foreign sender once", "foreign", full(R, {500: [Cycle(state=CA, foreign=True), Cycle(state=CA)]}), R, STOP)
    add(
        "foreign sender 10 times",
        "foreign",
        full(S, {300: [Cycle(state=CA, foreign=True)] * 10 + [Cycle(state=CA)]}),
        S,
    )


def _session_cases(c: _Cases) -> None:
    """Robot-side ends, period and clock faults, a robot that does not follow."""
    add, full, R, S = c.add, c.full, c.R, c.S
    # robot-side ends at speed (the controller stops the robot itself: the client stops answering)
    side = {
        "safety stop": dict(safety=2),
        "drives off": dict(drive=1),
        "quality POOR": dict(quality=0),
        "back to MONITORING_READY": dict(state=MR),
        "back to COMMANDING_WAIT": dict(state=CW),
        "IDLE": dict(state=IDLE),
    }
    reasons = {"safety stop": EndReason.SAFETY_STOP, "drives off": EndReason.DRIVES_OFF,
               "quality POOR": EndReason.QUALITY_POOR, "IDLE": EndReason.IDLE}  # fmt: skip
    for name, kw in side.items():
        add(name + " at speed", "robot side", full(R, {500: Cycle(**{"state": CA, **kw})}), R,
            (reasons.get(name, EndReason.LEFT_COMMANDING),))  # fmt: skip
    add("quality FAIR at speed", "quality", full(R, {500: Cycle(state=CA, quality=1)}), R, STOP)
    add("safety stop in COMMANDING_WAIT", "robot side", preamble()[:-1] + [Cycle(state=CW, safety=1)] + active(100), S,
        (EndReason.SAFETY_STOP,))  # fmt: skip
    # period and clock
    add(
        "period change at speed",
        "period",
        full(R, {500: Cycle(state=CA, send_period=2)}),
        R,
        (EndReason.PERIOD_CHANGED,),
    )
    add("receive multiplier change", "period", full(S, {300: Cycle(state=CA, receive_multiplier=2)}), S,
        (EndReason.PERIOD_CHANGED,))  # fmt: skip
    add("5 ms claimed, 2 ms real", "clock", preamble(send_period=5, clock_ms=2) + active(700, send_period=5, clock_ms=2),
        swing(400, amp=0.3), (EndReason.SUPERVISION,), period_s=5e-3)  # fmt: skip
    add("clock jumps back", "clock", full(S, {300: Cycle(state=CA, clock_ms=-100)}), S, (EndReason.SUPERVISION,))
    add("5 ms session", "period", preamble(send_period=5) + active(700, send_period=5), swing(400), FIN, period_s=5e-3)
    add("2 ms, receive multiplier 2", "period", preamble(send_period=2, receive_multiplier=2)
        + active(2 * 400 + 200, send_period=2, receive_multiplier=2), swing(400), FIN, period_s=4e-3)  # fmt: skip
    # the robot does not follow
    add("pushed 0.3 rad at speed", "pushed", full(R, {k: Cycle(state=CA, push=0.3) for k in range(500, 520)}), R,
        (EndReason.SUPERVISION,))  # fmt: skip
    add("pushed 0.1 rad at rest", "pushed", full(S, {k: Cycle(state=CA, push=0.1) for k in range(20, 60)}), S,
        (EndReason.SUPERVISION,))  # fmt: skip
    add("pushed away before activation", "pushed", preamble()[:-2] + [Cycle(state=CW, push=0.01)] * 2
        + active(len(S) + 300), S, (EndReason.CLIENT_REFUSED, EndReason.GUARD))  # fmt: skip


def _stop_cases(c: _Cases) -> None:
    """Signals and a full disk at several points of the move."""
    add, full, R, S = c.add, c.full, c.R, c.S
    # signals
    for at, rows, label in ((PREAMBLE + 500, R, "at speed"), (PREAMBLE + 150, S, "accelerating"),
                            (PREAMBLE + 5, S, "just activated"), (5, S, "before commanding")):  # fmt: skip
        for reason in (EndReason.SIGINT, EndReason.SIGTERM):
            add(f"{reason.name} {label}", "signals", full(rows), rows, (reason,), on_cycle=_interrupt(at, reason))
    # a full disk
    for at, rows, label in ((200, R, "accelerating"), (600, R, "at speed"), (3, S, "at the start")):
        add(
            f"disk full {label}",
            "full disk",
            full(rows),
            rows,
            (EndReason.OBSERVER_FAILED,),
            full_disk_at=PREAMBLE + at,
        )


def _bad_file_cases(c: _Cases) -> None:
    """Bad files at the library level: what the CLI's checks would refuse before, the guard refuses here."""
    add, full, R, S = c.add, c.full, c.R, c.S
    # bad files (the library level: what the CLI's checks would refuse before, the guard refuses here)
    jump = R.copy()
    jump[450:, 3] += 0.05
    nan = S.copy()
    nan[300, 2] = math.nan
    osc = np.repeat(Q0[None], 200, axis=0)
    osc[50:, 0] += 0.95 * LIM.velocity[0] * 1e-3 * (np.arange(150) % 2)
    u = np.linspace(0.0, 1.0, 800)
    beyond = np.repeat(Q0[None], 800, axis=0)
    beyond[:, 0] = LIM.position[0] - 0.1 + 0.15 * (10 * u**3 - 15 * u**4 + 6 * u**5)  # ends 0.05 rad past A1's limit
    ends_moving = R[:600]
    far = S + 0.1
    add("file jumps at speed", "bad files", full(jump), jump, (EndReason.GUARD,))
    add("file has NaN", "bad files", full(nan), nan, (EndReason.GUARD,))
    add("file oscillates", "bad files", full(osc), osc, (EndReason.GUARD,))
    add("file crosses a position limit", "bad files", full(beyond), beyond, (EndReason.GUARD, EndReason.CLIENT_REFUSED),
        q_start=beyond[0])  # fmt: skip
    add("file ends moving", "bad files", full(ends_moving), ends_moving, FIN)
    add("file starts far away", "bad files", full(far), far, (EndReason.CLIENT_REFUSED,))


def execute_cases() -> list[Case]:
    """The CSV player (``lbr execute``) under every fault (≥ 70 cases)."""
    c = _Cases()
    for group in (_loss_cases, _order_cases, _malformed_cases, _session_cases, _stop_cases, _bad_file_cases):
        group(c)
    return c.out
