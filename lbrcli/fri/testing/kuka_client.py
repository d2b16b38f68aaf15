"""A raw FRI client that answers like KUKA's C++ example clients (socket + lbrcli.fri.codec only).

Like KUKA's ``LBRClient``: in COMMANDING_WAIT it mirrors the ipo position (and, in torque/wrench mode, sends a
zero torque/wrench: KUKA's consistency check); in COMMANDING_ACTIVE it sends ``ipo + offset`` with an overlay
from ``overlay(n, h)`` (n: COMMANDING_ACTIVE messages answered so far, h: sample time [s]) returning
(joint offset (7,) [rad], torque (7,) [Nm] or None, wrench (6,) or None); ``io(message) -> [(name, type,
value), ...]`` writes IO in every state. It records every monitoring message and every command it sent.
Used by tests/lbrcli/fri/sim/test_simulator_kuka.py and benchmarks/bench_fri_sim.py.
"""

from __future__ import annotations

import math
import socket
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from lbrcli.fri.codec import FriCodec
from lbrcli.fri.constants import COMMAND_MESSAGE_ID, SessionState
from trajectories.errors import FriDecodeError

CW, CA = int(SessionState.COMMANDING_WAIT), int(SessionState.COMMANDING_ACTIVE)


@dataclass
class Sent:
    seq: int  # our sequence counter
    reflected: int  # the monitoring message answered
    q: np.ndarray | None  # [rad]
    torque: np.ndarray | None
    wrench: np.ndarray | None
    io: dict = field(default_factory=dict)


@dataclass
class Run:
    messages: list = field(default_factory=list)  # decoded monitoring messages (copies)
    sent: list = field(default_factory=list)  # Sent

    def active(self) -> list:
        return [m for m in self.messages if m.connectionInfo.sessionState == CA]

    def executed_pairs(self, steady: int = 0):
        """(command, message) pairs where the message proves the controller had the command before filling it:
        it reflects the command's counter and is the next message after the one the command answered. With
        ``steady`` > 0 only pairs whose ``steady`` preceding messages were such pairs too (no late reply just
        before: after one the controller's interpolator catches up within its limits)."""
        by_seq = {s.seq: s for s in self.sent}
        timely = set()
        for m in self.messages:
            s = by_seq.get(m.header.reflectedSequenceCounter)
            n = m.header.sequenceCounter
            if s is not None and n == s.reflected + 1:
                timely.add(n)
                if all(n - i in timely for i in range(1, steady + 1)):
                    yield s, m


def joint_sine(joint: int = 3, amplitude: float = 0.04, freq_hz: float = 1.0, filter_coeff: float = 0.99):
    """KUKA's LBRJointSineOverlay: offset ← c·offset + (1 − c)·A·sin(φ), φ advancing 2π·f·h per answer
    (its defaults: A4, 0.04 rad, 0.25 Hz, c = 0.99 — the filter softens the start within the joint limits)."""
    state = [0.0]

    def overlay(n: int, h: float):
        state[0] = filter_coeff * state[0] + (1.0 - filter_coeff) * amplitude * math.sin(2 * math.pi * freq_hz * h * n)
        off = np.zeros(7)
        off[joint] = state[0]
        return off, None, None

    return overlay


class KukaLikeClient:
    """Binds 127.0.0.1:0; ``run`` answers the simulator until IDLE or the timeout."""

    def __init__(self, version: str = "1.15") -> None:
        self.codec = FriCodec(version)
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.port = self.sock.getsockname()[1]

    def close(self) -> None:
        self.sock.close()

    def run(
        self,
        overlay: Callable | None = None,
        mode: str = "position",
        io: Callable | None = None,
        timeout: float = 10.0,
        record: bool = True,
    ) -> Run:
        """Answer until IDLE, ``timeout`` [s], or 1 s without a message; ``record=False`` keeps nothing (an echo
        client for timing measurements)."""
        codec, sock = self.codec, self.sock
        mon, cmd = codec.new_monitoring(), codec.new_command()
        cmd.header.messageIdentifier = COMMAND_MESSAGE_ID
        out = Run()
        seq = 0
        n_active = 0
        end = time.perf_counter() + timeout
        sock.settimeout(min(timeout, 20.0))  # the simulator process may still be starting
        while time.perf_counter() < end:
            try:
                data, addr = sock.recvfrom(2048)
            except socket.timeout:
                break
            sock.settimeout(1.0)
            try:
                codec.decode_monitoring(data, into=mon)
            except FriDecodeError:
                continue
            if record:
                copy = codec.new_monitoring()
                copy.CopyFrom(mon)
                out.messages.append(copy)
            state = mon.connectionInfo.sessionState
            if state == 0:
                break
            h = mon.connectionInfo.sendPeriod * 1e-3
            cmd.commandData.Clear()
            cd = cmd.commandData
            q = tau = wrench = None
            if state in (CW, CA):
                q = np.array(mon.ipoData.jointPosition.value)
                tau, wrench = np.zeros(7), np.zeros(6)
                if state == CA and overlay is not None:
                    off, t, w = overlay(n_active, h)
                    q = q + off
                    tau = t if t is not None else tau
                    wrench = w if w is not None else wrench
                    n_active += 1
                cd.jointPosition.value.extend(q.tolist())
                if mode == "torque":
                    cd.jointTorque.value.extend(tau.tolist())
                elif mode == "wrench":
                    cd.cartesianWrenchFeedForward.element.extend(wrench.tolist())
            writes = {}
            if io is not None:
                for name, kind, value in io(mon):
                    w = cd.writeIORequest.add()
                    w.name, w.type, w.direction = name, kind, 1
                    if kind == 2:
                        w.analogValue = float(value)
                    else:
                        w.digitalValue = int(value)
                    writes[name] = value
            cmd.header.sequenceCounter = seq
            cmd.header.reflectedSequenceCounter = mon.header.sequenceCounter
            sock.sendto(codec.encode(cmd), addr)
            if record:
                out.sent.append(
                    Sent(
                        seq,
                        mon.header.sequenceCounter,
                        q,
                        tau if mode == "torque" else None,
                        wrench if mode == "wrench" else None,
                        writes,
                    )
                )
            seq += 1
        return out
