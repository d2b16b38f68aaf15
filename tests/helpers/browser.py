"""The view's browser tests skip, saying what is missing, without Chromium or playwright."""

from __future__ import annotations

import pytest

from lbrcli.view.testing import chromium_path


def require_browser() -> str:
    """The Chromium executable, or skip the test saying what is missing."""
    path = chromium_path()
    if path is None:
        pytest.skip("no Chromium (apt-get install chromium; .ci/run installs it)")
    pytest.importorskip("playwright.sync_api", reason="playwright is not installed (pip install -e .[test])")
    return path
