"""Options several commands share, declared once, and the flags behind the settings they make.

An :class:`OptionGroup` is a function whose parameters are command-line options (typer ``Annotated`` aliases with
their defaults) and whose result is the one value a command receives for them — typically a settings object. A
command names the group by a parameter (``fri: FriOptions``); :func:`with_options` puts the group's options into the
command's signature at that place (what typer parses and ``--help`` lists), builds the value from them when the
command runs, and turns a :class:`~trajectories.errors.SettingError` the command's libraries raise into the one-line
OptionError naming the flag the setting came from (``flags``: ``"Class.field"`` → ``"--option"``). Adding an option
to a group adds it to every command that uses the group; nothing else changes.
"""

from __future__ import annotations

import functools
import inspect
from dataclasses import dataclass, field, replace
from typing import Any, Callable, Mapping

from trajectories.errors import InputError, LbrError, OptionError, SettingError


def _parameters(fn: Callable, skip: frozenset[str] | set[str] = frozenset()) -> dict[str, inspect.Parameter]:
    """``fn``'s parameters with their annotations evaluated in its module, except those named in ``skip`` (their
    types need not be importable when the command is declared: a group's value) and the return annotation."""
    out = {}
    for name, p in inspect.signature(fn).parameters.items():
        if isinstance(p.annotation, str) and name not in skip:
            p = p.replace(annotation=eval(p.annotation, fn.__globals__))  # noqa: S307 - the module's own annotation
        out[name] = p
    return out


def _flag(parameter: inspect.Parameter) -> str | None:
    """The longest option name of a typer ``Annotated`` parameter (None: not a command-line option)."""
    import typer.models

    for meta in getattr(parameter.annotation, "__metadata__", ()):
        if isinstance(meta, typer.models.OptionInfo):
            first = (meta.default,) if isinstance(meta.default, str) else ()
            names = [d.split("/")[0] for d in (*first, *(meta.param_decls or ())) if d.startswith("-")]
            return max(names, key=len) if names else None
    return None


@dataclass(frozen=True)
class OptionGroup:
    """A group of options (the parameters of ``build``) and the value ``build`` makes of them. A parameter of
    ``build`` without a typer annotation is not an option: ``present`` receives the names of the group's options the
    command has (a command may leave some out, :meth:`without`; they take ``build``'s defaults)."""

    build: Callable[..., Any]
    flags: Mapping[str, str] = field(default_factory=dict)  # "Class.field" of a setting → the flag it comes from
    omitted: frozenset[str] = frozenset()
    aliases: Mapping[str, Any] = field(default_factory=dict)  # parameter → another annotation (same option, other help)

    def without(self, *names: str) -> "OptionGroup":
        """The group without the options ``names`` (parameter names)."""
        unknown = set(names) - set(self._all())
        if unknown:
            raise TypeError(f"{self.build.__name__} has no options {sorted(unknown)}")
        return replace(self, omitted=self.omitted | frozenset(names))

    def replacing(self, **annotations: Any) -> "OptionGroup":
        """The group with other annotations for some options (their help differs for this command)."""
        return replace(self, aliases={**self.aliases, **annotations})

    def renaming(self, **flags: str) -> "OptionGroup":
        """The group with other flags for some settings (``Class__field="--flag"``: ``Class.field`` → flag)."""
        return replace(self, flags={**self.flags, **{k.replace("__", "."): v for k, v in flags.items()}})

    def _all(self) -> dict[str, inspect.Parameter]:
        return _parameters(self.build, {"present"})

    def parameters(self) -> list[inspect.Parameter]:
        """The group's options as keyword parameters of a command."""
        out = []
        for name, p in self._all().items():
            if name in self.omitted or _flag(p) is None and name not in self.aliases:
                continue
            out.append(p.replace(kind=inspect.Parameter.KEYWORD_ONLY, annotation=self.aliases.get(name, p.annotation)))
        return out

    def make(self, values: dict[str, Any]) -> Any:
        """``build`` called with the options' values (and ``present`` if it takes it)."""
        extra = {"present": frozenset(values)} if "present" in self._all() else {}
        return self.build(**values, **extra)


def with_options(*, flags: Mapping[str, str] | None = None, **groups: OptionGroup) -> Callable[[Callable], Callable]:
    """Decorator of a command: each parameter named in ``groups`` is replaced by that group's options; the command
    gets the group's value instead. SettingError → OptionError naming the flag (the groups' ``flags``, then
    ``flags``: this command's own)."""

    def decorate(fn: Callable) -> Callable:
        sig = inspect.signature(fn)
        params: list[inspect.Parameter] = []
        for p in _parameters(fn, set(groups)).values():
            params.extend(
                groups[p.name].parameters() if p.name in groups else [p.replace(kind=inspect.Parameter.KEYWORD_ONLY)]
            )
        owned = {name: [p.name for p in g.parameters()] for name, g in groups.items()}
        names = {k: v for g in groups.values() for k, v in g.flags.items()} | dict(flags or {})

        @functools.wraps(fn)
        def command(**kwargs: Any) -> Any:
            with settings_named(names):
                for name, group in groups.items():
                    kwargs[name] = group.make({p: kwargs.pop(p) for p in owned[name]})
                return fn(**kwargs)

        command.__signature__ = sig.replace(parameters=params, return_annotation=inspect.Signature.empty)  # type: ignore[attr-defined]
        command.__annotations__ = {p.name: p.annotation for p in params}  # what get_type_hints reports
        return command

    return decorate


SHARED_FLAGS = {
    "RobotConfig.tool": "--tool",
    "RobotConfig.flange": "--flange",
    "Plot.path": "--plot",
    "read_table.headerless_dt": "--dt",
    "solve_ik_path.q0": "--q0",
}
"""Settings every command that takes them takes by the same option: the app maps a SettingError of these that no
command mapped (:func:`flag_message`)."""


def flag_message(exc: SettingError, names: Mapping[str, str] = SHARED_FLAGS) -> str | None:
    """The message of ``exc`` naming the option its setting comes from (``names``), or None if it has none."""
    flag = names.get(exc.setting)
    return f"{flag}: {exc.message}" if flag is not None else None


def name_text(text: str, names: Mapping[str, str] | None = None) -> str:
    """``text`` with the flags for the settings it names (``Class.field``, e.g. a hint "lower SwingUpRequest.theta_d"
    → "lower --theta-d"); ``names`` default: those of the commands running (:class:`settings_named`) and the shared
    ones."""
    import re

    if names is None:
        names = {k: v for n in (SHARED_FLAGS, *_active) for k, v in n.items()}
    found = [s for s in names if s in text]
    if not found:
        return text
    pattern = re.compile("|".join(rf"\b{re.escape(s)}\b" for s in sorted(found, key=len, reverse=True)))
    return pattern.sub(lambda m: names[m.group(0)], text)


def name_flags(exc: LbrError, names: Mapping[str, str]) -> None:
    """Write the flags for the settings an error's text names (:func:`name_text`), in place: the error keeps its
    type, exit code and place."""
    if isinstance(exc, InputError):
        exc.message = name_text(exc.message, names)
        exc.args = (str(exc),)
    elif exc.args:
        exc.args = (name_text(str(exc.args[0]), names), *exc.args[1:])


_active: list[Mapping[str, str]] = []  # the flag names of the settings_named contexts entered (innermost last)


class settings_named:
    """Context: a SettingError raised inside becomes an OptionError naming the flag of its setting
    (``names``: "Class.field" → "--flag"); a setting without a flag keeps its own name. Another lbr error that names
    settings in its text (a hint) names their flags instead (:func:`name_flags`)."""

    def __init__(self, names: Mapping[str, str]) -> None:
        self.names = names

    def __enter__(self) -> "settings_named":
        _active.append(self.names)
        return self

    def __exit__(self, kind, exc, tb) -> bool:
        _active.pop()
        if isinstance(exc, SettingError) and exc.setting in self.names:
            raise OptionError(flag_message(exc, self.names)) from None
        if isinstance(exc, LbrError):
            name_flags(exc, self.names)
        return False
