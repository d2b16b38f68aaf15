"""Work counted rather than timed: the lines of Python a call runs (the same on a busy machine as on an idle one)."""

from __future__ import annotations

import sys
from typing import Callable


def line_events(fn: Callable[[], object]) -> int:
    """Lines of Python executed by ``fn()`` (every frame it runs, this thread)."""
    count = [0]

    def local(frame, event, arg):
        if event == "line":
            count[0] += 1
        return local

    sys.settrace(lambda frame, event, arg: local)
    try:
        fn()
    finally:
        sys.settrace(None)
    return count[0]
