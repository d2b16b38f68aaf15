"""Human output, JSON figures and progress bars at the CLI edge.

With ``--json`` one JSON object goes to stdout and all human text to stderr. Progress bars show only when
stdout is a terminal and ``--json`` is off.
"""

from __future__ import annotations

import contextlib
import json
import math
import sys
from typing import Any, Callable, Iterator

import numpy as np


def _jsonable(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        return v if math.isfinite(v) else None
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


_emitted = False  # whether this process printed its JSON figures (main() then adds no error object)


def json_emitted() -> bool:
    """True once a Reporter printed the command's JSON object on stdout."""
    return _emitted


class Reporter:
    """Where a command prints: text on stdout (stderr with --json), figures as one JSON object."""

    def __init__(self, json_mode: bool = False) -> None:
        from rich.console import Console  # (rich loads when a command prints, not for every `lbr` start-up)

        self.json_mode = json_mode
        self.console = Console(stderr=json_mode, highlight=False, soft_wrap=True)

    def print(self, *args: Any, **kwargs: Any) -> None:
        self.console.print(*args, **kwargs)

    def warn(self, text: str) -> None:
        from rich.console import Console

        Console(stderr=True, highlight=False, soft_wrap=True).print(f"[yellow]warning:[/yellow] {text}")

    def emit(self, figures: dict[str, Any]) -> None:
        """Print the figures as one JSON object on stdout (only with --json)."""
        global _emitted
        if self.json_mode:
            _emitted = True
            sys.stdout.write(json.dumps(_jsonable(figures)) + "\n")
            sys.stdout.flush()

    @property
    def interactive(self) -> bool:
        return not self.json_mode and sys.stdout.isatty()

    @contextlib.contextmanager
    def progress(self, description: str, total: float | None) -> Iterator[Callable[[float], None]]:
        """Context manager yielding ``update(completed)``; a rich progress bar on a terminal, else a no-op."""
        if not self.interactive:
            yield lambda completed: None
            return
        from rich.progress import BarColumn, Progress, TaskProgressColumn, TextColumn, TimeRemainingColumn

        with Progress(
            TextColumn("{task.description}"),
            BarColumn(),
            TaskProgressColumn(),
            TimeRemainingColumn(),
            console=self.console,
            transient=True,
        ) as prog:
            task = prog.add_task(description, total=total)
            yield lambda completed: prog.update(task, completed=completed)
