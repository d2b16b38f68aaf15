"""The `lbr` command: a Typer app whose commands live one group per module in ``lbrcli.commands``.

Every module in ``lbrcli/commands`` exposes ``register(app, groups)``; heavy libraries are imported inside
the command functions so that ``lbr --help`` stays fast.
"""

from __future__ import annotations

import importlib
import pkgutil
import sys

import typer

from . import commands

app = typer.Typer(
    name="lbr",
    help="Dynamic-control experiments with the KUKA LBR iiwa 7 R800: plan, check, execute over FRI, track, compare.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    rich_markup_mode="rich",
    context_settings={"help_option_names": ["-h", "--help"]},
    add_completion=False,
)
groups: dict[str, typer.Typer] = {
    "plan": typer.Typer(help="Plan trajectories (anti-sway crane moves, swing-up).", no_args_is_help=True),
    "track": typer.Typer(help="Track the ball in experiment videos; calibrate the camera.", no_args_is_help=True),
}
for _name, _group in groups.items():
    app.add_typer(_group, name=_name)

for _info in sorted(pkgutil.iter_modules(commands.__path__), key=lambda m: m.name):
    importlib.import_module(f"{commands.__name__}.{_info.name}").register(app, groups)


def main() -> None:
    """Entry point: runs the app and turns lbr errors, and file-system errors naming their file (an output folder
    that does not exist, a path that is a directory, no permission), into one line on stderr and an exit code."""
    from trajectories.errors import LbrError

    try:
        app()
    except LbrError as exc:
        sys.stderr.write(f"lbr: error: {exc}\n")
        sys.exit(exc.exit_code)
    except OSError as exc:
        if exc.filename is None:  # not about a file the user named (e.g. a socket): a bug, keep the traceback
            raise
        sys.stderr.write(f"lbr: error: {exc.filename}: {exc.strerror or exc}\n")
        sys.exit(2)
    except KeyboardInterrupt:
        sys.stderr.write("lbr: interrupted\n")
        sys.exit(130)
