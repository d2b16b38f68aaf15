"""`lbr view`: a 3D replay in the browser of plans, execution logs, predictions, tracks and obstacle files."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

from ..fri_options import DEFAULT_BALL_LENGTH, DrawnLengthOpt, parse_ip
from ..options import DEFAULT_FLANGE, FlangeOpt, JsonOpt, ToolOpt, floats, number

MAX_OFFSET = 86400.0  # [s] the largest --offset


def _offset(item: str | tuple) -> tuple[str, float]:
    """typer ``parser`` of one --offset FILE=SECONDS (plain decimal seconds within ±MAX_OFFSET)."""
    from trajectories.numbers import NotANumber, plain_float

    if isinstance(item, tuple):
        return item
    name, sep, value = str(item).rpartition("=")
    try:
        seconds = plain_float(value)
    except NotANumber:
        seconds = None
    if not sep or not name or seconds is None or abs(seconds) > MAX_OFFSET:
        raise typer.BadParameter(f"expected FILE=SECONDS with |SECONDS| ≤ {MAX_OFFSET:g} (e.g. track.csv=0.45), got "
                                 f"{item!r}")  # fmt: skip
    return name, seconds


def view(
    files: Annotated[
        list[Path],
        typer.Argument(
            metavar="FILE...",
            help="Files lbr wrote: joint and task trajectories, execution logs, predictions, tracks, obstacle files (recognised by their header).",
        ),
    ],
    out: Annotated[
        Optional[Path],
        typer.Option(
            "-o",
            "--out",
            help="Write the replay as one self-contained HTML file (opens in any browser, offline, without lbr) instead of serving it.",
        ),
    ] = None,
    serve: Annotated[bool, typer.Option("--serve", help="With -o: also serve the view.")] = False,
    host: Annotated[
        str,
        typer.Option(
            "--host",
            parser=parse_ip,
            metavar="IP",
            help="IP address the view's server binds (loopback by default; another address opens the view to that network).",
        ),
    ] = "127.0.0.1",
    port: Annotated[
        int, number("--port", low=0, high=65535, integer=True, help="TCP port of the view's server (0: any free port).")
    ] = 8080,
    duration: Annotated[
        Optional[float],
        number(
            "--duration",
            low=0,
            high=1e7,
            low_open=True,
            unit="s",
            help="Stop serving after this many seconds \\[s] (default: until Ctrl-C).",
        ),
    ] = None,
    open_browser: Annotated[bool, typer.Option("--open", help="Open the view in the default web browser.")] = False,
    fps: Annotated[
        float,
        number(
            "--fps",
            low=1,
            high=240,
            unit="1/s",
            help="Frames per second of the replay \\[1/s]; the files are sampled on this grid.",
        ),
    ] = 30.0,
    length: DrawnLengthOpt = DEFAULT_BALL_LENGTH,
    ball_radius: Annotated[
        float, number("--ball-radius", low=0.001, high=0.5, unit="m", help="Radius of the drawn ball \\[m].")
    ] = 0.02,
    cup: Annotated[
        Optional[tuple],
        floats(
            "--cup",
            count=2,
            low=0.005,
            high=0.5,
            unit="m",
            metavar="RADIUS,DEPTH",
            help="Draw a cup on the TCP: RADIUS,DEPTH \\[m] of a translucent cylinder from the TCP along the flange's z axis.",
        ),
    ] = None,
    offset: Annotated[
        Optional[list[tuple]],
        typer.Option(
            "--offset",
            parser=_offset,
            metavar="FILE=SECONDS",
            help="Place a file on the time line by hand (view time = file time + SECONDS, before the time line is shifted to start at 0). Repeatable.",
        ),
    ] = None,
    flange: FlangeOpt = DEFAULT_FLANGE,
    tool: ToolOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Replay files in 3D in the web browser, on one time line with play/pause and a slider.

    Draws the iiwa 7 from the project's kinematic model (--flange, --tool) for every plan (planned) and execution
    log (commanded and measured, as two ghosts), the pivot (TCP) paths and the plan's turning points, obstacle
    boxes, the cup (--cup), the balls — predicted, simulated and tracked side by side, each with its string —
    and the log's session state and phase. An execution log is the reference clock; a plan and its prediction are
    placed where the log commanded their first row; a track where its θ matches the reference ball (as `lbr
    compare` does); --offset places a file by hand.

    Serves the view on loopback (viser; Ctrl-C to stop) — or, with -o, writes one self-contained HTML file with
    the same replay that a colleague opens in any browser without lbr.
    """
    import signal
    import threading
    import time
    import webbrowser

    from trajectories.errors import OptionError

    from ..console import Reporter
    from ..options import make_robot
    from ..outputs import guard_outputs
    from ..view.inputs import read_input
    from ..view.scene import ViewSettings, build_scene
    from ..view.timeline import align

    t0 = time.perf_counter()
    rep = Reporter(json_out)
    if out is not None and out.suffix.lower() not in (".html", ".htm"):
        raise OptionError(f"-o: the offline view is an HTML file (.html), got {out}")
    given = dict(offset or [])
    settings = ViewSettings(length=length, fps=fps, ball_radius=ball_radius, cup=cup)
    guard_outputs({f"FILE {p}": p for p in files}, {"-o": out})
    robot = make_robot(flange, tool)
    inputs = [read_input(p) for p in files]
    unknown = set(given) - {k for f in inputs for k in (f.path, f.name, str(Path(f.path).resolve()))}
    if unknown:
        raise OptionError(f"--offset: {sorted(unknown)[0]} is none of the files given")
    alignment = align(inputs, given)
    scene = build_scene(inputs, alignment, robot, settings)
    for f in inputs:
        how = alignment.how.get(f.path)
        place = f", at {alignment.offsets[f.path]:+.3f} s: {how}" if how else ""
        rep.print(f"{f.path}: {f.kind}{place}")
    figures = {
        "files": [
            {
                "file": f.path,
                "kind": f.kind,
                "offset_s": alignment.offsets.get(f.path),
                "placed": alignment.how.get(f.path),
            }
            for f in inputs
        ],
        "duration_s": scene.duration,
        "frames": len(scene.t),
        "fps": fps,
        "arms": [a.key for a in scene.arms],
        "balls": [b.key for b in scene.balls],
        "turning_points": len(scene.turning_points),
        "obstacles": len(scene.obstacles),
    }
    if out is not None:
        from ..view.serve import write_offline

        size = write_offline(scene, robot, out)
        rep.print(f"wrote {out}: {size / 1e6:.1f} MB, {len(scene.t)} frames over {scene.duration:.2f} s")
        figures.update(out=str(out), size_bytes=size)
        if not serve:
            figures["seconds"] = time.perf_counter() - t0
            rep.emit(figures)
            return
    if host not in ("127.0.0.1", "::1"):
        rep.warn(f"--host {host}: the view is served beyond this computer")
    from ..view.serve import Player, start_server, stop_server

    server = start_server(host, port)
    player = Player(server, scene, robot)
    url = f"http://{'127.0.0.1' if host in ('0.0.0.0', '::') else host}:{server.get_port()}"
    figures.update(url=url, ready_s=time.perf_counter() - t0)
    rep.print(f"view: {url}  ({len(scene.t)} frames over {scene.duration:.2f} s; Ctrl-C to stop)")
    import sys

    sys.stderr.flush()
    if open_browser:
        webbrowser.open(url)
    stop = threading.Event()
    interrupted = []  # Ctrl-C or SIGTERM end the wait below (no exception in the middle of stopping the server)

    def _stop(signum, _frame) -> None:
        interrupted.append(signum)
        stop.set()

    previous = {sig: signal.signal(sig, _stop) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        stop.wait(duration)
    finally:
        player.close()
        stop_server(server)
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    figures.update(frames_shown=player.frames_shown, seconds=time.perf_counter() - t0)
    rep.emit(figures)
    if signal.SIGINT in interrupted:  # Ctrl-C: 130 as everywhere; SIGTERM ends a server normally
        raise typer.Exit(130)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("view")(view)
