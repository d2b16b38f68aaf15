"""Ctrl-C (SIGINT) and SIGTERM as a clean, braking end of a session instead of an exception."""

from __future__ import annotations

import contextlib
import signal
from typing import Iterator

from .application import ClientApplication
from .outcome import EndReason


@contextlib.contextmanager
def interrupts_brake(app: ClientApplication) -> Iterator[None]:
    """While active, SIGINT and SIGTERM ask ``app`` to brake and end (reported as SIGINT or SIGTERM)."""

    def on_int(signum, frame) -> None:  # noqa: ANN001
        app.interrupt(EndReason.SIGINT)

    def on_term(signum, frame) -> None:  # noqa: ANN001
        app.interrupt(EndReason.SIGTERM)

    old_int = signal.signal(signal.SIGINT, on_int)
    old_term = signal.signal(signal.SIGTERM, on_term)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old_int)
        signal.signal(signal.SIGTERM, old_term)
