"""The FRI stack is a library: importing every module of ``lbrcli.fri`` (simulator included) pulls in neither the
CLI, the planners, the tracking nor the lab package; its public names exist; no module grows past ~400 lines."""

from __future__ import annotations

import pytest

import json
import subprocess
import sys
from pathlib import Path

import lbrcli.fri

FRI_DIR = Path(lbrcli.fri.__file__).parent
FORBIDDEN = ("planners", "tracking", "typer", "matplotlib", "lbrcli.commands", "lbrcli.lab", "lbrcli.control",
             "lbrcli.bridge", "lbrcli.plants", "lbrcli.app", "lbrcli.demo")  # fmt: skip


@pytest.mark.heavy
def test_importing_every_fri_module_loads_no_planner_cli_or_lab_module():
    probe = (
        "import importlib, json, pkgutil, sys\n"
        "import lbrcli.fri as f\n"
        "for m in pkgutil.walk_packages(f.__path__, 'lbrcli.fri.'):\n"
        "    importlib.import_module(m.name)\n"
        "print(json.dumps(sorted(sys.modules)))\n"
    )
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout
    loaded = json.loads(out.strip().splitlines()[-1])
    assert any(m.startswith("lbrcli.fri.sim") for m in loaded)  # the walk reached the simulator
    offending = [m for m in loaded if any(m == f or m.startswith(f + ".") for f in FORBIDDEN)]
    assert offending == []


def test_every_public_name_exists():
    missing = [n for n in lbrcli.fri.__all__ if not hasattr(lbrcli.fri, n)]
    assert missing == [] and len(lbrcli.fri.__all__) == len(set(lbrcli.fri.__all__))


def test_no_fri_module_is_over_about_400_lines():
    sizes = {str(p.relative_to(FRI_DIR)): len(p.read_text().splitlines()) for p in FRI_DIR.rglob("*.py")}
    long = {name: n for name, n in sizes.items() if n > 420}
    assert len(sizes) > 20 and long == {}
    assert long == {}
