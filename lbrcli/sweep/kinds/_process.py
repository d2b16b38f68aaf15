"""Runs that are `lbr` processes: the closed-loop commands (an FRI session with the simulator) and any command
given by name. The run's figures are the process's ``--json`` object, its exit code and ``lbr: error:`` line."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any, Sequence

from . import Outcome

TIMEOUT_EXIT = 124  # exit code recorded for a run stopped at the study's timeout (as coreutils' timeout)
_LIBC = None


def _die_with_parent() -> None:  # pragma: no cover (runs in the child between fork and exec)
    """The child gets SIGTERM (lbr's clean stop) when the worker thread that started it dies (a killed worker)."""
    if _LIBC is not None:
        _LIBC.prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG


def _load_libc() -> None:
    global _LIBC
    if _LIBC is None and sys.platform.startswith("linux"):
        import ctypes

        _LIBC = ctypes.CDLL(None)  # loaded here, before the fork: the child only calls the function


def error_line(stderr: str) -> str | None:
    """The last ``lbr: error: ...`` (or ``lbr: interrupted``) line of a command's stderr, without the prefix."""
    for line in reversed(stderr.splitlines()):
        if line.startswith("lbr: error: "):
            return line[len("lbr: error: ") :]
        if line.startswith("lbr: interrupted"):
            return "interrupted"
    return None


def run_lbr(words: Sequence[str], timeout: float | None, joints: Path | None = None) -> Outcome:
    """``python -m lbrcli WORDS... --json``: its JSON figures (an error object gives none), exit code, error line;
    the joints of ``joints`` (a file the command wrote) when given and written."""
    _load_libc()
    cmd = [sys.executable, "-m", "lbrcli", *words, "--json"]
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, stdin=subprocess.DEVNULL,
                           preexec_fn=_die_with_parent if _LIBC is not None else None)  # fmt: skip
    except subprocess.TimeoutExpired:
        return Outcome({}, TIMEOUT_EXIT, f"timed out after {timeout:g} s (the study's timeout)")
    figures: dict[str, Any] = {}
    lines = [ln for ln in p.stdout.splitlines() if ln.startswith("{")]
    if lines:
        figures = json.loads(lines[-1])
        if figures.get("ok") is False and set(figures) <= {"ok", "exit_code", "error", "file", "row", "column"}:
            figures = {}  # the error object main() prints: no figures
    error = error_line(p.stderr) if p.returncode else None
    if p.returncode and error is None:
        tail = [ln for ln in p.stderr.splitlines() if ln.strip()]
        error = tail[-1] if tail else f"exit {p.returncode}"
    traj = None
    if joints is not None and joints.exists():
        from trajectories.csvio import read_joint_csv

        traj = read_joint_csv(joints)
    return Outcome(figures, p.returncode, error, traj)
