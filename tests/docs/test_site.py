"""The docs site builds strictly (broken links, missing references, warnings fail), and its API reference covers
every public name: each name in the `__all__` of every package and module of the library appears in the built
reference (mkdocstrings' inventory) and has a docstring."""

import os
import subprocess
import sys
import zlib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
LIBRARY = ("lbrcli.fri", "lbrcli.bridge", "lbrcli.plants", "lbrcli.control", "planners", "trajectories", "tracking")


@pytest.fixture(scope="session")
def site(tmp_path_factory) -> Path:
    """The site, built once for every test that looks at it."""
    out = tmp_path_factory.mktemp("docs") / "site"
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    res = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
    )
    assert res.returncode == 0, "mkdocs build --strict failed:\n" + res.stderr[-4000:]
    return out


def _inventory(site: Path) -> set[str]:
    """Object names of the site's objects.inv (Sphinx inventory v2: four header lines, then zlib)."""
    data = (site / "objects.inv").read_bytes()
    body = data.split(b"\n", 4)[4]
    return {line.split(" ", 1)[0] for line in zlib.decompress(body).decode().splitlines() if line.strip()}


def _exports() -> dict[str, list[str]]:
    """{module path: its __all__} for every package and module of the library that declares one (griffe, static)."""
    import griffe

    loader = griffe.GriffeLoader(search_paths=[str(ROOT)])
    for top in {name.split(".")[0] for name in LIBRARY}:
        loader.load(top)
    found = {}

    def walk(module):
        if any(module.path == r or module.path.startswith(r + ".") for r in LIBRARY) and module.exports is not None:
            found[module.path] = [e if isinstance(e, str) else e.name for e in module.exports]
        for sub in module.modules.values():
            walk(sub)

    for top in {name.split(".")[0] for name in LIBRARY}:
        walk(loader.modules_collection[top])
    return found, loader


@pytest.mark.heavy
def test_site_builds_strictly_and_covers_the_api(site):
    """One build (it takes most of this test's time), four checks: it built, every public name is in the API
    reference with a docstring, and the pages quote the code and the benchmarks' files rather than copies of them."""
    assert (site / "index.html").exists() and (site / "reference" / "cli" / "index.html").exists()
    _every_public_name_is_in_the_api_reference_with_a_docstring(site)
    _pages_quote_the_code_not_copies(site)
    _pages_quote_the_benchmarks_files(site)


def _every_public_name_is_in_the_api_reference_with_a_docstring(site):
    exports, loader = _exports()
    assert {"lbrcli.fri", "lbrcli.bridge", "planners", "planners.feedback", "trajectories", "tracking"} <= set(exports)
    inventory = _inventory(site)
    missing, undocumented = [], []
    for module, names in exports.items():
        for name in names:
            if f"{module}.{name}" not in inventory:
                missing.append(f"{module}.{name}")
            obj = loader.modules_collection[module].members.get(name)
            doc = obj.docstring if obj is not None else None
            if doc is None or not doc.value.strip():
                undocumented.append(f"{module}.{name}")
    total = sum(len(n) for n in exports.values())
    assert not missing, f"{len(missing)} of {total} public names not in the API reference: {missing[:20]}"
    assert not undocumented, f"{len(undocumented)} of {total} public names without a docstring: {undocumented[:20]}"


def _pages_quote_the_code_not_copies(site):
    """The file-formats page's column lists come from the constants (hooks.py); a marker left over means none was."""
    from trajectories.csvio import JOINT_COLUMNS

    page = (site / "reference" / "file-formats" / "index.html").read_text()
    assert ",".join(JOINT_COLUMNS) in page and "lbr:columns" not in page


def _pages_quote_the_benchmarks_files(site):
    """The view guide's figures are the values in benchmarks/results/view_export.json (hooks.py), no marker left."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("hooks", ROOT / "docs" / "hooks.py")
    hooks = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(hooks)
    page = (site / "guides" / "view-and-export" / "index.html").read_text()
    assert hooks.figure("view_export.view_open_s") in page and "lbr:bench" not in page
