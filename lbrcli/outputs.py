"""Output safety at the CLI edge: a command never overwrites one of its inputs, nor writes two outputs to one file.

Call :func:`guard_outputs` before any work, with the options as the user typed them (every command does through
:func:`guarded`): an output that is an input, two outputs on one file, or an output that exists as a link, device,
FIFO or socket are refused before anything is computed. Every output is then written
through :func:`trajectories.atomic.atomic_path` (CSV writers and plots already do), so an interrupted command never
leaves a half-written file under the final name.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Mapping, Optional

from trajectories.atomic import atomic_open, atomic_path  # noqa: F401  (re-exported for the commands)

Named = Mapping[str, Optional["str | Path"]]  # option name (e.g. "-o", "--plot", "JOINT_CSV") → path or None


def _same_file(a: Path, b: Path) -> bool:
    if os.path.realpath(a) == os.path.realpath(b):
        return True
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)  # hard links
    except OSError:
        return False


def guard_outputs(inputs: Named, outputs: Named) -> None:
    """Raise OptionError (exit 2, naming both paths) when an output is an input or two outputs are one file, and
    OutputRefused (exit 2) when an output exists as a symbolic link, a device, a FIFO or a socket."""
    from trajectories.atomic import refuse_special
    from trajectories.errors import OptionError

    ins = [(name, Path(p)) for name, p in inputs.items() if p is not None]
    outs = [(name, Path(p)) for name, p in outputs.items() if p is not None]
    for oname, opath in outs:
        refuse_special(opath, oname)
    for oname, opath in outs:
        for iname, ipath in ins:
            if _same_file(opath, ipath):
                raise OptionError(
                    f"{oname} {opath} is the input {iname} {ipath}: refusing to overwrite an input (choose another name)"
                )
    for k, (aname, apath) in enumerate(outs):
        for bname, bpath in outs[k + 1 :]:
            if _same_file(apath, bpath):
                raise OptionError(
                    f"{aname} {apath} and {bname} {bpath} are the same file: give each output its own name"
                )


def require_folders(outputs: Named) -> None:
    """Before long work (a plan): an output whose folder does not exist, or that is a folder, raises the OSError its
    write would raise (exit 2, naming the path) — now, not after minutes of planning."""
    import errno

    for _, p in outputs.items():
        if p is None:
            continue
        path = Path(p)
        if path.is_dir():
            raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(path))
        if not path.absolute().parent.is_dir():
            raise FileNotFoundError(errno.ENOENT, os.strerror(errno.ENOENT), str(path))


INPUT_OPTIONS = frozenset(
    {"limits", "calibration", "plane", "obstacles", "secret", "geometry"}
)  # Path options that are read


def _path_roles(fn) -> dict[str, tuple[str, str]]:
    """{parameter: (role, name shown to the user)} for the Path parameters of a Typer command function: arguments
    are inputs, options are outputs (except INPUT_OPTIONS)."""
    import typing
    from pathlib import Path

    import typer.models

    hints = typing.get_type_hints(fn, include_extras=True)
    roles = {}
    for name, hint in hints.items():
        if typing.get_origin(hint) is not typing.Annotated:
            continue
        base, *meta = typing.get_args(hint)
        inner = [a for a in typing.get_args(base) if a is not type(None)] or [base]
        inner = [typing.get_args(a)[0] if typing.get_origin(a) in (list, tuple) else a for a in inner]
        if Path not in inner:
            continue
        for m in meta:
            if isinstance(m, typer.models.ArgumentInfo):
                roles[name] = ("input", (m.metavar or name).upper().rstrip("."))
            elif isinstance(m, typer.models.OptionInfo):
                decls = [d for d in (m.param_decls or ()) if d.startswith("-")] or [f"--{name.replace('_', '-')}"]
                shown = max(decls, key=len)
                roles[name] = ("input" if name in INPUT_OPTIONS else "output", shown)
    return roles


def guarded(fn):
    """Wrap a command function so that it refuses (exit 2) an output that is one of its inputs, or two outputs on
    one file, before it runs — for every command, whether or not it calls :func:`guard_outputs` itself."""
    import functools
    import inspect

    roles = _path_roles(fn)
    if not any(r == "output" for r, _ in roles.values()):
        return fn
    signature = inspect.signature(fn)

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        bound = signature.bind_partial(*args, **kwargs).arguments
        inputs, outputs = {}, {}
        for name, (role, shown) in roles.items():
            value = bound.get(name)
            values = value if isinstance(value, (list, tuple)) else [value]
            for k, v in enumerate(values):
                if v is not None:
                    key = shown if len(values) == 1 else f"{shown}[{k + 1}]"
                    (inputs if role == "input" else outputs)[key] = v
        guard_outputs(inputs, outputs)
        return fn(*args, **kwargs)

    return wrapper
