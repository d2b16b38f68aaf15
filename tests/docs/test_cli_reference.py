"""The command reference is generated from the Typer app and committed: it must be what the app gives now."""

import runpy
from pathlib import Path
from types import SimpleNamespace

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def gen() -> SimpleNamespace:
    """The generator, and the page it renders now (rendered once for both tests)."""
    module = SimpleNamespace(
        **runpy.run_path(str(ROOT / "docs" / "gen_cli_reference.py"), run_name="gen_cli_reference")
    )
    module.text = module.render()
    return module


@pytest.mark.heavy
def test_committed_reference_is_what_the_app_gives(gen):
    assert gen.PAGE.read_text() == gen.text, f"docs/reference/cli.md is stale: run {gen.REGENERATE}"


def test_every_command_and_option_is_on_the_page(gen):
    text = gen.text
    commands = list(gen.commands())
    assert len(commands) >= 20
    for path, command in commands:
        assert f"## `{' '.join(path)}`" in text, path
        for param in command.params:
            if param.param_type_name == "option" and not getattr(param, "hidden", False):
                for opt in param.opts:
                    assert opt in text, (path, opt)
