"""`lbr` as the tests run it — in this process or as a subprocess — and the thesis start pose the tests start from."""

from __future__ import annotations

import subprocess
import sys

import numpy as np

Q_START = np.array([0.0, 0.071, 0.0, -1.3523, 0.0, 0.1301, 0.0])  # [rad], thesis §5.3.2


def run_in_process(argv) -> tuple[int, str, str]:
    """(exit code, stdout, stderr) of `lbr ARGV` run in this process by ``lbrcli.app.main`` (the code path of the
    `lbr` script without a Python start-up: for many quick refusals)."""
    import contextlib
    import io

    import lbrcli.console
    from lbrcli.app import main

    lbrcli.console._emitted = False
    out, err = io.StringIO(), io.StringIO()
    code = 0
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            main([str(a) for a in argv])
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    return code, out.getvalue(), err.getvalue()


def run_lbr(*args: str, timeout: float = 120, process: bool = False, **kwargs) -> subprocess.CompletedProcess:
    """`lbr ARGS` as a CompletedProcess: by ``lbrcli.app.main`` in this process (the `lbr` script's code path without
    a Python start-up, ≈ 0.6 s of CPU each), or with ``process=True`` (or any ``subprocess.run`` keyword: cwd, env,
    input) the real entry point in a subprocess, as a user runs it — for signals, a timeout, the interpreter's exit."""
    if process or kwargs:
        return run_lbr_process(*args, timeout=timeout, **kwargs)
    code, out, err = run_in_process(args)
    return subprocess.CompletedProcess(["lbr", *map(str, args)], code, out, err)


def run_lbr_process(*args: str, timeout: float = 120, **kwargs) -> subprocess.CompletedProcess:
    """Run the real `lbr` entry point in a subprocess (as a user would)."""
    return subprocess.run(
        [sys.executable, "-m", "lbrcli", *map(str, args)], capture_output=True, text=True, timeout=timeout, **kwargs
    )


def one_line_error(res, code=2):
    assert res.returncode == code, res.stderr
    lines = [l for l in res.stderr.strip().splitlines() if l]
    assert len(lines) == 1, res.stderr
    assert "Traceback" not in res.stderr
    return lines[0]
