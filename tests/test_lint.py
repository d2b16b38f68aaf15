"""The lint step of CI, inside the suite (CI runs one test command): ruff with the project's configuration
(pyproject.toml, [tool.ruff]) finds nothing, and every file is as `ruff format` writes it."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _ruff() -> str:
    ruff = shutil.which("ruff") or str(Path(sys.executable).with_name("ruff"))
    if not Path(ruff).exists():
        pytest.skip("ruff is not installed (pip install -e .[test] installs it)")
    return ruff


def test_ruff_finds_nothing():
    p = subprocess.run(
        [_ruff(), "check", "--output-format", "concise", "."], cwd=ROOT, capture_output=True, text=True, timeout=300
    )
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-1000:]


def test_every_file_is_formatted():
    p = subprocess.run([_ruff(), "format", "--check", "."], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, "run `ruff format .`:\n" + p.stdout[-3000:] + p.stderr[-1000:]
