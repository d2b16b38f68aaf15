"""`lbr demo`: the whole loop on the built-in simulator, results in one folder."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ..options import JsonOpt


def demo(
    out: Annotated[Path, typer.Option("--out", help="Folder for every file the demo writes.")] = Path("lbr-demo"),
    json_out: JsonOpt = False,
) -> None:
    """Run the user's loop end to end on the built-in FRI simulator and write one folder.

    Plans a crane move with the thesis baseline and with the default shaper, checks and executes both on the
    simulator with the ball simulated; plans and executes a swing-up; films the simulated ball, tracks it back
    and compares model and "experiment"; plans the cup-and-ball catch, rehearses it on the simulator with the cup,
    films, tracks and compares the flight. Ends with a table; `summary.md` lists every command it ran.

    The run happens in a hidden sibling folder that replaces --out only when it completes: an interrupted run
    leaves --out as it was. An existing --out is replaced only if it holds a previous demo (its summary.md).
    """
    import time

    from rich.markup import escape
    from rich.table import Table

    from ..console import Reporter
    from ..option_groups import settings_named
    from ..demo.folder import discard, prepare_out, publish, staging_folder
    from ..demo.pipeline import demo_steps, run_demo, summary_figures, summary_rows, write_summary

    rep = Reporter(json_out)
    with settings_named({"demo.out": "--out"}):
        replaces = prepare_out(out)
    if replaces:
        rep.print(f"{out}/ holds a previous demo ({replaces}): it is replaced when this run completes")
    staging = staging_folder(out)
    steps = demo_steps()
    t0 = time.perf_counter()
    with rep.progress("lbr demo", len(steps)) as update:

        def on_step(step, k):
            update(k)
            if not rep.interactive:
                rep.print(f"[{k + 1}/{len(steps)}] {step.title} …")

        def on_done(step, res):
            status = "[green]ok[/green]" if res.ok else f"[red]failed[/red]: {res.error}"
            rep.print(f"  {step.name}: {status} ({res.seconds:.1f} s)")

        try:
            results = run_demo(staging, on_step, on_done)
            update(len(steps))
            seconds = time.perf_counter() - t0
            figures = summary_figures(results)
            write_summary(staging, results, figures, seconds)
        except BaseException:  # Ctrl-C or a crash: no partial folder under --out, no mix with the old one
            discard(staging)
            raise
    publish(staging, out)
    summary = out / "summary.md"
    table = Table(title=f"lbr demo — {seconds:.0f} s, files in {out}/")
    table.add_column("figure")
    table.add_column("value", justify="right")
    for row in summary_rows(figures):
        table.add_row(*(escape(cell) for cell in row))  # labels carry units like [s]
    rep.print(table)
    rep.print(f"summary: {summary}")
    figures["seconds"] = seconds
    figures["out"] = str(out)
    rep.emit(figures)
    if not figures["ok"]:
        raise typer.Exit(1)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("demo")(demo)
