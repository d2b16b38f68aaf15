"""UDP transport of the FRI client: the bound socket, the peer filter and the reply address.

The client binds the port of the robot's FRI configuration (30200 by default), accepts datagrams only from the
controller's IP address (any source port: a simulator on the same machine cannot own the port too) and replies
to the port each datagram came from.

Waiting (default): the receive blocks in the kernel (one ``recvmsg`` with ``SO_RCVTIMEO``) until a datagram
arrives or the receive timeout passes, as KUKA's client blocks in ``select``: the process costs no CPU while it waits,
so on a busy PC the scheduler wakes it at once (a process that polls uses up its share and waits behind the others).
Either way, when more of the controller's datagrams already wait behind the one read (the client fell behind), the
newest is returned and the older ones are counted (``overtaken``): their periods are past, the controller bridged them
(``catch_up=False``: each in turn — for a test controller that sends unanswered datagrams in bursts, not once a period).
With a busy-wait window (``busy_wait_s``) and the controller's send period known
(``expect_period``), it sleeps only until the window before the next message is due and then polls the socket without
sleeping (sleep-then-spin): on a quiet PC the reply no longer waits for the scheduler to wake the process, at the cost
of the window's CPU per period. While it polls, ``warm`` (if set) is called every ``WARM_EVERY_S``: the application
re-runs the checks of its next reply on the last message, so that their code and data are in the CPU's caches when
the message arrives. See docs/explanations/fri-timing.md for the figures.
"""

from __future__ import annotations

import fcntl
import select
import socket
import struct
import time
from typing import Callable

from .constants import MAX_DATAGRAM
from trajectories.errors import SettingError

from .errors import FriError

RECV_TIMEOUT_S = 0.05  # [s] how often a blocked receive returns to look at clocks and interrupt flags
DEFAULT_BUSY_WAIT_S = 0.0  # [s] polled before a message is due: none by default (block in the kernel; see above)
WARM_EVERY_S = 5e-5  # [s] how often the busy-wait calls ``warm``
SIOCGSTAMPNS = 0x8907  # Linux: the kernel's receive time of the last datagram read from a socket
_TIMESPEC = struct.Struct("qq")
_TIMEVAL = struct.Struct("ll")
_DONTWAIT = socket.MSG_DONTWAIT
_RX_SIZE = MAX_DATAGRAM + 64
_SO_TIMESTAMPNS = getattr(socket, "SO_TIMESTAMPNS", 35)  # Linux; the control message's type has the same number
_ANC_SIZE = socket.CMSG_SPACE(_TIMESPEC.size)  # room for the receive time stamp


def resolve_ip(host: str) -> str:
    """The IPv4 address of ``host`` (an address or a name)."""
    try:
        return socket.getaddrinfo(host, None, socket.AF_INET, socket.SOCK_DGRAM)[0][4][0]
    except (socket.gaierror, IndexError, UnicodeError):
        raise SettingError("UdpTransport", "robot", f"cannot resolve {host!r} to an IPv4 address") from None


class UdpTransport:
    """A bound UDP socket that receives from one controller address and answers the last sender."""

    def __init__(
        self,
        robot_ip: str,
        port: int,
        bind_host: str = "",
        timeout_s: float = RECV_TIMEOUT_S,
        busy_wait_s: float = 0.0,
        catch_up: bool = True,
    ) -> None:
        self.robot_ip = resolve_ip(robot_ip)
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            sock.bind((bind_host, port))
        except OSError as exc:
            sock.close()
            raise FriError(f"cannot bind the FRI port {bind_host or '*'}:{port}: {exc.strerror}") from None
        # blocking, with the receive timeout in the kernel (SO_RCVTIMEO): one system call per datagram; the polls of
        # the busy-wait, drain and send pass MSG_DONTWAIT
        sock.setblocking(True)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVTIMEO, _TIMEVAL.pack(int(timeout_s), int(timeout_s % 1 * 1e6)))
        try:  # stamp every datagram on arrival (else the first ones read are stamped when read: see received_ns)
            sock.setsockopt(socket.SOL_SOCKET, _SO_TIMESTAMPNS, 1)
        except OSError:
            pass
        self.sock = sock
        self._rlist = (sock,)  # for select, built once
        self._waiting = select.poll()  # is a datagram waiting? (no system call that fails, no exception, per message)
        self._waiting.register(sock, select.POLLIN)
        self.port: int = sock.getsockname()[1]
        self.timeout_s = timeout_s
        self.busy_wait_s = max(0.0, busy_wait_s)  # [s]
        self.period_s: float | None = None  # [s] the controller's send period, once known (expect_period)
        self.peer: tuple[str, int] | None = None  # where replies go (the last accepted datagram's source)
        self.foreign = 0  # datagrams from other addresses (ignored)
        self._t_last = 0.0  # [s] perf_counter when the last datagram was taken
        self.polled = 0  # datagrams taken while busy-waiting (not woken by the scheduler)
        self.catch_up = catch_up  # take the newest of the controller's datagrams waiting (False: each in turn)
        self.overtaken = 0  # the controller's datagrams skipped because a newer one was already waiting
        self.warm: Callable[[], None] | None = None  # called every WARM_EVERY_S while busy-waiting
        self._stamp = bytearray(16)
        self._stamps = True  # the kernel gives receive times (SIOCGSTAMPNS); off after the first failure
        self._anc: list = []  # the last datagram's control messages (its receive time stamp)

    def expect_period(self, period_s: float | None) -> None:
        """The controller sends every ``period_s`` [s]: busy-wait the window before each message (if any)."""
        self.period_s = period_s if period_s and period_s > 0 else None

    def receive(self) -> bytes | None:
        """The next datagram from the controller, or None after the receive timeout."""
        busy = self.busy_wait_s if self.period_s is not None else 0.0
        if busy > 0.0:
            return self._receive_spinning(busy)
        recvmsg = self.sock.recvmsg
        while True:
            try:
                data, anc, _, addr = recvmsg(_RX_SIZE, _ANC_SIZE)  # blocks until a datagram or SO_RCVTIMEO
            except (BlockingIOError, InterruptedError):  # the time-out (EAGAIN)
                return None
            except ConnectionRefusedError:  # an ICMP error from an earlier reply: nothing to read
                continue
            if self._take(addr):
                self._anc = anc
                return self._newest(data)

    def _receive_spinning(self, busy: float) -> bytes | None:
        """Sleep until ``busy`` [s] before the next message is due, then poll until it arrives (or ``busy`` after)."""
        recvmsg = self.sock.recvmsg
        sock = self._rlist
        due = self._t_last + self.period_s  # type: ignore[operator]
        spin_until = due + busy
        t = time.perf_counter()
        if due - busy - t > self.timeout_s or t > spin_until:
            busy = 0.0  # long silent or late: plain wait
        elif due - busy > t:
            select.select(sock, (), (), due - busy - t)
        warm = self.warm if busy > 0.0 else None
        t_warm = 0.0
        while True:
            try:
                data, anc, _, addr = recvmsg(_RX_SIZE, _ANC_SIZE, _DONTWAIT)
            except (BlockingIOError, InterruptedError):
                if busy > 0.0:
                    t = time.perf_counter()
                    if t < spin_until:
                        if warm is not None and t > t_warm:
                            warm()
                            t_warm = t + WARM_EVERY_S
                        continue
                    busy = 0.0
                if not select.select(sock, (), (), self.timeout_s)[0]:
                    return None
                continue
            except ConnectionRefusedError:  # an ICMP error from an earlier reply: nothing to read
                continue
            if self._take(addr):
                self._anc = anc
                if busy > 0.0:
                    self.polled += 1
                return self._newest(data)

    def _newest(self, data: bytes) -> bytes:
        """``data``, or the newest of the controller's datagrams already waiting behind it: a client that fell
        behind (a stall) answers the message the controller sent last, not each older one too late (the controller
        bridged those periods; the application counts them as missed). One poll of the socket when none waits."""
        if not self.catch_up:
            return data
        recvmsg, waiting = self.sock.recvmsg, self._waiting.poll
        while waiting(0):
            try:
                newer, anc, _, addr = recvmsg(_RX_SIZE, _ANC_SIZE, _DONTWAIT)
            except (BlockingIOError, InterruptedError):
                return data
            except ConnectionRefusedError:
                continue
            if self._take(addr):
                data, self._anc = newer, anc
                self.overtaken += 1
        return data

    def _take(self, addr: tuple[str, int]) -> bool:
        """A datagram from ``addr``: True (and it becomes the reply address) if it is the controller's."""
        if addr[0] != self.robot_ip:
            self.foreign += 1
            return False
        self._t_last = time.perf_counter()
        self.peer = addr
        return True

    def received_ns(self) -> int | None:
        """The kernel's receive time [ns, the ``time.time_ns`` clock] of the last datagram returned by ``receive`` —
        when it arrived, however late this process read it — or None where the kernel does not say. From the
        datagram's ``SO_TIMESTAMPNS`` control message (kernels since 6.x refuse ``SIOCGSTAMPNS`` on a socket that has
        it on), else the ``SIOCGSTAMPNS`` ioctl. ≈ 1 µs: called after the reply."""
        for level, kind, payload in self._anc:
            if level == socket.SOL_SOCKET and kind == _SO_TIMESTAMPNS and len(payload) >= _TIMESPEC.size:
                sec, nsec = _TIMESPEC.unpack_from(payload)
                return sec * 1_000_000_000 + nsec
        if not self._stamps:
            return None
        try:
            fcntl.ioctl(self.sock, SIOCGSTAMPNS, self._stamp, True)
        except OSError:
            self._stamps = False
            return None
        sec, nsec = _TIMESPEC.unpack_from(self._stamp)
        return sec * 1_000_000_000 + nsec

    def send(self, data: bytes) -> None:
        """Send a datagram to the last sender (OSError propagates: the caller decides)."""
        try:
            self.sock.sendto(data, _DONTWAIT, self.peer)  # type: ignore[arg-type]
        except BlockingIOError:  # the socket's send buffer is full: wait for room, once
            if not select.select((), [self.sock], (), self.timeout_s)[1]:
                raise
            self.sock.sendto(data, _DONTWAIT, self.peer)  # type: ignore[arg-type]

    def drain(self) -> int:
        """Discard the datagrams waiting in the socket; their number."""
        n = 0
        try:
            while True:
                self.sock.recvfrom(_RX_SIZE, _DONTWAIT)
                n += 1
        except (BlockingIOError, InterruptedError, ConnectionRefusedError):
            pass
        return n

    def close(self) -> None:
        self.sock.close()


def no_message_text(transport: UdpTransport, waited: float, undecodable: int, version: str) -> str:
    """Why no monitoring message arrived within ``waited`` [s], with hints from what did arrive."""
    text = f"no FRI monitoring message from {transport.robot_ip} on UDP port {transport.port} within {waited:.1f} s"
    hints = []
    if undecodable:
        hints.append(f"{undecodable} datagrams from it did not decode as {version} (ClientApplication.version?)")
    if transport.foreign:
        hints.append(f"{transport.foreign} datagrams came from other addresses (ClientApplication.robot?)")
    if not hints:
        hints.append("is the robot application running with this PC's address and port, and the firewall open?")
    return text + "; " + "; ".join(hints)
