"""Typed exceptions of the FRI layer (all are ``trajectories.errors.LbrError``: the CLI maps them to exit codes)."""

from __future__ import annotations

from trajectories.errors import FriDecodeError, FriError, FriForeignMessage, InputError

__all__ = [
    "FriError",
    "FriDecodeError",
    "FriForeignMessage",
    "FriTimeout",
    "FriCommandError",
    "FriStateError",
    "StopSession",
]


class FriTimeout(FriError):
    """No monitoring message arrived in time (nothing was ever sent)."""


class FriCommandError(FriError):
    """A client set a command the session's client command mode does not allow (KUKA's FRIException)."""


class FriStateError(FriError):
    """A value the controller did not send in this message (e.g. an IO channel that is not configured)."""


class StopSession(Exception):
    """Raised by a client callback to end the session: the application brakes (if commanding) and ends.

    ``completed`` True: the client finished what it was asked to do (outcome COMPLETED); False: it refused to go on
    (outcome REFUSED, e.g. a start too far from the robot); ``bad_input``: refused because the client's input does not
    fit the controller (reason BAD_INPUT, e.g. rows sampled at another period).
    """

    def __init__(self, reason: str, completed: bool = True, bad_input: bool = False) -> None:
        super().__init__(reason)
        self.reason = reason
        self.completed = completed
        self.bad_input = bad_input  # the client's input does not fit this controller (the CLI exits 2)


# re-exported for callers that only import the FRI layer
_ = InputError
