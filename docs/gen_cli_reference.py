"""Write docs/reference/cli.md from the `lbr` Typer app itself: every command, its help, arguments and options.

`python docs/gen_cli_reference.py` regenerates the page; `--check` exits 1 when the committed page differs from what
the app gives (tests/docs/test_cli_reference.py runs the same comparison in CI). Never edit the page by hand.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

PAGE = Path(__file__).resolve().parent / "reference" / "cli.md"
REGENERATE = "python docs/gen_cli_reference.py"

INTRO = f"""# Command reference

Generated from the `lbr` command-line app by `{REGENERATE}` — do not edit by hand; a test fails when this page
and the app differ. Every command also prints this with `--help`. Conventions shared by all commands (exit codes,
`--json`, outputs written under a temporary name) are in [Errors, inputs and outputs](../guides/errors-and-outputs.md);
file columns and units in [File formats](file-formats.md).
"""


def _root_command():
    import typer.main

    from lbrcli.app import app

    return typer.main.get_command(app)


def commands(group=None, path: tuple[str, ...] = ("lbr",)):
    """(path, click command) of every leaf command, depth first, alphabetical; groups are walked, not returned."""
    group = _root_command() if group is None else group
    for name, sub in sorted(group.commands.items()):
        if getattr(sub, "hidden", False):
            continue
        if hasattr(sub, "commands"):
            yield from commands(sub, (*path, name))
        else:
            yield (*path, name), sub


def _plain(text: str) -> str:
    """Typer's rich-markup escapes removed, then Markdown-safe: no HTML, no emphasis, no table breaks."""
    text = text.replace("\\[", "[")
    text = text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
    return re.sub(r"([*_|`\[\]])", r"\\\1", text)


def _help_paragraphs(help_text: str) -> str:
    # click's \b marks a paragraph not to rewrap; a paragraph's lines are joined as the terminal would
    paragraphs = [p.replace("\b\n", "").strip() for p in re.split(r"\n\s*\n", help_text or "")]
    return "\n\n".join(" ".join(line.strip() for line in p.splitlines()) for p in paragraphs if p)


def _section(path: tuple[str, ...], command) -> str:
    ctx = command.make_context(path[-1], [], resilient_parsing=True)
    ctx.info_name = " ".join(path)
    usage = " ".join([" ".join(path), *command.collect_usage_pieces(ctx)])
    out = [f"## `{' '.join(path)}`\n", f"```\n{usage}\n```\n", _plain(_help_paragraphs(command.help)) + "\n"]
    rows = {"Arguments": [], "Options": []}
    for param in command.params:
        if getattr(param, "hidden", False):
            continue
        record = param.get_help_record(ctx)
        if record is None:  # click gives arguments no help record; Typer's do, but be safe
            record = (param.human_readable_name, getattr(param, "help", "") or "")
        kind = "Options" if param.param_type_name == "option" else "Arguments"
        names, help_text = record
        rows[kind].append(f"| `{names.replace('|', '¦')}` | {_plain(' '.join(help_text.split()))} |")
    for kind, lines in rows.items():
        if lines:
            out.append(f"\n**{kind}**\n\n| name | description |\n|---|---|\n" + "\n".join(lines) + "\n")
    return "\n".join(out)


def render() -> str:
    """The page's Markdown, from the app as it is now."""
    root = _root_command()
    parts = [INTRO, f"\n{_plain(_help_paragraphs(root.help))}\n"]
    parts.append("\n| command | what it does |\n|---|---|\n")
    sections = []
    for path, command in commands(root):
        name = " ".join(path)
        anchor = re.sub(r"[^a-z0-9]+", "-", name.lower()).strip("-")
        parts.append(f"| [`{name}`](#{anchor}) | {_plain(command.get_short_help_str(limit=120))} |\n")
        sections.append(_section(path, command))
    return "".join(parts) + "\n" + "\n".join(sections)


def main(argv: list[str]) -> int:
    text = render()
    if "--check" in argv:
        if not PAGE.exists() or PAGE.read_text() != text:
            print(f"{PAGE.relative_to(PAGE.parents[2])} is stale: run {REGENERATE}", file=sys.stderr)
            return 1
        return 0
    PAGE.parent.mkdir(parents=True, exist_ok=True)
    PAGE.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
