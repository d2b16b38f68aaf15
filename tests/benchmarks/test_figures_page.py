"""The docs page of benchmark figures is what benchmarks/results/*.json give, and the links into it (README and docs
pages) land."""

import importlib.util
import json
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _figures_page():
    spec = importlib.util.spec_from_file_location("figures_page", ROOT / "benchmarks" / "figures_page.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_page_is_generated_from_the_results():
    page = _figures_page()
    assert page.PAGE.read_text() == page.render(), "run python benchmarks/figures_page.py"
    rendered = page.rendered()
    assert rendered, "no benchmark renders its own results file"
    for path, text in rendered.items():
        assert path.read_text() == text, f"{path.name} is stale: run python benchmarks/figures_page.py"


def test_every_result_is_on_the_page_with_its_values(tmp_path):
    page = _figures_page()
    (tmp_path / "demo.json").write_text(
        json.dumps(
            {
                "benchmark": "demo",
                "command": "python benchmarks/run_all.py demo",
                "measured": "2026-01-02T03:04:05",
                "seconds": 1.5,
                "cpus": 2,
                "load_1min_before": 0.5,
                "figures": [
                    {"name": "a | b", "value": 0.1234567, "unit": "s"},
                    {"name": "n", "value": 12345, "unit": ""},
                    {"name": "x", "value": float("nan"), "unit": "deg"},
                ],
            }
        )
    )
    text = page.render(tmp_path)
    assert "## demo" in text and "| a \\| b | 0.1235 | s |" in text and "| n | 12,345 |  |" in text
    assert "| x | — | deg |" in text and "2026-01-02 03:04:05" in text


def test_links_to_the_page_land_on_a_section():
    """Each link names a benchmark; once that benchmark has results, the page has its section."""
    page = _figures_page().PAGE.read_text()
    sections = {line[3:].strip() for line in page.splitlines() if line.startswith("## ")}
    texts = [(ROOT / "README.md").read_text()] + [p.read_text() for p in (ROOT / "docs").rglob("*.md")]
    links = {name for text in texts for name in re.findall(r"benchmark-figures\.md#([a-z0-9_-]+)", text)}
    assert links
    for name in links:
        assert (ROOT / "benchmarks" / f"bench_{name}.py").exists(), name
        if (ROOT / "benchmarks" / "results" / f"{name}.json").exists():
            assert name in sections, name
