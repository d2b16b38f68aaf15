"""Run kinds of `lbr sweep`: what one run of a study does, one small module per `lbr` command.

Every module in this package defines ``KIND`` (or ``KINDS``), a :class:`RunKind`: the command it stands for, the
option names a study may set (the command's long options without ``--``), and ``run(options, timeout) -> Outcome``
executed in a Dask worker (``timeout`` [s] or None: kinds that start a process stop it then; in-process kinds
ignore it). A new kind (e.g. the cup-and-ball catch) is a new module here; nothing else changes.
In-process kinds call the same functions as the command, so a run's figures are the command's ``--json`` object;
the closed-loop kinds run the command itself (``kinds.subprocess``).
"""

from __future__ import annotations

import functools
import importlib
import pkgutil
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

from ..values import cli_text


@dataclass(frozen=True)
class Outcome:
    """What a run produced: the command's JSON figures, its exit code and error line, and what the judges and the
    joint files need (a JointTrajectory and the kind's own context)."""

    figures: dict
    exit_code: int = 0
    error: str | None = None
    joints: Any = None  # trajectories.trajectory.JointTrajectory or None
    context: Any = None  # for the kind's judge (e.g. the time the motion stops [s])


@dataclass(frozen=True)
class RunKind:
    """One kind of run: ``lbr <command…>`` with the options of a study."""

    name: str  # as written in a study's `kind`
    command: (
        tuple[str, ...] | None
    )  # the lbr command words, e.g. ("plan", "anti-sway"); () from the options, None: none
    run: Callable[[Mapping[str, Any], float | None], Outcome]  # in a worker; options by command-line names
    options: tuple[str, ...] | None  # option names a study may set (None: any, the command checks them)
    summary: str = ""  # one line for `lbr sweep --kinds`
    required: tuple[str, ...] = ()
    paths: tuple[str, ...] = ()  # options naming files: resolved against the study file's folder
    arguments: tuple[str, ...] = ()  # options that are positional arguments on the command line
    repeatable: tuple[str, ...] = ()  # options given once per value of a list (e.g. --push)
    kind_only: tuple[str, ...] = ()  # options of the kind that no command has: a run using one has no command line
    defaults: Mapping[str, Any] = field(default_factory=dict)  # set unless the study sets them
    judge: Callable[[Outcome, "Judge"], dict] | None = None  # judged figures (string-length band)
    version: int = 1  # bump when a kind's results change: its cached runs are then recomputed
    warm_up: Callable[[], None] | None = None  # imports and first-use costs, paid by each worker before the runs

    def command_line(self, options: Mapping[str, Any]) -> list[str]:
        """The `lbr` command line that does what a run with ``options`` does (outputs left out); [] if none does."""
        import shlex

        if self.command is None or any(k in options for k in self.kind_only):
            return []
        if self.command:
            words, rest = list(self.command), dict(options)
        else:  # the `command` kind: the words are an option
            rest = {k: v for k, v in options.items() if k not in ("command", "out", "args")}
            args = options.get("args", ())
            words = shlex.split(str(options["command"])) + [
                cli_text(a) for a in (args if isinstance(args, (list, tuple)) else [args])
            ]
        words += [cli_text(rest.pop(a)) for a in self.arguments if a in rest]
        return ["lbr", *words, *option_words(rest, self.repeatable)]

    def shell_line(self, options: Mapping[str, Any]) -> str | None:
        """:meth:`command_line` quoted for a shell; None when no command does what the run does."""
        import shlex

        line = self.command_line(options)
        return " ".join(shlex.quote(w) for w in line) if line else None


def option_words(options: Mapping[str, Any], repeatable: tuple[str, ...] = ()) -> list[str]:
    """``--name value`` words of the options: a flag for true, nothing for false or None, ``--name v`` once per
    value of a list for a repeatable option."""
    words: list[str] = []
    for name, value in options.items():
        if value is None or value is False:
            continue
        if value is True:
            words.append(f"--{name}")
        elif name in repeatable and isinstance(value, (list, tuple)):
            for v in value:
                words += [f"--{name}", cli_text(v)]
        else:
            words += [f"--{name}", cli_text(value)]
    return words


@dataclass(frozen=True)
class Judge:
    """Judged figures of a study: each run's joint path re-simulated for string lengths off by ``errors``."""

    errors: tuple[float, ...]  # relative string-length errors, e.g. (-0.1, 0, 0.1)
    model: str = "project"  # project: the planners' pendulum model; independent: planners.sway_judge (DOP853)


def python_args(options: Mapping[str, Any]) -> dict[str, Any]:
    """Options by command-line name → keyword arguments (``a-max`` → ``a_max``); lists as their command-line
    text, so that a run parses exactly what the command would."""
    return {k.replace("-", "_"): cli_text(v) if isinstance(v, (list, tuple)) else v for k, v in options.items()}


@functools.lru_cache(maxsize=1)
def registry() -> dict[str, RunKind]:
    """Every kind of every module of this package, by name (found once per process)."""
    found: dict[str, RunKind] = {}
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        module = importlib.import_module(f"{__name__}.{info.name}")
        for kind in getattr(module, "KINDS", ()) or ((module.KIND,) if hasattr(module, "KIND") else ()):
            found[kind.name] = kind
    return found


def warm_robot() -> None:
    """Import the planners and build the robot model once (pinocchio, scipy): seconds a worker's first run would
    otherwise carry."""
    import lbrcli.antisway  # noqa: F401
    import planners.swingup  # noqa: F401
    import trajectories.ik  # noqa: F401
    from lbrcli.options import DEFAULT_FLANGE, make_robot

    make_robot(DEFAULT_FLANGE, None).fk_path(__import__("numpy").zeros((2, 7)))


def warm_up(name: str) -> None:
    """Run a kind's warm-up in this process (Dask calls it on every worker before the runs)."""
    kind = get_kind(name)
    if kind.warm_up is not None:
        kind.warm_up()


def get_kind(name: str) -> RunKind:
    """The kind called ``name``; KeyError listing the known ones."""
    kinds = registry()
    if name not in kinds:
        raise KeyError(f"unknown kind {name!r}; known: {', '.join(sorted(kinds))}")
    return kinds[name]
