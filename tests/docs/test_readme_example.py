"""The README's user loop runs as written on a fresh folder and ends with model and experiment agreeing.

Test-only changes, all named here: `lbr execute` gets `--port 0` (other sessions on a shared machine may hold
30200), `--realtime` and `--sim-lenient` (the docs' advice for a busy PC: the test machine runs other suites meanwhile), and
`lbr track film` renders a 640x360 video (quicker; the tracker's accuracy at full size is benchmarked).
"""

import json
import pytest
import shlex
import subprocess
import sys
from pathlib import Path
from lbrcli.fri.realtime import permitted

README = Path(__file__).resolve().parents[2] / "README.md"


def example_commands() -> list[list[str]]:
    text = README.read_text()
    block = text.split("## The user's loop", 1)[1].split("```bash", 1)[1].split("```", 1)[0]
    commands = []
    for line in block.splitlines():
        line = line.split("#", 1)[0].strip()
        if line:
            commands.append(shlex.split(line))
    return commands


REALTIME = ["--realtime"] if permitted() else []  # refused with exit 2 where the system does not grant it


def _run_chain(chain: list[list[str]], cwd: Path) -> dict:
    figures = {}
    for argv in chain:
        assert argv[0] == "lbr"
        args = argv[1:]
        if args[0] == "execute":
            args += ["--port", "0", *REALTIME, "--sim-lenient"]
        if args[:2] == ["track", "film"]:
            args += ["--size", "640x360"]
        res = subprocess.run(
            [sys.executable, "-m", "lbrcli", *args, "--json"], cwd=cwd, capture_output=True, text=True, timeout=300
        )
        assert res.returncode == 0, f"{' '.join(argv)}\n{res.stderr[-2000:]}"
        figures[" ".join(args[:2])] = json.loads(res.stdout)
    return figures


@pytest.mark.slow
def test_readme_example_session_runs_as_written(tmp_path):
    from concurrent.futures import ThreadPoolExecutor

    commands = example_commands()
    assert [c[:2] for c in commands][-3:] == [["lbr", "track"], ["lbr", "track"], ["lbr", "compare"]]
    # each `lbr plan` starts a chain that only uses its own files: the chains run side by side (in order inside)
    chains: list[list[list[str]]] = []
    for argv in commands:
        if argv[1] == "plan" or not chains:
            chains.append([])
        chains[-1].append(argv)
    with ThreadPoolExecutor(len(chains)) as pool:
        figures = {}
        for f in pool.map(lambda c: _run_chain(c, tmp_path), chains):
            figures.update(f)
    for name in ("swing.csv", "swing_run.csv", "pred.csv", "experiment.mp4", "track.csv", "check.mp4", "compare.png"):
        assert (tmp_path / name).stat().st_size > 1000, name
    cmp = figures["compare pred.csv"]
    # the filmed simulated ball is the plan's ball: same sign, sub-degree agreement once aligned
    assert cmp["rms_deg"] < 2.0 and cmp["overlap_s"] > 1.0
    assert not [p.name for p in tmp_path.iterdir() if ".part" in p.name]  # no temporary file left behind
