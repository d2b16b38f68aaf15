"""The click that Typer runs on: vendored as ``typer._click`` by Typer ≥ 0.17, the ``click`` package before."""

from __future__ import annotations


def click_exceptions():
    """The module holding ClickException, UsageError and NoArgsIsHelpError."""
    try:
        from typer._click import exceptions
    except ImportError:  # older Typer depends on click itself
        from click import exceptions
    return exceptions
