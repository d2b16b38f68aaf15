"""Figures in the docs come only from files the benchmarks write, never typed by hand.

A measured figure is quoted with a marker, ``<!-- lbr:bench FILE.KEY… -->``, which ``docs/hooks.py`` expands from
``benchmarks/results/FILE.json`` at build time (an unknown file or key fails the build). This test scans the hand-
written pages (``docs/**/*.md`` but the generated ones, and ``README.md``) for a figure typed by hand: a number
followed by a unit a measurement comes out in — µs, ms, s, min, °, %, ×, px, mm, poses/s, runs/s, frames/s, MB —
in prose, outside fenced code blocks, inline code, HTML comments (the markers) and link targets.

Parameters and limits (the 1 ms period, a ±10 % band, a 10° push, a goal of ≤ 5 s) are not measured figures. They
are allowed only in the phrases of ``ALLOWED`` below, each a regex whose group ``fig`` is the allowed figure:

- bounds: a figure right after ≤, ≥, <, >, "up to", "at least" or "at most" (a goal, limit or threshold — a
  measured maximum is quoted with a marker, never typed as a bound), and the cells of a table column headed "goal";
- the FRI send period: a figure followed by "period"/"cycle", or 1, 2, 4, 5 or 10 ms after "at"/"every";
- a band or perturbation of an input: ±N; N followed by shorter/longer/short/long/off/wider/narrower/larger/
  smaller/heavier/lighter; N "of the"/"of its" … after at/to/within/of (a share of the limits);
- what a run is given: a figure followed by a word of ``INPUT_WORDS`` naming the input (hold, push, path, log, run,
  session, video, window, timeout, delay, late, tilt, step, grid, apart, exposure, amplitude, …), a size followed by
  ball/string/circle/disc/marker/radius/rod/cup/frame (one word may come between), "a/with N ms latency";
- a default: "default N", "(default: N)".

Anything else is a measured figure: quote it with a marker, write a parameter as the option that sets it in code
(`--hold 60`) or an ``lbr:value`` marker of the constant, or link to the benchmark figures page.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
# written by programs, not by hand (each says so on its first lines): exempt
GENERATED = {
    "docs/reference/cli.md",  # docs/gen_cli_reference.py
    "docs/explanations/benchmark-figures.md",  # benchmarks/figures_page.py
    "docs/guides/ik-suite.md",  # benchmarks/bench_ik_chain.py
}
GENERATED_FOLDERS = ("docs/guides/results/",)  # bench_live, bench_track_robust, bench_camera_damp

UNIT = r"(?:µs|us|ms|s|min|°|deg|%|×|px|mm|poses/s|runs/s|frames/s|MB|GB|kB|KB)"
NUMBER = r"[−\-+]?\d[\d,]*(?:\.\d+)?(?:e[−\-]?\d+)?"
# a number or a range / list of them (0.2–0.5, 0.2 / 0.3, 0.2/0.3/0.5), then its unit; not part of a word or path
FIGURE = re.compile(rf"(?<![\w.\-/^]){NUMBER}(?:\s?(?:–|-|/|…|\.\.\.)\s?{NUMBER})*\s?{UNIT}(?![\w/²³])")
FIG = rf"(?P<fig>{FIGURE.pattern})"
INPUT_WORDS = (
    r"hold|push|pushes|paths?|logs?|runs?|sessions?|videos?|clips?|moves?|windows?|timeouts?|delays?|"
    r"late|early|jitter|tilts?|yaw|turns?|swings?|pumping|settle|waits?|of streaming|of motion|of swing|"
    r"streams?|recording|budget|studies|sleeps?|sleeping|apart|slices?|steps?|grid|"
    r"exposure|shutter|per command|segments?|above|below|around|down|wide|margin|stages?|"
    r"plans?|later|earlier|tail|lost|malformed|amplitudes?"
)
ALLOWED = [
    re.compile(p)
    for p in (
        rf"(?:≤|≥|<|>|up to|at least|at most)\s*{FIG}",  # a bound: goal, limit, threshold
        rf"{FIG}\s+(?:send\s+|command\s+|FRI\s+|control\s+)?(?:periods?|cycles?)\b",  # the FRI period
        r"\b(?:at|every)\s+(?P<fig>(?:1|2|4|5|10)(?:\s?(?:–|,|/|and|or)\s?(?:1|2|4|5|10))*\s?ms)\b",
        rf"±\s*{FIG}",  # a band
        rf"{FIG}\s+(?:shorter|longer|short|long|off|wider|narrower|larger|smaller|heavier|lighter|too long|too short)\b",
        rf"\b(?:at|to|within|of)\s+{FIG}\s+of\s+(?:the|its|their|every|each)\b",  # a share of the limits
        rf"{FIG}\s+(?:{INPUT_WORDS})\b",  # what a run is given
        rf"{FIG},?\s+(?:\w+\s+)?(?:ball|string|circle|disc|marker|radius|square|board|rod|cup|frame)\b",
        rf"\bdefault:?\s+{FIG}",
        rf"\b(?:a|an|with)\s+{FIG}\s+(?:camera\s+)?latency\b",  # a camera's latency, as a run is given it
    )
]


def pages() -> list[Path]:
    found = [ROOT / "README.md"]
    for path in sorted((ROOT / "docs").rglob("*.md")):
        rel = path.relative_to(ROOT).as_posix()
        if rel not in GENERATED and not rel.startswith(GENERATED_FOLDERS):
            found.append(path)
    return found


def _blank(match: re.Match) -> str:
    return re.sub(r"[^\n]", " ", match.group(0))


def _prose(lines: list[str]):
    """(line number, text) of the page's prose: fenced code blocks, inline code (also across a line break), HTML
    comments and link targets blanked, and the cells of a table column headed "goal"."""
    text = "\n".join(lines)
    text = re.sub(r"^ *(```|~~~).*?^ *\1", _blank, text, flags=re.M | re.S)
    text = re.sub(r"`[^`]*?`", _blank, text)  # a paragraph's code spans, line breaks included
    text = re.sub(r"<!--.*?-->", _blank, text, flags=re.S)
    text = re.sub(r"\]\([^)]*\)", lambda m: "]" + _blank(m)[1:], text)
    goal_cols, in_table = set(), False
    for number, line in enumerate(text.split("\n"), 1):
        if line.strip().startswith("|"):
            cells = line.strip().strip("|").split("|")
            if not in_table:  # the header row
                goal_cols = {i for i, head in enumerate(cells) if "goal" in head.lower()}
            in_table = True
            line = "|".join("" if i in goal_cols else c for i, c in enumerate(cells))
        else:
            in_table = False
        yield number, line


def hand_typed(text: str, before: str = "", after: str = "") -> list[str]:
    """The figures in one line of prose that no allowed phrase covers (``before``/``after``: the lines around it,
    for a phrase broken over lines)."""
    whole, start = f"{before}\n{text}\n{after}", len(before) + 1
    allowed = [m.span("fig") for pattern in ALLOWED for m in pattern.finditer(whole)]
    return [
        m.group(0)
        for m in FIGURE.finditer(whole, start, start + len(text))
        if not any(a <= m.start() and m.end() <= b for a, b in allowed)
    ]


def page_figures(path: Path) -> list[str]:
    """``file:line: figure`` of every figure typed by hand on the page."""
    lines = [text for _, text in _prose(path.read_text().splitlines())]
    found = []
    for i, text in enumerate(lines):
        before, after = (lines[i - 1] if i else ""), (lines[i + 1] if i + 1 < len(lines) else "")
        found += [f"{path.relative_to(ROOT)}:{i + 1}: {fig!r}" for fig in hand_typed(text, before, after)]
    return found


@pytest.mark.heavy
def test_no_measured_figure_is_typed_by_hand():
    found = [line for path in pages() for line in page_figures(path)]
    assert not found, (
        f"{len(found)} figures typed by hand (quote them with <!-- lbr:bench FILE.KEY -->; see this "
        "test's docstring for the parameter phrases allowed):\n" + "\n".join(found)
    )


@pytest.mark.parametrize(
    "text",
    [
        "p99 0.058 ms, 1.08× KUKA's",
        "28,300 poses/s best of 3",
        "100 % found, centre RMS 0.20 px",
        "in 1,231 s end",
        "planning 4.0 s",
        "viser's client is 0.8 MB",
        "θ RMS 0.020°",
        "median 0.75 (0.2–0.5°)",
        "8.42 runs/s",
        "a largest offset of 17.6 mm",
        "decode 1,659 frames/s",
        "it took 2 min",
    ],
)
def test_a_measured_figure_is_found(text):
    assert hand_typed(text), text


@pytest.mark.parametrize(
    "text",
    [
        "at a 1 ms send period",
        "every 5 ms",
        "strings ±10 % off",
        "the string 20 % short",
        "a 60 s hold and a 10° push",
        "(goal ≤ 5 s)",
        "at 20 % of the limits",
        "a 13 px ball",
        "(default 0.2°)",
        "5 and 15 ms delay",
    ],
)
def test_a_parameter_phrase_is_allowed(text):
    assert not hand_typed(text), text


def test_a_goal_column_is_a_parameter_and_code_is_not_prose():
    table = ["| what | figure | goal |", "|---|---|---|", "| open | 3.5 s | ≤ 5 s, 2 min |"]
    assert [hand_typed(t) for _, t in _prose(table)] == [[], [], ["3.5 s"]]
    assert not [hand_typed(t) for _, t in _prose(["```", "took 3.5 s", "```", "`3.5 s` <!-- 3 s -->"]) if hand_typed(t)]


def _hooks():
    import importlib.util

    spec = importlib.util.spec_from_file_location("hooks", ROOT / "docs" / "hooks.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_marker_quotes_the_results_file_with_its_unit_and_rounding(tmp_path, monkeypatch):
    import json

    hooks = _hooks()
    monkeypatch.setattr(hooks, "RESULT_FOLDERS", (tmp_path,))
    (tmp_path / "demo.json").write_text(
        json.dumps(
            {
                "benchmark": "demo",
                "load_1min_before": 2.5,
                "figures": [
                    {"name": "plan: time (4 segments)", "value": 1.23456, "unit": "s"},
                    {"name": "plan: residual", "value": 0.0012345, "unit": "deg"},
                    {"name": "run: residual", "value": 0.5, "unit": "deg"},
                ],
            }
        )
    )
    (tmp_path / "own.json").write_text(
        json.dumps({"cases": [{"key": "a", "p99_ms": 1.0, "share": 0.25}, {"key": "b", "p99_ms": 2.5, "share": 0.5}]})
    )
    assert hooks.figure('demo."plan: time (4 segments)"') == "1.23 s"
    assert hooks.figure('demo."plan: time (4 segments)"', "unit=ms") == "1,230 ms"
    assert hooks.figure('demo."plan: residual"') == "0.00123°"
    assert hooks.figure('demo."*: residual"', "max") == "0.500°" and hooks.figure("demo.load_1min_before") == "2.50"
    assert (
        hooks.figure("own.cases.b.p99_ms") == "2.50 ms"
        and hooks.figure("own.cases.*.p99_ms", "range") == "1.00–2.50 ms"
    )
    assert hooks.figure("own.cases.0.share", "unit=%") == "25 %" and hooks.figure("own.cases.*", "count") == "2"
    assert hooks.expand("x <!-- lbr:bench own.cases.b.p99_ms digits=2 --> y") == "x 2.5 ms y"
    for spec, options in (
        ("nothing.x", ""),
        ("own.cases.c.p99_ms", ""),
        ("own.cases.a.p50_ms", ""),
        ("own.cases.*.p99_ms", ""),
        ("own.cases.a.p99_ms", "sideways"),
    ):
        with pytest.raises(hooks.FigureError):
            hooks.figure(spec, options)
    with pytest.raises(ValueError, match="not understood"):
        hooks.expand('<!-- lbr:bench own.cases."a -->')
