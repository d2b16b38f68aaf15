"""KUKA's FRI client SDK 2.7 example applications, built from lbr-stack/fri's copy of the SDK when a compiler is here.

No KUKA code is committed in this repository: the source is a checkout (or bare git directory) of
https://github.com/lbr-stack/fri named by the environment variable ``LBR_KUKA_FRI_SRC``; its ``fri-2.7`` branch is
built with cmake and g++ into ``~/.cache/lbr-bench/kuka-fri-2.7`` (``XDG_CACHE_HOME`` respected), once; later calls
use the cached executables. lbr-stack's CMakeLists builds every example but the Cartesian overlay; the build adds
it the same way. ``kuka_app(name)`` returns the executable's path or ``(None, why)``. Used by
tests/lbrcli/fri/sim/test_simulator_kuka27.py and benchmarks/bench_fri_cartesian.py.
"""

from __future__ import annotations

import fcntl
import os
import shutil
import subprocess
from pathlib import Path

BUILD_DIR = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "lbr-bench" / "kuka-fri-2.7"
APPS = ("LBRCartesianOverlay", "TransformationProvider", "SimulatedTransformationProvider", "LBRJointSineOverlay")
_EXTRA = "\nif (BUILD_FRI_APPS)\n    build_fri_example(LBRCartesianOverlay)\nendif()\n"


def _exe(name: str) -> Path:
    return BUILD_DIR / "build" / f"{name}App"


def build(src: str | None = None) -> str | None:
    """Build the 2.7 examples of ``APPS``; None when done (or cached), else why not. One build at a time (a lock
    file: test workers in parallel wait for the first one's build)."""
    if all(_exe(a).exists() for a in APPS):
        return None
    BUILD_DIR.parent.mkdir(parents=True, exist_ok=True)
    with open(BUILD_DIR.parent / "kuka-fri-2.7.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        return None if all(_exe(a).exists() for a in APPS) else _build(src)


def _build(src: str | None) -> str | None:
    src = src or os.environ.get("LBR_KUKA_FRI_SRC")
    if not src:
        return "no KUKA SDK source: set LBR_KUKA_FRI_SRC to a checkout of github.com/lbr-stack/fri"
    missing = [t for t in ("cmake", "g++", "git") if shutil.which(t) is None]
    if missing:
        return f"cannot build KUKA's SDK 2.7 examples: {', '.join(missing)} not found"
    tree = BUILD_DIR / "src"
    shutil.rmtree(BUILD_DIR, ignore_errors=True)
    tree.mkdir(parents=True)
    git = subprocess.run(f"git -C '{src}' archive fri-2.7 | tar -x -C '{tree}'", shell=True, capture_output=True,
                         text=True)  # fmt: skip
    if git.returncode != 0 or not (tree / "CMakeLists.txt").exists():
        return f"no fri-2.7 branch in {src}: {git.stderr.strip()[-200:]}"
    with open(tree / "CMakeLists.txt", "a") as f:
        f.write(_EXTRA)
    steps = [["cmake", "-S", str(tree), "-B", str(BUILD_DIR / "build"), "-DBUILD_FRI_APPS=ON",
              "-DCMAKE_BUILD_TYPE=Release"],
             ["cmake", "--build", str(BUILD_DIR / "build"), "-j2", "--target", *[f"{a}App" for a in APPS]]]  # fmt: skip
    for step in steps:
        r = subprocess.run(step, capture_output=True, text=True)
        if r.returncode != 0:
            return f"building KUKA's SDK 2.7 examples failed: {(r.stderr or r.stdout).strip().splitlines()[-1:]}"
    return None if all(_exe(a).exists() for a in APPS) else "no executables built"


def kuka_app(name: str) -> tuple[str | None, str]:
    """(path of KUKA's ``name``App from SDK 2.7, how) or (None, why not)."""
    why = build()
    if why is not None:
        return None, why
    return str(_exe(name)), f"built in {BUILD_DIR}"


if __name__ == "__main__":  # build once: LBR_KUKA_FRI_SRC=... python -m lbrcli.fri.testing.kuka_sdk
    print(build() or f"built in {BUILD_DIR}")
