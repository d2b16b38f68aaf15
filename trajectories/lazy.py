"""Lazy package exports (PEP 562).

A package names its public API in ``__all__`` and imports each name under ``if TYPE_CHECKING:`` (read by type
checkers and by the API reference, which documents the names from there). At run time :func:`lazy_exports` imports
a name's submodule on its first access, so ``import planners`` stays as cheap as before and the CLI's help does not
load scipy or pinocchio for names it never touches::

    TYPE_CHECKING = False  # typing.TYPE_CHECKING, without importing typing
    if TYPE_CHECKING:
        from .antisway import AntiSwayOptions, plan_layout

    __all__ = ["AntiSwayOptions", "plan_layout"]
    __getattr__, __dir__ = lazy_exports(__name__)
"""

from __future__ import annotations

import importlib
import sys

TYPE_CHECKING = False  # typing.TYPE_CHECKING without importing typing
if TYPE_CHECKING:
    from pathlib import Path
    from typing import Any, Callable


def type_checking_imports(init_file: str | Path) -> dict[str, tuple[str, str]]:
    """{exported name: (submodule, its name there)} of the ``from .sub import name`` lines under
    ``if TYPE_CHECKING:`` in a package's ``__init__.py``."""
    import ast  # only on the first lookup: importing the package stays cheap

    with open(init_file, encoding="utf-8") as f:
        tree = ast.parse(f.read())
    found: dict[str, tuple[str, str]] = {}
    for node in tree.body:
        if isinstance(node, ast.If) and isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING":
            for stmt in node.body:
                if isinstance(stmt, ast.ImportFrom) and stmt.level == 1 and stmt.module:
                    for alias in stmt.names:
                        found[alias.asname or alias.name] = (stmt.module, alias.name)
    return found


def lazy_exports(package: str) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``(__getattr__, __dir__)`` for the package named ``package`` (its ``__name__``): a name of its
    ``if TYPE_CHECKING:`` imports is imported from its submodule on first access and kept in the package."""
    module = sys.modules[package]
    table: dict[str, tuple[str, str]] = {}

    def where() -> dict[str, tuple[str, str]]:
        if not table:
            table.update(type_checking_imports(module.__file__))
        return table

    def __getattr__(name: str) -> Any:
        if name not in where():
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        submodule, attribute = table[name]
        value = getattr(importlib.import_module(f".{submodule}", package), attribute)
        setattr(module, name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(module)) | set(where()))

    return __getattr__, __dir__
