"""MkDocs hooks: pages quote the code and the benchmarks' own files, never copies of them.

- ``<!-- lbr:columns MODULE.NAME -->`` becomes the tuple of column names ``MODULE.NAME`` holds (a CSV header),
  ``<!-- lbr:value MODULE.NAME -->`` its value, ``<!-- lbr:docstring MODULE -->`` the module's docstring in a text
  block (wire formats are documented there, next to the code that packs them).
- ``benchmarks/results/*.md`` (written by the benchmarks themselves) are published as ``explanations/results/*.md``.

An unknown name fails the build (a page would otherwise quote something that no longer exists).
"""

from __future__ import annotations

import importlib
import inspect
import re
from pathlib import Path

from mkdocs.structure.files import File

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
_MARKER = re.compile(r"<!-- lbr:(columns|value|docstring) ([A-Za-z0-9_.]+) -->")


def _resolve(dotted: str):
    module, _, name = dotted.rpartition(".")
    try:
        return getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError) as exc:
        raise ValueError(f"docs marker names {dotted}, which does not exist: {exc}") from exc


def expand(markdown: str) -> str:
    """The page with every ``lbr:`` marker replaced by what the code says."""

    def one(match: re.Match) -> str:
        kind, dotted = match.groups()
        if kind == "docstring":
            return "```text\n" + inspect.cleandoc(importlib.import_module(dotted).__doc__ or "") + "\n```"
        value = _resolve(dotted)
        if kind == "columns":
            return "`" + ",".join(value) + "`"
        return f"`{value}`"

    return _MARKER.sub(one, markdown)


def on_files(files, config):
    for path in sorted(RESULTS.glob("*.md")):
        files.append(File.generated(config, f"explanations/results/{path.name}", abs_src_path=str(path)))
    return files


def on_page_markdown(markdown, page, config, files):
    return expand(markdown)
