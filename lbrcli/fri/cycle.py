"""What the application tells its observers: the current cycle, and the observer protocol."""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol, Sequence

from .outcome import SessionResult

if TYPE_CHECKING:
    from .application import ClientApplication

from .constants import STATE_IDLE as IDLE

_ZERO7 = (0.0,) * 7


class Observer(Protocol):
    """Called by the application; must return quickly (the next message is due within a period)."""

    def on_start(self, app: "ClientApplication") -> None: ...

    def on_cycle(self, app: "ClientApplication") -> None: ...

    def on_end(self, app: "ClientApplication", result: SessionResult) -> None: ...


class Cycle:
    """What happened in the current cycle (read by observers after the reply went out)."""

    __slots__ = ("t", "state", "answered", "sent_position", "command", "torque", "wrench", "braking", "phase", "row")

    def __init__(self) -> None:
        self.t = 0.0  # [s] controller time since the first message (sequence counter × send period)
        self.state = IDLE  # session state (int)
        self.answered = False  # a command message went out for this monitoring message
        self.sent_position = False  # ... carrying a joint position
        self.command: Sequence[float] = _ZERO7  # [rad] the joint position in force after this cycle
        self.torque: Sequence[float] | None = None  # [Nm] sent this cycle (TORQUE mode)
        self.wrench: Sequence[float] | None = None  # sent this cycle (WRENCH mode)
        self.braking = False  # the command came from the braking stop
        self.phase = 0  # the client's phase / row (logged)
        self.row = -1

    def begin(self, t: float, state: int) -> None:
        """A new cycle at controller time ``t`` [s] in session ``state``: nothing sent yet."""
        self.t = t
        self.state = state
        self.answered = self.sent_position = self.braking = False
        self.torque = self.wrench = None
