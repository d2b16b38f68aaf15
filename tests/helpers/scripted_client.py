"""A small scripted FRI client for the simulator tests: answers per state, records what it received.

The client mirrors the ipo position in COMMANDING_WAIT; in COMMANDING_ACTIVE it sends ``policy(k, q_start)``
(a joint vector [rad]) where k counts the COMMANDING_ACTIVE messages received (0, 1, ...; the time is
k·period) and q_start is the ipo position of the first one — or no reply at all when the policy returns None (a reply without joint positions when it returns ()).
"""

from __future__ import annotations

import socket
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from lbrcli.fri.codec import FriCodec
from lbrcli.fri.constants import COMMAND_MESSAGE_ID, SessionState
from trajectories.errors import FriDecodeError

Policy = Callable[[int, np.ndarray], "np.ndarray | None"]


@dataclass
class Received:
    """One monitoring message as the client saw it."""

    t: float  # [s] arrival (perf_counter)
    seq: int
    reflected: int
    state: int
    quality: int
    send_period: int
    multiplier: int
    safety: int
    drives: tuple[int, ...]
    msr_q: np.ndarray
    ipo_q: np.ndarray
    msr_tau: np.ndarray
    tracking: float
    stamp: tuple[int, int]
    io: dict[str, float]
    mode: int
    overlay: int


@dataclass
class ClientRun:
    received: list[Received] = field(default_factory=list)
    sent_seq: list[int] = field(default_factory=list)  # our sequence counters, in order
    undecodable: int = 0

    @property
    def states(self) -> list[int]:
        out: list[int] = []
        for r in self.received:
            if not out or out[-1] != r.state:
                out.append(r.state)
        return out

    def where(self, state: int) -> list[Received]:
        return [r for r in self.received if r.state == state]


class ScriptedClient:
    """Binds 127.0.0.1:0; ``run`` answers the simulator until IDLE or the timeout."""

    def __init__(self, version: str = "1.15", host: str = "127.0.0.1") -> None:
        self.codec = FriCodec(version)
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind((host, 0))
        self.port = self.sock.getsockname()[1]

    def close(self) -> None:
        self.sock.close()

    def run(
        self,
        policy: Policy | None = None,
        *,
        multiplier: int = 1,
        timeout: float = 10.0,
        answer_monitoring: Callable[[Received], bool] | None = None,
    ) -> ClientRun:
        codec, sock = self.codec, self.sock
        mon, cmd = codec.new_monitoring(), codec.new_command()
        cmd.header.messageIdentifier = COMMAND_MESSAGE_ID
        out = ClientRun()
        seq = 0
        count = 0
        k_active = 0
        q_active = None
        end = time.perf_counter() + timeout
        sock.settimeout(min(timeout, 20.0))  # the first message: the simulator process may still be starting
        while time.perf_counter() < end:
            try:
                data, addr = sock.recvfrom(2048)
            except socket.timeout:
                break
            sock.settimeout(1.0)
            now = time.perf_counter()
            try:
                codec.decode_monitoring(data, into=mon)
            except FriDecodeError:
                out.undecodable += 1
                continue
            md = mon.monitorData
            rec = Received(
                t=now,
                seq=mon.header.sequenceCounter,
                reflected=mon.header.reflectedSequenceCounter,
                state=mon.connectionInfo.sessionState,
                quality=mon.connectionInfo.quality,
                send_period=mon.connectionInfo.sendPeriod,
                multiplier=mon.connectionInfo.receiveMultiplier,
                safety=mon.robotInfo.safetyState,
                drives=tuple(mon.robotInfo.driveState),
                msr_q=np.array(md.measuredJointPosition.value),
                ipo_q=np.array(mon.ipoData.jointPosition.value),
                msr_tau=np.array(md.measuredTorque.value),
                tracking=mon.ipoData.trackingPerformance,
                stamp=(md.timestamp.sec, md.timestamp.nanosec),
                io={io.name: io.analogValue for io in md.readIORequest},
                mode=mon.ipoData.clientCommandMode,
                overlay=mon.ipoData.overlayType,
            )
            out.received.append(rec)
            if rec.state == SessionState.IDLE:
                break
            if rec.state == SessionState.COMMANDING_ACTIVE:
                if q_active is None:
                    q_active = rec.ipo_q.copy()
                else:
                    k_active += 1
            count += 1
            if count % multiplier:
                continue
            if answer_monitoring is not None and not answer_monitoring(rec):
                continue
            cmd.commandData.Clear()
            if rec.state == SessionState.COMMANDING_WAIT:
                cmd.commandData.jointPosition.value.extend(mon.ipoData.jointPosition.value)  # mirror
            elif rec.state == SessionState.COMMANDING_ACTIVE:
                q = q_active if policy is None else policy(k_active, q_active)
                if q is None:
                    continue
                cmd.commandData.jointPosition.value.extend(np.asarray(q, dtype=float).tolist())  # () : header only
            cmd.header.sequenceCounter = seq
            cmd.header.reflectedSequenceCounter = rec.seq
            sock.sendto(codec.encode(cmd), addr)
            out.sent_seq.append(seq)
            seq += 1
        return out
