"""Every shell block of the tutorials and how-to guides runs as written, in order, in a fresh folder, on the simulator.

A fenced ```bash or ```console block is executed line by line (`lbr …` and `python …` only; `$ ` prompts and `#`
comments are ignored, a trailing backslash continues the line) and each command must exit 0. An `lbr` line runs the
`lbr` console script's entry point (`lbrcli.app.main`) in the test's process, in the page's folder — the same code
and exit code as the script, without a new interpreter and its imports for every line; a `python` line runs in its
own process. An HTML comment on the line before a block changes that:

- `<!-- robot-only -->`: needs the real robot (or hardware, or another program): never run; every `lbr` command in it
  must name an existing command and only options that command has (so a renamed option fails here);
- `<!-- not-run: REASON -->`: a reference listing with placeholders (FILE.csv), checked the same way;
- `<!-- slow -->`: runs only in the slow set (`python -m pytest -m slow`), e.g. a minute of planning;
- `<!-- expect-exit N -->`: runs, and every command in it must exit N (a check that is meant to fail);
- `<!-- same-as: PAGE.md -->`: the same commands as PAGE.md ran (to get its files): the page then runs in PAGE.md's
  folder right after it, this block skipped — and every command of the block must be one PAGE.md ran.
"""

from __future__ import annotations

import io
import os
import re
import shlex
import subprocess
import sys
from contextlib import redirect_stderr, redirect_stdout
from dataclasses import dataclass
from pathlib import Path

import pytest

from tests.helpers.shared import shared_swing_up

ROOT = Path(__file__).resolve().parents[2]
PAGES = sorted((ROOT / "docs" / "tutorials").glob("*.md")) + sorted((ROOT / "docs" / "guides").glob("*.md"))
_FENCE = re.compile(r"^```(bash|console|sh|shell)\s*$")
_MARK = re.compile(r"^<!-- (robot-only|not-run: .+|slow|expect-exit \d+|same-as: [\w.-]+\.md) -->$")


@dataclass(frozen=True)
class Block:
    page: str
    line: int  # 1-based line of the opening fence
    mark: str  # "", "robot-only", "not-run", "slow", "expect-exit", "same-as"
    expect: int  # exit code every command must give
    commands: tuple[tuple[str, ...], ...]
    after: str = ""  # same-as: the page whose commands these are


def blocks(path: Path) -> list[Block]:
    """The page's shell blocks in order, each with its marker and its commands split as a shell would."""
    lines = path.read_text().splitlines()
    found, i = [], 0
    while i < len(lines):
        if not _FENCE.match(lines[i]):
            i += 1
            continue
        prev = next((lines[k].strip() for k in range(i - 1, -1, -1) if lines[k].strip()), "")
        mark_match = _MARK.match(prev)
        mark = mark_match.group(1) if mark_match else ""
        start, body, i = i + 1, [], i + 1
        while i < len(lines) and lines[i].strip() != "```":
            body.append(lines[i])
            i += 1
        text = "\n".join(line[2:] if line.startswith("$ ") else line for line in body).replace("\\\n", " ")
        commands = tuple(
            tuple(argv) for argv in (shlex.split(line, comments=True) for line in text.splitlines()) if argv
        )
        expect = int(mark.split()[1]) if mark.startswith("expect-exit") else 0
        kind = mark.split(":")[0].split()[0] if mark else ""
        after = mark.split(": ", 1)[1] if kind == "same-as" else ""
        found.append(Block(path.name, start, kind, expect, commands, after))
        i += 1
    return found


def _lbr_command(argv: tuple[str, ...]):
    import typer.main

    from lbrcli.app import app

    command, rest = typer.main.get_command(app), list(argv[1:])
    while hasattr(command, "commands"):
        if rest and rest[0].startswith("-"):  # the group's own options (lbr --version)
            break
        assert rest and rest[0] in command.commands, f"`{' '.join(argv)}`: no command of that name"
        command = command.commands[rest.pop(0)]
    return command, rest


def check_syntax(argv: tuple[str, ...], where: str) -> None:
    """An `lbr` line names an existing command and only its options; a `python` line an existing script."""
    if argv[0] == "lbr":
        command, rest = _lbr_command(argv)
        names = {opt for p in command.params for opt in (*p.opts, *p.secondary_opts)} | {"--help", "-h"}
        for token in rest[: rest.index("--")] if "--" in rest else rest:
            if token.startswith("-") and not re.fullmatch(r"-[\d.]+(deg|rad)?", token):
                assert token.split("=")[0] in names, f"{where}: `{' '.join(argv)}`: {token} is not an option of it"
    elif argv[0] == "python" and len(argv) > 1 and argv[1].endswith(".py"):
        assert (ROOT / argv[1]).exists() or not argv[1].startswith("examples/"), f"{where}: no {argv[1]}"


def prerequisite(path: Path) -> str:
    """The page whose folder this page continues in (its `same-as` blocks), or ""."""
    afters = {b.after for b in blocks(path) if b.mark == "same-as"}
    assert len(afters) <= 1, f"{path.name}: same-as names more than one page"
    return afters.pop() if afters else ""


def chains() -> list[list[Path]]:
    """Pages in the order the tests run them: each page without a prerequisite, followed by the pages continuing it."""
    by_name = {p.name: p for p in PAGES}
    out = []
    for page in PAGES:
        if not prerequisite(page):
            chain, k = [page], 0
            while k < len(chain):
                chain += [p for p in PAGES if prerequisite(p) == chain[k].name]
                k += 1
            out.append(chain)
    assert sorted(p for c in out for p in c) == sorted(by_name.values()), "a same-as names a page that is not run"
    return out


def run_lbr(argv: tuple[str, ...], cwd: Path) -> tuple[int, str]:
    """(exit code, stderr) of `lbr ARGS` run by the console script's entry point in this process, in ``cwd``."""
    from lbrcli.app import main

    err, here = io.StringIO(), os.getcwd()
    os.chdir(cwd)
    try:
        with redirect_stdout(io.StringIO()), redirect_stderr(err):
            main(list(argv[1:]))
        code = 0
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 0 if exc.code is None else 1
    finally:
        os.chdir(here)
    return code, err.getvalue()


def run_python(argv: tuple[str, ...], cwd: Path) -> tuple[int, str]:
    """(exit code, stderr) of `python ARGS` in its own process, in ``cwd``."""
    res = subprocess.run([sys.executable, *argv[1:]], cwd=cwd, capture_output=True, text=True, timeout=300)
    return res.returncode, res.stderr


def run_page(path: Path, tmp: Path, with_slow: bool, ran_before: list[tuple[str, ...]]) -> list[tuple[str, ...]]:
    """Run the page's blocks in order in ``tmp``; the commands run (appended to ``ran_before``)."""
    if not (tmp / "examples").exists():
        (tmp / "examples").symlink_to(ROOT / "examples")
    ran = ran_before
    for block in blocks(path):
        where = f"{block.page}:{block.line}"
        for argv in block.commands:
            if block.mark in ("robot-only", "not-run") or (block.mark == "slow" and not with_slow):
                check_syntax(argv, where)
                continue
            if block.mark == "same-as":
                assert argv in ran, f"{where}: `{' '.join(argv)}` is not a command {block.after} ran"
                continue
            assert argv[0] in ("lbr", "python"), f"{where}: `{argv[0]}` is not run by this test: mark the block"
            check_syntax(argv, where)
            code, stderr = (run_lbr if argv[0] == "lbr" else run_python)(argv, tmp)
            assert code == block.expect, (
                f"{where}: `{' '.join(argv)}` exited {code}, the page expects {block.expect}\n{stderr[-3000:]}"
            )
            ran.append(argv)
    assert not [p.name for p in tmp.iterdir() if ".part" in p.name], "a temporary output was left behind"
    return ran


@pytest.mark.heavy
@pytest.mark.parametrize("chain", chains(), ids=lambda c: "+".join(p.name for p in c))
def test_pages_run_as_written(chain, tmp_path, tmp_path_factory, monkeypatch):
    # a fast swing-up the planner's tests plan with the very same request (tests/planners/test_swingup_fast.py) is
    # planned once per run: the command still parses, writes and checks it; only the optimisation is not run twice
    monkeypatch.setattr("planners.swingup.plan_swing_up", shared_swing_up(tmp_path_factory))
    ran: list[tuple[str, ...]] = []
    for page in chain:
        run_page(page, tmp_path, with_slow=False, ran_before=ran)


@pytest.mark.slow
@pytest.mark.parametrize(
    "chain",
    [c for c in chains() if any(b.mark == "slow" for p in c for b in blocks(p))],
    ids=lambda c: "+".join(p.name for p in c),
)
def test_pages_run_as_written_with_their_slow_blocks(chain, tmp_path):
    ran: list[tuple[str, ...]] = []
    for page in chain:
        run_page(page, tmp_path, with_slow=True, ran_before=ran)


def test_tutorials_run_commands():
    """The tutorials are executed, not only parsed: each runs commands outside the slow set."""
    for page in sorted((ROOT / "docs" / "tutorials").glob("*.md")):
        runnable = [c for b in blocks(page) if b.mark in ("", "expect-exit") for c in b.commands]
        assert runnable, page.name


@pytest.mark.heavy
def test_the_syntax_check_catches_a_renamed_option():
    check_syntax(("lbr", "plan", "anti-sway", "--length", "0.25", "-o", "x.csv"), "here")
    with pytest.raises(AssertionError, match="--lenght is not an option"):
        check_syntax(("lbr", "plan", "anti-sway", "--lenght", "0.25"), "here")
    with pytest.raises(AssertionError, match="no command"):
        check_syntax(("lbr", "plan", "anti-swing"), "here")
