"""The command reference is generated from the Typer app and committed: it must be what the app gives now."""

import runpy
from pathlib import Path
from types import SimpleNamespace

ROOT = Path(__file__).resolve().parents[2]


def _generator() -> SimpleNamespace:
    return SimpleNamespace(**runpy.run_path(str(ROOT / "docs" / "gen_cli_reference.py"), run_name="gen_cli_reference"))


def test_committed_reference_is_what_the_app_gives():
    gen = _generator()
    assert gen.PAGE.read_text() == gen.render(), f"docs/reference/cli.md is stale: run {gen.REGENERATE}"


def test_every_command_and_option_is_on_the_page():
    gen = _generator()
    text = gen.render()
    commands = list(gen.commands())
    assert len(commands) >= 20
    for path, command in commands:
        assert f"## `{' '.join(path)}`" in text, path
        for param in command.params:
            if param.param_type_name == "option" and not getattr(param, "hidden", False):
                for opt in param.opts:
                    assert opt in text, (path, opt)
