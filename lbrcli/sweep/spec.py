"""The study file of `lbr sweep` (TOML) and the runs it expands to.

```toml
[study]
kind = "anti-sway"          # a run kind (`lbr sweep --kinds`)
samples = 44                # draws of the random parameters (all of them together), per grid point
seed = 17
figures = ["motion_s", "worst_residual_sway_deg"]   # JSON keys of the command (dotted for nested); default all
timeout = 600               # [s] per run, for kinds that run a process

[fixed]                     # options of the command, by their long names without --
shaper = "auto"

[vary]
length = { from = 0.12, to = 0.45, steps = 12 }     # a grid (log = true for a geometric one)
a-max = [0.8, 1.5, 2.5]                             # a list (or { values = [...] }, { glob = "paths/*.csv" })
points = { layout = { segments = [2, 5] } }         # random: uniform, loguniform, normal, integers, choice, layout

[judge]
string-errors = [-0.1, 0.0, 0.1]   # re-simulate each run's joints with the string this much off (relative)

[[plot]]
x = "length"
y = "a-max"
value = "judged_residual_sway_deg"  # or "ok": the share of runs that exited 0 (a success map)
```

Runs are the grid points (product of the lists and grids, in file order) × ``samples``; sample i draws every random
parameter from its own stream seeded by (seed, i, the parameter's name), so every grid point sees the same draws and
a study extended by more samples or grid points keeps the runs it had (same inputs → same cache key).
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import re
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from trajectories.errors import InputError

from .kinds import Judge, RunKind, get_kind
from .values import canonical, plain

RANDOM = ("uniform", "loguniform", "normal", "integers", "choice", "layout")
SECTIONS = ("study", "fixed", "vary", "judge", "plot")
STUDY_KEYS = ("name", "kind", "samples", "seed", "figures", "timeout")
MAX_RUNS = 1_000_000
LAYOUT_DEFAULTS = {"segments": [2, 5], "x": [0.35, 0.72], "y": [-0.38, 0.38], "step": [0.08, 0.35]}  # [m]


@dataclass(frozen=True)
class Axis:
    """One varied option: its values (a list or grid), or a random sampler and its arguments."""

    name: str
    values: tuple | None = None
    sampler: str | None = None
    args: Any = None


@dataclass(frozen=True)
class PlotSpec:
    """A map of ``value`` (a figure, or ``ok``) over the varied options ``x`` and ``y`` (a curve without y)."""

    x: str
    y: str | None
    value: str


@dataclass(frozen=True)
class Study:
    path: str
    name: str
    kind: str
    fixed: tuple[tuple[str, Any], ...]
    axes: tuple[Axis, ...]
    samples: int
    seed: int
    figures: tuple[str, ...] | None
    judge: Judge | None
    plots: tuple[PlotSpec, ...]
    timeout: float | None

    @property
    def size(self) -> int:
        n = self.samples
        for a in self.axes:
            n *= len(a.values) if a.values is not None else 1
        return n

    @property
    def varied(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.axes)


@dataclass(frozen=True)
class Run:
    """One run of a study: every option it is given (canonical), the varied ones, and its cache key."""

    index: int
    key: str
    kind: str
    options: tuple[tuple[str, Any], ...]
    params: tuple[tuple[str, Any], ...]
    sample: int
    judge: Judge | None
    timeout: float | None


def _fail(path: str, message: str) -> InputError:
    return InputError(message, file=path)


def read_study(path: str | Path) -> Study:
    """Parse and check a study file; InputError (exit 2) naming the file (and line, for TOML syntax) otherwise."""
    import tomllib

    from trajectories.inputs import MAX_SMALL_BYTES, read_text_input

    spath = str(path)
    text = read_text_input(path, MAX_SMALL_BYTES, what="study file")  # bounded: /dev/zero, a FIFO, a huge file
    try:
        doc = tomllib.loads(text)
    except RecursionError:
        raise InputError("not a study file: nested too deeply", file=spath) from None
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"\(at line (\d+), column (\d+)\)", str(exc))
        msg = re.sub(r"\s*\(at line \d+, column \d+\)", "", str(exc))
        raise InputError(
            f"not valid TOML: {msg}", file=spath, row=int(m[1]) if m else None, column=int(m[2]) if m else None
        ) from None
    return parse_study(doc, spath)


def parse_study(doc: dict, path: str) -> Study:
    """A study from its TOML document (``path`` names it in messages and anchors relative paths)."""
    for section in doc:
        if section not in SECTIONS:
            raise _fail(path, f"unknown section [{section}]; sections: {', '.join(SECTIONS)}")
    st = _table(doc, "study", path)
    for k in st:
        if k not in STUDY_KEYS:
            raise _fail(path, f"[study] unknown key {k!r}; keys: {', '.join(STUDY_KEYS)}")
    if "kind" not in st:
        raise _fail(path, "[study] kind is missing (see `lbr sweep --kinds`)")
    try:
        kind = get_kind(str(st["kind"]))
    except KeyError as exc:
        raise _fail(path, f"[study] kind: {exc.args[0]}") from None
    base = Path(path).resolve().parent
    fixed = {**kind.defaults, **{k: _path_value(kind, k, v, base) for k, v in _table(doc, "fixed", path).items()}}
    axes = tuple(_axis(name, spec, kind, base, path) for name, spec in _table(doc, "vary", path).items())
    for a in axes:
        if a.name in _table(doc, "fixed", path):
            raise _fail(path, f"{a.name!r} is both in [fixed] and [vary]")
        fixed.pop(a.name, None)  # a varied option replaces the kind's default
    for name in list(fixed) + [a.name for a in axes]:
        if kind.options is not None and name not in kind.options and name not in kind.defaults:
            raise _fail(
                path,
                f"{name!r} is not an option of {kind.name} ({' '.join(kind.command)}); options: "
                f"{', '.join(kind.options)}",
            )
    for name in kind.required:
        if name not in fixed and name not in [a.name for a in axes]:
            raise _fail(path, f"{kind.name} needs {name!r} in [fixed] or [vary]")
    random_axes = [a for a in axes if a.sampler is not None]
    samples = _int(st.get("samples", 1), "[study] samples", path, 1)
    if random_axes and "samples" not in st:
        raise _fail(
            path, f"[study] samples is needed with random parameters ({', '.join(a.name for a in random_axes)})"
        )
    figures = st.get("figures")
    if figures is not None and not (isinstance(figures, list) and all(isinstance(f, str) for f in figures)):
        raise _fail(path, '[study] figures must be a list of JSON keys, e.g. ["motion_s", "max_ratio.jerk"]')
    timeout = st.get("timeout")
    if timeout is not None and not (isinstance(timeout, (int, float)) and 0 < timeout <= 86400):
        raise _fail(path, f"[study] timeout must be in (0, 86400] s, got {timeout!r}")
    study = Study(
        path=path,
        name=str(st.get("name", Path(path).stem)),
        kind=kind.name,
        fixed=tuple((k, canonical(v)) for k, v in fixed.items()),
        axes=axes,
        samples=samples,
        seed=_int(st.get("seed", 0), "[study] seed", path, 0),
        figures=tuple(figures) if figures else None,
        judge=_judge(doc, kind, path),
        plots=_plots(doc, axes, path),
        timeout=float(timeout) if timeout is not None else None,
    )
    if study.size > MAX_RUNS:
        raise _fail(path, f"{study.size:,} runs: more than {MAX_RUNS:,} (split the study)")
    if study.size == 0:
        raise _fail(path, "the study has no runs (an empty list or glob in [vary])")
    return study


def _table(doc: dict, name: str, path: str) -> dict:
    value = doc.get(name, {})
    if not isinstance(value, dict):
        raise _fail(path, f"[{name}] must be a table")
    return value


def _int(value: Any, what: str, path: str, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < low:
        raise _fail(path, f"{what} must be an integer ≥ {low}, got {value!r}")
    return value


def _path_value(kind: RunKind, name: str, value: Any, base: Path) -> Any:
    """Options naming files: relative to the study file's folder → absolute."""
    if name in kind.paths and isinstance(value, str):
        return str((base / value).resolve()) if not Path(value).is_absolute() else value
    return value


def _axis(name: str, spec: Any, kind: RunKind, base: Path, path: str) -> Axis:
    where = f"[vary] {name}"
    if isinstance(spec, list):
        return Axis(name, tuple(canonical(_path_value(kind, name, v, base)) for v in spec))
    if not isinstance(spec, dict) or len(spec) != 1 and not {"from", "to", "steps"} <= set(spec):
        raise _fail(
            path,
            f"{where}: expected a list, {{ values = [...] }}, {{ from, to, steps }}, {{ glob = ... }} "
            f"or one of {', '.join(f'{{ {r} = ... }}' for r in RANDOM)}",
        )
    if {"from", "to", "steps"} <= set(spec):
        return Axis(name, _grid(spec, where, path))
    ((how, arg),) = spec.items()
    if how == "values":
        if not isinstance(arg, list):
            raise _fail(path, f"{where}: values must be a list")
        return Axis(name, tuple(canonical(_path_value(kind, name, v, base)) for v in arg))
    if how == "glob":
        return Axis(name, tuple(str(p.resolve()) for p in sorted(base.glob(str(arg)))))
    if how not in RANDOM:
        raise _fail(path, f"{where}: unknown {how!r}; use values, from/to/steps, glob or {', '.join(RANDOM)}")
    _check_sampler(how, arg, where, path)
    return Axis(name, sampler=how, args=canonical(arg))


def _grid(spec: dict, where: str, path: str) -> tuple:
    import numpy as np

    extra = set(spec) - {"from", "to", "steps", "log"}
    if extra:
        raise _fail(path, f"{where}: unknown key {sorted(extra)[0]!r} in a grid (from, to, steps, log)")
    lo, hi, n, log = spec["from"], spec["to"], spec["steps"], bool(spec.get("log", False))
    if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in (lo, hi)):
        raise _fail(path, f"{where}: from and to must be numbers")
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise _fail(path, f"{where}: steps must be an integer ≥ 1, got {n!r}")
    if log and (lo <= 0 or hi <= 0):
        raise _fail(path, f"{where}: a log grid needs from and to > 0")
    values = np.geomspace(lo, hi, n) if log else np.linspace(lo, hi, n)
    if isinstance(lo, int) and isinstance(hi, int) and np.all(values == np.round(values)):
        return tuple(int(v) for v in np.round(values))  # an integer grid stays integers (counts, indices)
    return tuple(canonical(float(v)) for v in values)


def _check_sampler(how: str, arg: Any, where: str, path: str) -> None:
    def pair(a) -> bool:
        return (
            isinstance(a, list)
            and len(a) == 2
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in a)
        )

    ok = {
        "uniform": pair(arg) and arg[0] <= arg[1],
        "loguniform": pair(arg) and 0 < arg[0] <= arg[1],
        "normal": pair(arg) and arg[1] >= 0,
        "integers": pair(arg) and all(isinstance(v, int) for v in arg) and arg[0] <= arg[1],
        "choice": isinstance(arg, list) and len(arg) > 0,
        "layout": isinstance(arg, dict) and set(arg) <= set(LAYOUT_DEFAULTS) and all(pair(v) for v in arg.values()),
    }[how]
    if not ok:
        expect = {"uniform": "[low, high]", "loguniform": "[low, high] with low > 0", "normal": "[mean, std]",
                  "integers": "[low, high] (inclusive)", "choice": "a non-empty list",
                  "layout": f"a table with {', '.join(LAYOUT_DEFAULTS)} as [low, high]"}[how]  # fmt: skip
        raise _fail(path, f"{where}: {how} expects {expect}, got {arg!r}")


def _judge(doc: dict, kind: RunKind, path: str) -> Judge | None:
    spec = _table(doc, "judge", path)
    if not spec:
        return None
    if kind.judge is None:
        raise _fail(path, f"[judge]: the kind {kind.name} has no judged figures")
    extra = set(spec) - {"string-errors", "model"}
    if extra:
        raise _fail(path, f"[judge] unknown key {sorted(extra)[0]!r} (string-errors, model)")
    errors = spec.get("string-errors")
    if not (isinstance(errors, list) and errors and all(isinstance(e, (int, float)) and -0.9 < e < 5 for e in errors)):
        raise _fail(path, "[judge] string-errors must be a list of relative errors in (-0.9, 5), e.g. [-0.1, 0, 0.1]")
    model = spec.get("model", "project")
    if model not in ("project", "independent"):
        raise _fail(path, f"[judge] model must be project or independent, got {model!r}")
    return Judge(tuple(canonical(float(e)) for e in errors), model)


def _plots(doc: dict, axes: tuple[Axis, ...], path: str) -> tuple[PlotSpec, ...]:
    specs = doc.get("plot", [])
    if not isinstance(specs, list):
        raise _fail(path, "[[plot]] must be an array of tables ([[plot]] x = ..., y = ..., value = ...)")
    names = [a.name for a in axes]
    out = []
    for k, p in enumerate(specs, 1):
        if not isinstance(p, dict) or "x" not in p or "value" not in p or set(p) - {"x", "y", "value"}:
            raise _fail(path, f"[[plot]] {k}: needs x and value (and y for a map), nothing else")
        for axis in ("x", "y"):
            if p.get(axis) is not None and p[axis] not in names:
                raise _fail(path, f"[[plot]] {k}: {axis} = {p[axis]!r} is not a varied option ({', '.join(names)})")
        out.append(PlotSpec(p["x"], p.get("y"), str(p["value"])))
    return tuple(out)


def run_key(kind: RunKind, options: dict, judge: Judge | None) -> str:
    """The cache key of a run: a hash of what determines its result (kind, its version, options, judge)."""
    doc = {
        "kind": kind.name,
        "version": kind.version,
        "options": {k: plain(v) for k, v in options.items()},
        "judge": None if judge is None else {"errors": list(judge.errors), "model": judge.model},
    }
    return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()[:24]


def draw(axis: Axis, seed: int, sample: int) -> Any:
    """Sample ``sample``'s value of a random parameter: its own stream, seeded by (seed, sample, name)."""
    import numpy as np

    rng = np.random.default_rng([seed, sample, zlib.crc32(axis.name.encode())])
    a = plain(axis.args)
    if axis.sampler == "uniform":
        return canonical(float(rng.uniform(a[0], a[1])))
    if axis.sampler == "loguniform":
        return canonical(float(math.exp(rng.uniform(math.log(a[0]), math.log(a[1])))))
    if axis.sampler == "normal":
        return canonical(float(rng.normal(a[0], a[1])))
    if axis.sampler == "integers":
        return int(rng.integers(a[0], a[1] + 1))
    if axis.sampler == "choice":
        return canonical(a[int(rng.integers(len(a)))])
    return canonical(random_layout(rng, **{**LAYOUT_DEFAULTS, **a}))


def random_layout(rng, segments, x, y, step) -> list[list[float]]:
    """Start and turning points [m] with 90° turns inside the box x × y: ``segments`` [low, high] moves, each
    ``step`` [low, high] long along x or y in turn (the layouts of benchmarks/bench_antisway_robust.py); 0.1 mm."""
    while True:
        n = int(rng.integers(segments[0], segments[1] + 1))
        pts = [[rng.uniform(*x), rng.uniform(*y)]]
        axis = int(rng.integers(0, 2))
        for _ in range(n):
            for _ in range(20):
                q = list(pts[-1])
                q[axis] += rng.choice([-1, 1]) * rng.uniform(*step)
                if x[0] <= q[0] <= x[1] and y[0] <= q[1] <= y[1]:
                    pts.append(q)
                    axis = 1 - axis
                    break
        if len(pts) >= min(3, segments[0] + 1):
            return [[round(float(v), 4) for v in p] for p in pts]


def expand(study: Study) -> list[Run]:
    """The runs of a study in order: grid points (file order) × samples."""
    kind = get_kind(study.kind)
    grid = [a for a in study.axes if a.values is not None]
    fixed = dict(study.fixed)
    runs = []
    for combo in itertools.product(*(a.values for a in grid)):
        for sample in range(study.samples):
            params = dict(zip((a.name for a in grid), combo))
            for a in study.axes:
                if a.sampler is not None:
                    params[a.name] = draw(a, study.seed, sample)
            params = {a.name: params[a.name] for a in study.axes}  # file order
            options = {**fixed, **params}
            runs.append(
                Run(
                    len(runs),
                    run_key(kind, options, study.judge),
                    kind.name,
                    tuple(options.items()),
                    tuple(params.items()),
                    sample,
                    study.judge,
                    study.timeout,
                )
            )
    return runs
