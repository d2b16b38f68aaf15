"""The `lbr` command: a Typer app whose commands live one group per module in ``lbrcli.commands``.

Every module in ``lbrcli/commands`` exposes ``register(app, groups)``; heavy libraries are imported inside
the command functions so that ``lbr --help`` stays fast.
"""

from __future__ import annotations

import importlib
import json
import os
import pkgutil
import signal
import sys
from typing import Annotated, NoReturn

import typer

from . import commands
from .outputs import guarded

# OpenCV and FFmpeg print warnings of their own on stderr (e.g. one per frame a full disk refused); lbr reports the
# outcome in one line instead.
os.environ.setdefault("OPENCV_LOG_LEVEL", "ERROR")
os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")

app = typer.Typer(
    name="lbr",
    help="Dynamic-control experiments with the KUKA LBR iiwa 7 R800: plan, check, execute over FRI, track, compare.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    rich_markup_mode="rich",
    context_settings={"help_option_names": ["-h", "--help"]},
    add_completion=True,
)
groups: dict[str, typer.Typer] = {
    "plan": typer.Typer(help="Plan trajectories (anti-sway crane moves, swing-up).", no_args_is_help=True),
    "track": typer.Typer(help="Track the ball in experiment videos; calibrate the camera.", no_args_is_help=True),
    "control": typer.Typer(
        help="Feedback control at the FRI rate (pendulum module upright, sway damping).", no_args_is_help=True
    ),
}
for _name, _group in groups.items():
    app.add_typer(_group, name=_name)

for _info in sorted(pkgutil.iter_modules(commands.__path__), key=lambda m: m.name):
    importlib.import_module(f"{commands.__name__}.{_info.name}").register(app, groups)

# Every command refuses to overwrite its own inputs (Path arguments) with its outputs (Path options), centrally.
for _typer in (app, *groups.values()):
    for _command in _typer.registered_commands:
        _command.callback = guarded(_command.callback)


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("lbr")
    except PackageNotFoundError:  # run from a source tree that is not installed
        return "unknown"


def _show_version(value: bool) -> None:
    if value:
        sys.stdout.write(f"lbr {_version()}\n")
        raise typer.Exit(0)


@app.callback()
def _root(
    version: Annotated[
        bool,
        typer.Option("--version", callback=_show_version, is_eager=True, help="Print the lbr version and exit."),
    ] = False,
) -> None:
    """Dynamic-control experiments with the KUKA LBR iiwa 7 R800: plan, check, execute over FRI, track, compare."""


def _json_requested(argv: list[str]) -> bool:
    head = argv[: argv.index("--")] if "--" in argv else argv
    return "--json" in head


def _usage_message(exc) -> str:
    """A click usage error as one line: what is wrong, then where to read the usage. A bad value names its option
    first ('--margin must be in [0, 1), got 2'), as the option parsers of lbrcli.options phrase it."""
    message = " ".join(line.strip() for line in exc.format_message().splitlines() if line.strip())
    param = getattr(exc, "param", None)
    if type(exc).__name__ == "BadParameter" and param is not None and getattr(exc, "param_hint", None) is None:
        names = [n for n in (getattr(param, "opts", None) or []) if n.startswith("-")]
        hint = max(names, key=len) if names else str(getattr(param, "metavar", None) or param.name or "").upper()
        text = " ".join(str(exc.message).split())
        message = f"{hint} {text}" if text.startswith("must ") else f"{hint}: {text}"
    ctx = getattr(exc, "ctx", None)
    if ctx is not None:
        return f"{ctx.command_path}: {message} (see '{ctx.command_path} --help')"
    return message


def _error_message(exc) -> str:
    """An lbr error's line: a setting's error names the option it comes from where every command names it alike."""
    from trajectories.errors import SettingError

    from .option_groups import SHARED_FLAGS, flag_message, name_flags

    name_flags(exc, SHARED_FLAGS)
    return (flag_message(exc) if isinstance(exc, SettingError) else None) or str(exc)


def _fail(message: str, code: int, argv: list[str], extra: dict | None = None) -> NoReturn:
    """One line on stderr; with --json also one JSON object on stdout (unless the command already printed its
    figures); then exit with ``code``."""
    from .console import json_emitted

    sys.stderr.write(f"lbr: error: {message}\n")
    if _json_requested(argv) and not json_emitted():
        sys.stdout.write(json.dumps({"ok": False, "exit_code": code, "error": message, **(extra or {})}) + "\n")
    sys.stdout.flush()
    sys.exit(code)


def _interrupted(argv: list[str]) -> NoReturn:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a second Ctrl-C must not print a traceback during cleanup
    from .console import json_emitted

    sys.stderr.write("lbr: interrupted\n")
    if _json_requested(argv) and not json_emitted():
        sys.stdout.write(json.dumps({"ok": False, "exit_code": 130, "error": "interrupted"}) + "\n")
    sys.stdout.flush()
    # CPython (3.8-3.12) marks a KeyboardInterrupt that ended a string exec/eval (dataclasses, namedtuple, numpy
    # build code that way) as unhandled even when it was caught, and under `python -m` then dies by SIGINT instead
    # of exiting 130; a string exec that completes clears the mark.
    exec("pass", {})
    sys.exit(130)


_command = None


def _click_command():
    """The click group of the app, built once per process (typer builds it anew on each call; ≈ 0.1 s)."""
    global _command
    if _command is None:
        _command = typer.main.get_command(app)
    return _command


def _internal(exc: BaseException, argv: list[str]) -> NoReturn:
    """An exception lbr did not expect: one line naming it (exit 1); LBR_TRACEBACK=1 re-raises it for a report."""
    if os.environ.get("LBR_TRACEBACK"):
        raise exc
    text = " ".join(str(exc).split())[:300] or type(exc).__name__
    _fail(f"internal error ({type(exc).__name__}: {text}); please report it with the command line "
          "(LBR_TRACEBACK=1 shows where)", 1, argv)  # fmt: skip


def main(argv: list[str] | None = None) -> None:
    """Entry point: runs the app and turns every failure into one line on stderr and an exit code.

    Usage errors (unknown option, missing argument, a value that does not parse) exit 2; lbr errors carry their
    code (2 bad input, 1 a check failed or a job that could not be done, e.g. an output on a full disk);
    file-system errors naming their file (an output folder that does not exist, a path that is a directory, no
    permission) exit 2; Ctrl-C exits 130; an exception lbr did not expect is one line "internal error" (exit 1).
    With --json the error is also one JSON object on stdout: ``{"ok": false, "exit_code": N, "error": "..."}``.
    """
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        from trajectories.errors import LbrError

        from ._click import click_exceptions

        exc_mod = click_exceptions()
    except KeyboardInterrupt:
        _interrupted(argv)
    try:
        rv = _click_command().main(args=argv, prog_name="lbr", standalone_mode=False)
    except getattr(exc_mod, "NoArgsIsHelpError", ()):  # `lbr` or `lbr plan` alone: the help was printed
        sys.exit(2)
    except exc_mod.ClickException as exc:
        _fail(_usage_message(exc), exc.exit_code, argv)
    except typer.Abort:  # end of input at a prompt, or Ctrl-C inside click
        _interrupted(argv)
    except LbrError as exc:
        where = (("file", getattr(exc, "file", None)), ("row", getattr(exc, "row", None)),
                 ("column", getattr(exc, "column", None)))  # fmt: skip
        _fail(_error_message(exc), exc.exit_code, argv, {k: v for k, v in where if v is not None})
    except BrokenPipeError:  # `lbr ... | head`: the reader left; say nothing more
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        sys.exit(1)
    except OSError as exc:
        from trajectories.atomic import FAILED_WRITE_ERRNOS

        failed = exc.errno in FAILED_WRITE_ERRNOS  # the disk, not the path: the job failed (exit 1)
        if exc.filename is None:
            if not failed:  # not about a file the user named (e.g. a socket)
                _internal(exc, argv)
            _fail(f"cannot write an output: {exc.strerror or exc}", 1, argv)
        _fail(f"{exc.filename}: {exc.strerror or exc}", 1 if failed else 2, argv, {"file": str(exc.filename)})
    except KeyboardInterrupt:
        _interrupted(argv)
    except MemoryError:
        _fail("out of memory (is an input far larger than it should be?)", 1, argv)
    except Exception as exc:  # a bug: one line (and the traceback with LBR_TRACEBACK=1), never a bare traceback
        _internal(exc, argv)
    if rv == 130:  # typer turned a Ctrl-C into exit 130
        _interrupted(argv)
    if isinstance(rv, int) and rv:
        from .console import json_emitted

        if _json_requested(argv) and not json_emitted():
            sys.stdout.write(json.dumps({"ok": False, "exit_code": rv}) + "\n")
        sys.exit(rv)
