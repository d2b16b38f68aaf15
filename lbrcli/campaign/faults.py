"""The controller's faults every surface meets: each a script of the scripted controller with the fault at a given
COMMANDING_ACTIVE cycle (mid-motion), the session ends it may bring, and the hook that plays it (a signal, a disk
that fills). ``normal`` stands for the surface's own ends (finished, a dead-man, a timeout)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from lbrcli.fri import EndReason
from lbrcli.fri.testing import CA, Cycle, active, preamble

PREAMBLE = len(preamble())  # script cycles before COMMANDING_ACTIVE
NORMAL = "normal"  # placeholder in ``ends``: the surface's own ends
STOP = (EndReason.SUPERVISION, EndReason.GUARD)  # a fault the client side may answer with a braking stop


@dataclass(frozen=True)
class Fault:
    """A controller fault at COMMANDING_ACTIVE cycle ``at`` of an ``n``-cycle session."""

    name: str
    category: str
    script: Callable[[int, int], list[Cycle]]  # (n, at) -> the whole script
    ends: tuple[Any, ...]  # EndReasons, and NORMAL for the surface's own
    signal: EndReason | None = None  # an interrupt at that cycle (SIGINT, SIGTERM)
    full_disk: bool = False  # the log's disk fills at that cycle


def _at(cycle: Cycle | list[Cycle], **kw: Any) -> Callable[[int, int], list[Cycle]]:
    return lambda n, at: preamble(**kw) + active(n, {at: cycle}, **kw)


def _mutate(fn: Callable[[Any], None]) -> Cycle:
    return Cycle(state=CA, mutate=fn)


def _flip(bit: int) -> Callable[[Any], None]:
    """Flip one bit of the measured position of A1 (a wrong value that still decodes)."""

    def f(m: Any) -> None:
        v = np.array([m.monitorData.measuredJointPosition.value[0]], dtype=np.float64)
        v.view(np.uint64)[0] ^= np.uint64(1) << np.uint64(bit)
        m.monitorData.measuredJointPosition.value[0] = float(v[0])

    return f


def _stamps(offset_ms: float) -> Callable[[Any], None]:
    """Shift the message's timestamp by ``offset_ms`` [ms] (negative: back in time)."""

    def f(m: Any) -> None:
        ts = m.monitorData.timestamp
        ns = ts.sec * 1_000_000_000 + ts.nanosec + int(offset_ms * 1e6)
        ts.sec, ts.nanosec = ns // 1_000_000_000, ns % 1_000_000_000

    return f


def _frozen_from(n: int, at: int) -> list[Cycle]:
    """The controller's timestamp stands still from cycle ``at`` on (its clock froze; it keeps sending)."""
    frozen: dict[str, Any] = {}

    def freeze(m: Any) -> None:
        ts = m.monitorData.timestamp
        if not frozen:
            frozen["t"] = (ts.sec, ts.nanosec)
        ts.sec, ts.nanosec = frozen["t"]

    return preamble() + active(n, {k: _mutate(freeze) for k in range(at, n)})


def _network_faults() -> list[Fault]:
    """Messages lost (single, in bursts), duplicated, reordered or late; replies lost on the way back."""
    N = (NORMAL,)
    return [
        Fault("loss 1", "loss", _at(Cycle(state=CA, seq_jump=1)), N + STOP),
        Fault("loss 5", "loss", _at(Cycle(state=CA, seq_jump=5)), N + STOP),
        Fault("loss 30", "loss", _at(Cycle(state=CA, seq_jump=30)), N + STOP),
        Fault(
            "burst: every other lost",
            "bursts",
            lambda n, at: preamble() + active(n, {k: Cycle(state=CA, seq_jump=1) for k in range(at, at + 40, 2)}),
            N + STOP,
        ),  # fmt: skip
        Fault(
            "burst: 3 × loss 7",
            "bursts",
            lambda n, at: (
                preamble()
                + active(
                    n,
                    {
                        at: Cycle(state=CA, seq_jump=7),
                        at + 2: Cycle(state=CA, seq_jump=7),
                        at + 4: Cycle(state=CA, seq_jump=7),
                    },
                )
            ),
            N + STOP,
        ),  # fmt: skip
        Fault("100 lost at once", "bursts", _at(Cycle(state=CA, seq_jump=100)), N + STOP),
        Fault("duplicate", "duplicates", _at([Cycle(state=CA), Cycle(state=CA, repeat_seq=True)]), N + STOP),
        Fault("reordered by 3", "reordering", _at([Cycle(state=CA), Cycle(state=CA, stale_by=3)]), N + STOP),
        Fault("controller pauses 50 ms", "delay", _at(Cycle(state=CA, pause_s=0.05)), N + STOP),
        Fault("2 replies lost", "replies lost", _at([Cycle(state=CA, drop_reply=True)] * 2), N + STOP),
    ]


def _message_faults() -> list[Fault]:
    """Datagrams that must never be answered: malformed, lying (wrong but decodable), from a foreign sender."""
    N = (NORMAL,)
    return [
        Fault("garbage datagram", "malformed", _at([Cycle(raw=b"\x00\x01garbage"), Cycle(state=CA)]), N + STOP),
        Fault(
            "measured NaN",
            "lying messages",
            _at(_mutate(lambda m: m.monitorData.measuredJointPosition.value.__setitem__(0, math.nan))),
            N + STOP,
        ),
        Fault(
            "6 ipo values",
            "lying messages",
            _at(_mutate(lambda m: m.ipoData.jointPosition.value.__delitem__(slice(6, 7)))),
            N + STOP,
        ),
        Fault("measured A1 bit 55 flipped", "lying messages", _at(_mutate(_flip(55))), N + STOP),
        Fault(
            "foreign sender 10 times",
            "foreign",
            _at([Cycle(state=CA, foreign=True)] * 10 + [Cycle(state=CA)]),
            N + STOP,
        ),
    ]


def _session_faults() -> list[Fault]:
    """The robot side ending the session, period and clock faults, a pushed robot, signals and a full disk."""
    return [
        Fault("safety stop", "robot side", _at(Cycle(state=CA, safety=2)), (EndReason.SAFETY_STOP,)),
        Fault("drives off", "robot side", _at(Cycle(state=CA, drive=1)), (EndReason.DRIVES_OFF,)),
        Fault("quality POOR", "robot side", _at(Cycle(state=CA, quality=0)), (EndReason.QUALITY_POOR,)),
        Fault("back to MONITORING_READY", "robot side", _at(Cycle(state=2)), (EndReason.LEFT_COMMANDING,)),
        Fault("IDLE", "robot side", _at(Cycle(state=0)), (EndReason.IDLE,)),
        Fault("period change", "period", _at(Cycle(state=CA, send_period=2)), (EndReason.PERIOD_CHANGED,)),
        Fault("timestamps frozen", "clock", _frozen_from, (EndReason.SUPERVISION,)),
        Fault("timestamp back 100 ms", "clock", _at(_mutate(_stamps(-100.0))), (EndReason.SUPERVISION,)),
        Fault(
            "timestamps at 0.4 of the period",
            "clock",
            lambda n, at: preamble(clock_ms=0.4) + active(n, clock_ms=0.4),
            (EndReason.SUPERVISION,),
        ),
        Fault(
            "pushed 0.3 rad",
            "pushed",
            lambda n, at: preamble() + active(n, {k: Cycle(state=CA, push=0.3) for k in range(at, at + 20)}),
            (EndReason.SUPERVISION,),
        ),  # fmt: skip
        Fault("SIGINT", "signals", lambda n, at: preamble() + active(n), (EndReason.SIGINT,), signal=EndReason.SIGINT),
        Fault(
            "SIGTERM", "signals", lambda n, at: preamble() + active(n), (EndReason.SIGTERM,), signal=EndReason.SIGTERM
        ),
        Fault(
            "disk full", "full disk", lambda n, at: preamble() + active(n), (EndReason.OBSERVER_FAILED,), full_disk=True
        ),
    ]


def controller_faults() -> list[Fault]:
    """The faults of a controller, a network and a lab (≈ 30)."""
    return _network_faults() + _message_faults() + _session_faults()
