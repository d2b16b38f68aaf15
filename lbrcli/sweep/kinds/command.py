"""Kind ``command``: any `lbr` command with ``--json``, run as its own process — for commands without a kind module
yet (e.g. ``command = "plan cup-and-ball"``). With ``out = true`` (default) it is given ``-o`` a scratch file, whose
joints serve the joint files of chosen runs."""

from __future__ import annotations

import shlex
import tempfile
from pathlib import Path
from typing import Any, Mapping

from . import Outcome, RunKind, option_words
from ._process import run_lbr


def run(options: Mapping[str, Any], timeout: float | None = None) -> Outcome:
    opts = dict(options)
    words = shlex.split(str(opts.pop("command")))
    args = opts.pop("args", ())
    words += [str(a) for a in (args if isinstance(args, (list, tuple)) else [args])]
    with tempfile.TemporaryDirectory(prefix="lbr-sweep-") as tmp:
        out = Path(tmp) / "out.csv" if opts.pop("out", True) else None
        return run_lbr(words + option_words(opts) + (["-o", str(out)] if out else []), timeout, out)


KIND = RunKind(
    name="command",
    command=(),
    run=run,
    options=None,  # any: the command checks its own options
    summary='any lbr command with --json as a process: command = "plan cup-and-ball", its options beside it',
    required=("command",),
)
