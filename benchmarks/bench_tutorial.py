"""A newcomer's first tutorial from a fresh clone, timed: clone, the install line the tutorial gives, then every
block of docs/tutorials/first-anti-sway.md as written (plan → check → execute on the simulator → compare).

Goal (issue #38): a planned, checked and simulated anti-sway move in ≤ 10 minutes including the install. The
install uses pip's cache as a second install on a lab PC would; ``--cold`` (``python benchmarks/bench_tutorial.py
--cold``) passes ``--no-cache-dir`` to measure a first download as well.

    python benchmarks/run_all.py tutorial     # figures → benchmarks/results/tutorial.json
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "tutorials" / "first-anti-sway.md"
GOAL_S = 600.0  # [s] ten minutes
_FENCE = re.compile(r"^```(bash|console|sh|shell)\s*$")


def page_commands(path: Path) -> list[tuple[str, int]]:
    """(shell line, the exit code it must give) of the page's runnable blocks, in order: blocks marked robot-only or
    not-run skipped, ``expect-exit N`` blocks must exit N (a check shown failing)."""
    lines, out, i = path.read_text().splitlines(), [], 0
    while i < len(lines):
        if not _FENCE.match(lines[i]):
            i += 1
            continue
        prev = next((lines[k].strip() for k in range(i - 1, -1, -1) if lines[k].strip()), "")
        skip = prev.startswith("<!-- robot-only") or prev.startswith("<!-- not-run")
        expect = int(m.group(1)) if (m := re.match(r"<!-- expect-exit (\d+) -->", prev)) else 0
        i += 1
        text = []
        while i < len(lines) and lines[i].strip() != "```":
            text.append(lines[i])
            i += 1
        i += 1
        if skip:
            continue
        joined = "\n".join(text).replace("\\\n", " ")
        for line in joined.splitlines():
            line = line.strip().removeprefix("$ ").strip()
            if line and not line.startswith("#"):
                out.append((line, expect))
    return out


def _install_line(path: Path) -> str:
    """The page's install command (its first pip install line)."""
    for line in path.read_text().splitlines():
        if "pip install" in line:
            return line.strip()
    raise ValueError(f"{path}: no install line")


def run(quick: bool = False, cold: bool = False) -> list[tuple[str, float, str]]:
    with tempfile.TemporaryDirectory() as tmp:
        clone = Path(tmp) / "lbr"
        t0 = time.perf_counter()
        subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
        t_clone = time.perf_counter() - t0
        install = _install_line(PAGE) + (" --no-cache-dir" if cold else "") + " -q"
        t1 = time.perf_counter()
        subprocess.run(["bash", "-c", install], cwd=clone, check=True)
        t_install = time.perf_counter() - t1
        env = {
            **os.environ,
            "PATH": f"{clone / '.venv' / 'bin'}{os.pathsep}{os.environ['PATH']}",
            "VIRTUAL_ENV": str(clone / ".venv"),
        }
        env.pop("PYTHONPATH", None)
        work = Path(tmp) / "work"
        work.mkdir()
        commands = page_commands(PAGE)
        failed = 0
        t2 = time.perf_counter()
        for line, expect in commands:
            proc = subprocess.run(["bash", "-c", line], cwd=work, env=env, capture_output=True, text=True)
            if proc.returncode != expect:
                failed += 1
                print(
                    f"  failed ({proc.returncode}): {shlex.split(line)[:3]} {proc.stderr.strip()[-200:]}",
                    file=sys.stderr,
                )
        t_steps = time.perf_counter() - t2
    total = t_clone + t_install + t_steps
    return [
        ("clone", t_clone, "s"),
        ("install (the tutorial's pip line" + (", no cache)" if cold else ", pip's cache)"), t_install, "s"),
        ("tutorial commands run", float(len(commands)), ""),
        ("tutorial commands that did not exit as the page says", float(failed), ""),
        ("tutorial steps (plan, check, execute, compare)", t_steps, "s"),
        ("fresh clone to a compared simulated move", total, "s"),
        ("goal met (total ≤ 10 min, every command as the page says)", float(total <= GOAL_S and failed == 0), ""),
    ]


if __name__ == "__main__":
    for name, value, unit in run(cold="--cold" in sys.argv):
        print(f"  {name:<55} {value:>10.4g} {unit}")
