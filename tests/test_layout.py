"""The tests mirror the package layout: tests/<package>/<subpackage>/test_<module>[_<aspect>].py tests the module
<package>/<subpackage>/<module>.py (or the subpackage <module>/, or — named after its own package — the package's
public face); shared test code lives in tests/helpers, not in test modules."""

from __future__ import annotations

import pytest

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TESTS = ROOT / "tests"

# Cross-cutting suites that test no single module (the only test modules allowed outside the mirror):
ALLOWED = {
    "tests/test_layout.py",  # this file: the tests' own layout
    "tests/test_lint.py",  # ruff format and lint over the whole tree
    "tests/test_function_length.py",  # function and command-body lengths across the CLI and the FRI session code
    "tests/docs",  # the docs pages, tutorials, CLI reference and README examples, run as written
    "tests/examples",  # the examples/ scripts, run as a user runs them
    "tests/benchmarks",  # the benchmarks' figures page
}


def _allowed(rel: str) -> bool:
    return any(rel == a or rel.startswith(a + "/") for a in ALLOWED)


def _mirrored(path: Path) -> bool:
    """Whether test file ``path`` (tests/a/b/test_x.py) names a module of package a/b: x, x_<aspect>, or the
    package's own name b[_<aspect>]."""
    package = ROOT / path.parent.relative_to(TESTS)
    if not (package / "__init__.py").is_file():
        return False
    names = {p.stem for p in package.glob("*.py") if p.stem != "__init__"}
    names |= {p.name for p in package.iterdir() if (p / "__init__.py").is_file()}
    names.add(package.name)
    stem = path.stem.removeprefix("test_")
    return any(stem == n or stem.startswith(n + "_") for n in names)


def test_every_test_module_mirrors_a_package_module():
    """A test module in a place that mirrors no module fails here (move it, or add a cross-cutting suite to
    ALLOWED with a comment)."""
    stray = []
    for path in sorted(TESTS.rglob("test_*.py")):
        rel = path.relative_to(ROOT).as_posix()
        if not _allowed(rel) and not _mirrored(path):
            stray.append(rel)
    assert not stray, f"test modules that mirror no package module: {stray}"


def test_the_check_refuses_a_stray_place():
    """The rule itself: flat files and invented names are refused; modules, subpackages and packages accepted."""
    assert _mirrored(TESTS / "lbrcli" / "fri" / "test_codec.py")
    assert _mirrored(TESTS / "lbrcli" / "fri" / "sim" / "test_simulator_close.py")
    assert _mirrored(TESTS / "lbrcli" / "test_fri.py")  # the subpackage lbrcli/fri
    assert _mirrored(TESTS / "lbrcli" / "plants" / "test_plants.py")  # the package's public face
    assert not _mirrored(TESTS / "lbrcli" / "test_codec.py")  # codec is in lbrcli/fri/, not lbrcli/
    assert not _mirrored(TESTS / "lbrcli" / "commands" / "test_codec.py")
    assert not _mirrored(TESTS / "lbrcli" / "nowhere" / "test_codec.py")
    assert not _mirrored(TESTS / "planners" / "test_plannersx.py")


@pytest.mark.heavy
def test_every_test_folder_is_a_package_and_no_test_imports_another():
    """Every folder under tests/ has an __init__.py (test modules of one name in two folders stay apart:
    tests.lbrcli.commands.test_compare and tests.tracking.test_compare), and test modules import shared code from
    tests.helpers or the library — never another test module, never through sys.path."""
    folders = [d for d in TESTS.rglob("*") if d.is_dir() and d.name != "__pycache__"]
    assert [d for d in folders if not (d / "__init__.py").is_file()] == []
    bad = []
    for path in TESTS.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module:
                last = node.module.split(".")[-1]
                if last.startswith("test_") or last == "conftest":
                    bad.append(f"{path.relative_to(ROOT)}: from {node.module}")
            elif isinstance(node, ast.Import):
                bad += [f"{path.relative_to(ROOT)}: import {a.name}" for a in node.names if a.name.startswith("test_")]
    assert bad == []
