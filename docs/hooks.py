"""MkDocs hooks: pages quote the code and the benchmarks' own files, never copies of them.

- ``<!-- lbr:columns MODULE.NAME -->`` becomes the tuple of column names ``MODULE.NAME`` holds (a CSV header),
  ``<!-- lbr:value MODULE.NAME -->`` its value (``<!-- lbr:value MODULE.NAME unit=s -->``: a number in prose with
  its unit, a fraction with ``unit=%`` as a percentage — a parameter the page names, from the code that uses it),
  ``<!-- lbr:docstring MODULE -->`` the module's docstring in a text block (wire formats are documented there, next
  to the code that packs them). ``MODULE.CLASS.FIELD`` names a dataclass field's default.
- ``<!-- lbr:bench FILE.KEY.KEY… [OPTION …] -->`` becomes a measured figure, with its unit, from the results file a
  benchmark wrote: ``benchmarks/results/FILE.json`` (or ``docs/guides/results/FILE.json``). See :func:`figure`.
- ``benchmarks/results/*.md`` (written by the benchmarks themselves) are published as ``explanations/results/*.md``.

An unknown name, file or key fails the build (a page would otherwise quote something that no longer exists).
"""

from __future__ import annotations

import fnmatch
import importlib
import inspect
import json
import math
import re
import statistics
from pathlib import Path

from mkdocs.structure.files import File

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
RESULT_FOLDERS = (RESULTS, ROOT / "docs" / "guides" / "results")
_MARKER = re.compile(r"<!-- lbr:(columns|value|docstring) ([A-Za-z0-9_.]+)((?: +[a-z]+=[^\s]+)*) -->")
BENCH_MARKER = re.compile(r"<!-- lbr:bench ((?:[^\"\s>-]|\"[^\"]*\"|-(?!->))+)((?: +[a-z]+(?:=[^\s]+)?)*) -->")

# a key's unit from its last unit-like word (``p99_ms_median`` → ms); units as the pages write them
_KEY_UNITS = {
    "s": "s",
    "ms": "ms",
    "us": "µs",
    "deg": "°",
    "rad": "rad",
    "m": "m",
    "mm": "mm",
    "px": "px",
    "percent": "%",
    "mb": "MB",
    "fps": "frames/s",
}
_UNIT_ALIASES = {"deg": "°", "us": "µs", "-": "", "bool": "", "ratio": "×", "x": "×", "fraction": "", "share": ""}
# display-unit conversions: (stored, shown) → factor
_CONVERT = {
    ("s", "ms"): 1e3,
    ("s", "µs"): 1e6,
    ("ms", "µs"): 1e3,
    ("ms", "s"): 1e-3,
    ("µs", "ms"): 1e-3,
    ("m", "mm"): 1e3,
    ("mm", "m"): 1e-3,
    ("rad", "°"): 180 / math.pi,
    ("", "%"): 100.0,
    ("×", "%"): 100.0,
}
_NO_SPACE = ("°", "×")  # 0.17°, 1.26× — every other unit after a space (10 %, 6.68 s)


class FigureError(ValueError):
    """A ``lbr:bench`` marker names a results file, key or option that does not exist."""


def _resolve(dotted: str):
    """``MODULE.NAME`` or ``MODULE.CLASS.NAME`` (a dataclass field's default)."""
    parts = dotted.split(".")
    for cut in range(len(parts) - 1, 0, -1):
        try:
            node = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        try:
            for name in parts[cut:]:
                node = getattr(node, name)
        except AttributeError as exc:
            raise ValueError(f"docs marker names {dotted}, which does not exist: {exc}") from exc
        return node
    raise ValueError(f"docs marker names {dotted}, which does not exist: no module")


def _path(spec: str) -> list[str]:
    """``FILE.key."key with. dots".0`` → its components."""
    parts, pos = [], 0
    for m in re.finditer(r'"([^"]*)"|([^."]+)|(\.)', spec):
        if m.start() != pos:
            raise FigureError(f"lbr:bench {spec}: cannot read the key path")
        pos = m.end()
        if m.group(3) is None:
            parts.append(m.group(1) if m.group(1) is not None else m.group(2))
    if pos != len(spec) or len(parts) < 2:
        raise FigureError(f"lbr:bench {spec}: expected FILE.KEY[.KEY…]")
    return parts


def _results_file(name: str) -> Path:
    found = [folder / f"{name}.json" for folder in RESULT_FOLDERS if (folder / f"{name}.json").exists()]
    if len(found) != 1:
        where = " or ".join(str(f.relative_to(ROOT) if f.is_relative_to(ROOT) else f) for f in RESULT_FOLDERS)
        raise FigureError(
            f"lbr:bench: no results file {name}.json in {where}"
            if not found
            else f"lbr:bench: {name}.json is in more than one results folder"
        )
    return found[0]


def _child(node, key: str, spec: str):
    """One step down the results tree: a dict key, a list index, or a list element / figure named ``key``."""
    if isinstance(node, dict):
        if key in node:
            return node[key]
        if isinstance(node.get("figures"), list):  # run_all.save_results: figures by name
            node = node["figures"]
        else:
            raise FigureError(f"lbr:bench {spec}: no key {key!r} (there are: {', '.join(map(str, node))[:300]})")
    if isinstance(node, list):
        if re.fullmatch(r"\d+", key) and int(key) < len(node):
            return node[int(key)]
        named = [e for e in node if isinstance(e, dict) and key in (e.get("name"), e.get("key"), e.get("scenario"))]
        if len(named) == 1:
            return named[0]
        raise FigureError(f"lbr:bench {spec}: {'no' if not named else 'more than one'} element named {key!r}")
    raise FigureError(f"lbr:bench {spec}: {key!r} is below a value, not a table")


def _matching(node, pattern: str) -> list:
    """The children of ``node`` whose key or name matches the glob ``pattern`` (``*``: all of them)."""
    if isinstance(node, dict) and isinstance(node.get("figures"), list):
        node = node["figures"]
    if isinstance(node, dict):
        return [v for k, v in node.items() if fnmatch.fnmatchcase(str(k), pattern)]
    if isinstance(node, list):
        return [
            e
            for e in node
            if pattern == "*"
            or isinstance(e, dict)
            and any(
                isinstance(e.get(f), str) and fnmatch.fnmatchcase(e[f], pattern) for f in ("name", "key", "scenario")
            )
        ]
    return []


def _key_unit(key: str) -> str:
    words = key.lower().split("_")
    if len(words) >= 3 and words[-2:] == ["per", "s"]:
        return f"{words[-3]}/s"  # runs_per_s → runs/s
    if words[-2:] == ["m", "s"]:
        return "m/s"
    for word in reversed(words if len(words) > 1 else []):
        if word in _KEY_UNITS:
            return _KEY_UNITS[word]
    return ""


def number(value: float, digits: int | None = 3, whole: bool = True) -> str:
    """A measured value rounded for prose: ``digits`` significant digits (45,294.2 → 45,300), thousands separated,
    an exponent below 0.001 (5.28e-10); integers as they are (``whole=False``: a whole float rounded as any other,
    for a range whose other end is not whole)."""
    if isinstance(value, bool):
        return "yes" if value else "no"
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "—"
    if math.isinf(value):
        return "∞" if value > 0 else "−∞"
    if float(value).is_integer() and abs(value) < 1e15 and (whole or value == 0):
        return f"{int(value):,}".replace("-", "−")
    if digits is None:  # a parameter: as the code has it
        return f"{value:,.6g}".replace("-", "−")
    if value != 0 and abs(value) < 1e-3:
        mantissa, exp = f"{value:.{digits - 1}e}".split("e")
        return f"{mantissa.replace('-', '−')}e{int(exp)}"
    magnitude = math.floor(math.log10(abs(value))) if value else 0
    decimals = digits - 1 - magnitude  # negative: 45,294 → 45,300
    text = f"{round(value, decimals):,.{max(decimals, 0)}f}"
    return text.replace("-", "−")


def figure(spec: str, options: str = "") -> str:
    """The text of one ``<!-- lbr:bench SPEC OPTIONS -->`` marker.

    ``SPEC`` is ``FILE.KEY.KEY…``: ``FILE`` the results file's name without ``.json``, then keys down its tree — dict
    keys, list indices, or the ``name``/``key``/``scenario`` of a list's element; in the records `run_all.py` writes
    (``{"benchmark", "figures": [{"name", "value", "unit"}]}``) a figure by its name. A key with dots or spaces is
    quoted: ``antisway."anti-sway auto tol 0.1 dt 5 ms: moving time"``. The unit is the figure's own, or read from
    the key's last unit word (``p99_ms_median`` → ms, ``theta_rms_deg`` → °, ``runs_per_s`` → runs/s).

    ``OPTIONS``: ``unit=U`` shows the value in U (s/ms/µs, m/mm, rad/°, a fraction as %; ``unit=none`` shows none;
    another unit is only a label: the value is not converted; ``from=U`` names the stored unit where the key does
    not); ``digits=N`` significant digits (default 3);
    for a list of numbers (a list in the file, or ``*`` in the path) ``min``, ``max``, ``median``, ``sum``, ``count`` or
    ``range`` (``a–b``).
    """
    parts = _path(spec)
    path = _results_file(parts[0])
    nodes, spread = [json.loads(path.read_text())], False
    for key in parts[1:]:
        if "*" in key:  # every element (of a list, a table, a record's figures) whose name matches: a list of figures
            nodes = [c for n in nodes for c in _matching(n, key)]
            spread = True
        elif spread:  # below a ``*``: the elements that have the key
            nodes = [n[key] for n in nodes if isinstance(n, dict) and key in n]
        else:
            nodes = [_child(n, key, spec) for n in nodes]
    unit = _key_unit(parts[-1])
    if any(isinstance(n, dict) and "value" in n for n in nodes):
        unit = next(n.get("unit") or "" for n in nodes if isinstance(n, dict))
        nodes = [n["value"] if isinstance(n, dict) else n for n in nodes]
    if spread:
        nodes = [n for n in nodes if n is not None]
        if not nodes:
            raise FigureError(f"lbr:bench {spec}: no figure matches")
    node = nodes if spread else nodes[0]
    unit = _UNIT_ALIASES.get(unit, unit)
    return _formatted(node, unit, options, f"lbr:bench {spec}")


def _formatted(node, unit: str, options: str, where: str, digits: int | None = 3) -> str:
    """A number or a list of numbers in ``unit``, shown as ``options`` say (see :func:`figure`)."""
    opts = dict(o.split("=", 1) if "=" in o else (o, "") for o in options.split())
    unknown = set(opts) - {"unit", "from", "digits", "min", "max", "median", "range", "sum", "count"}
    if unknown:
        raise FigureError(f"{where}: unknown option {sorted(unknown)}")
    digits = int(opts["digits"]) if "digits" in opts else digits
    values = node if isinstance(node, list) else [node]
    if "count" not in opts and not all(v is None or isinstance(v, (int, float)) for v in values):
        raise FigureError(f"{where}: {str(node)[:80]!r} is not a number")
    aggregate = [a for a in ("min", "max", "median", "range", "sum", "count") if a in opts]
    if isinstance(node, list) != bool(aggregate) or len(aggregate) > 1:
        raise FigureError(f"{where}: a list needs one of min, max, median, range, sum, count (and a number none)")
    if aggregate == ["count"]:
        return number(len(node))
    unit = _UNIT_ALIASES.get(opts.get("from", unit), opts.get("from", unit))
    shown = opts.get("unit", unit)
    shown = "" if shown == "none" else _UNIT_ALIASES.get(shown, shown)
    factor = _CONVERT.get((unit, shown), 1.0) if shown != unit else 1.0
    nums = [v * factor if isinstance(v, (int, float)) and not isinstance(v, bool) else v for v in values]
    if aggregate == ["range"]:
        whole = all(float(v).is_integer() for v in (min(nums), max(nums)))
        text = f"{number(min(nums), digits, whole)}–{number(max(nums), digits, whole)}"
    elif aggregate:
        text = number({"min": min, "max": max, "median": statistics.median, "sum": sum}[aggregate[0]](nums), digits)
    else:
        text = number(nums[0], digits)
    if isinstance(values[0], bool) or text == "—":
        return text
    return text + (shown if shown[:1] in _NO_SPACE else f" {shown}" if shown else "")


def expand(markdown: str) -> str:
    """The page with every ``lbr:`` marker replaced by what the code and the benchmarks' files say."""

    def one(match: re.Match) -> str:
        kind, dotted, options = match.groups()
        if kind == "docstring" and not options:
            return "```text\n" + inspect.cleandoc(importlib.import_module(dotted).__doc__ or "") + "\n```"
        value = _resolve(dotted)
        if kind == "columns" and not options:
            return "`" + ",".join(value) + "`"
        if options:
            if kind != "value" or not isinstance(value, (int, float)):
                raise ValueError(f"docs marker {match.group(0)}: options are for a number's lbr:value")
            return _formatted(value, _key_unit(dotted.rpartition(".")[2]), options, f"lbr:value {dotted}", digits=None)
        return f"`{value}`"

    def prose(text: str) -> str:
        text = _MARKER.sub(one, BENCH_MARKER.sub(lambda m: figure(m.group(1), m.group(2)), text))
        left = re.search(r"<!-- lbr:.*?-->", text)
        if left:
            raise ValueError(f"docs marker not understood: {left.group(0)}")
        return text

    # a marker shown as code (a fenced block, `inline`) is left as it is
    parts = re.split(r"(^ *```.*?^ *```[^\n]*$|`[^`\n]+`)", markdown, flags=re.M | re.S)
    return "".join(part if i % 2 else prose(part) for i, part in enumerate(parts))


def on_files(files, config):
    for path in sorted(RESULTS.glob("*.md")):
        files.append(File.generated(config, f"explanations/results/{path.name}", abs_src_path=str(path)))
    return files


def on_page_markdown(markdown, page, config, files):
    return expand(markdown)
