"""`lbr compare`: the tracked string angle against the model's prediction — lag, RMS and max error, overlay plot."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

from ..options import JsonOpt, number

MIN_COVERAGE = 0.5  # share of the prediction's time span the track must overlap (without --partial)


def compare(
    prediction: Annotated[Path, typer.Argument(help="Prediction t,theta \\[s, rad] (`lbr plan ... --prediction`), or a simulated execution log with --column.")],
    track: Annotated[Path, typer.Argument(help="Track CSV from `lbr track video` with a theta column.")],
    plot: Annotated[Optional[Path], typer.Option("--plot", help="PNG overlaying model and experiment θ \\[deg] over time, and their difference.")] = None,
    lag: Annotated[Optional[float], number("--lag", low=-86400, high=86400, unit="s", help="Track time − prediction time \\[s]; estimated by cross-correlation when omitted.")] = None,
    max_lag: Annotated[Optional[float], number("--max-lag", low=0, high=86400, low_open=True, unit="s", help="Search the lag only within ± this \\[s] (default: half the longer of the two series, at least 2 s).")] = None,
    flip: Annotated[bool, typer.Option("--flip", help="Negate the track's θ (camera looking at the plane of motion from the other side).")] = False,
    column: Annotated[str, typer.Option("--column", help="Angle column \\[rad] of the prediction file (e.g. ball_theta in an execution log).")] = "theta",
    partial: Annotated[bool, typer.Option("--partial", help="Compare even when the track covers less than half of the prediction, or the execution log's session stopped early (refused otherwise).")] = False,
    json_out: JsonOpt = False,
) -> None:
    """Compare the model's θ with the tracked θ: align in time, report RMS and max error over the overlap.

    Lag convention: track time = prediction time + lag. The lag is searched within a window (reported) and the
    best other peak of the match score is reported too: when it scores nearly as well (a steady swing matches
    itself one period off) a warning says to give --lag or a tighter --max-lag. Frames where the ball (or
    pivot) was not found are skipped. Exit 1 when prediction and track do not overlap, or (without --partial) the
    overlap covers less than half of the prediction — the experiment stopped early, or the files do not belong
    together; exit 2 for an execution log (--column) whose session did not complete, without --partial.
    """
    import math

    import numpy as np

    from trajectories.csvio import PREDICTION_COLUMNS, read_table
    from trajectories.errors import CheckFailed, CsvFormatError, OptionError
    from tracking.compare import compare_angles
    from tracking.trackfile import read_track_csv

    from ..console import Reporter
    from ..session_end import require_complete

    rep = Reporter(json_out)
    for p, name in ((plot, "--plot"),):
        if p is not None and not p.resolve().parent.is_dir():
            raise OptionError(f"{name}: folder does not exist: {p.parent}")
    if column == "theta":
        pred = read_table(prediction, PREDICTION_COLUMNS, time="increasing")
    else:
        from lbrcli.fri.log import NAN_COLUMNS

        pred = read_table(prediction, ("t",), time="increasing", nan_columns=NAN_COLUMNS)
        if not pred.has(column):
            raise CsvFormatError(f"no column '{column}' (columns: {', '.join(pred.names)})", file=pred.path, row=1)
        require_complete(pred, partial, rep)
    t_model, theta_model = pred.column("t"), pred.column(column)
    known = np.isfinite(theta_model)  # an execution log's pendulum columns are nan before the first reading
    t_model, theta_model = t_model[known], theta_model[known]
    if len(t_model) < 2:
        raise CsvFormatError("need at least 2 samples", file=pred.path)
    tr = read_track_csv(track)
    if tr.theta is None:
        raise CsvFormatError("no 'theta' column: track the video with --pivot or --pivot-color", file=tr.path, row=1)

    cmp = compare_angles(t_model, theta_model, tr.t, tr.theta, lag_s=lag, flip=flip, max_lag_s=max_lag)
    how = f"estimated within ±{cmp.lag_window_s:.2f} s" if cmp.lag_estimated else "given"
    rep.print(f"lag {cmp.lag_s:+.4f} s ({how}; track time = prediction time + lag)")
    if cmp.lag_estimated and math.isfinite(cmp.rival_lag_s):
        rep.print(f"match score {cmp.correlation:.3f}; next best peak at {cmp.rival_lag_s:+.3f} s scores {cmp.rival_correlation:.3f}")
        if cmp.rival_correlation >= cmp.correlation - 0.02:
            rep.warn(
                f"the lag is ambiguous: {cmp.rival_lag_s:+.3f} s matches nearly as well as {cmp.lag_s:+.3f} s "
                "(give --lag, or --max-lag around the expected delay)"
            )
    rep.print(
        f"over {cmp.overlap_s:.3f} s ({cmp.samples} frames): RMS error {cmp.rms_deg:.3f}°, max {cmp.max_deg:.3f}°"
    )
    if cmp.mirrored:
        rep.warn("the track's θ matches the prediction much better negated: the camera sees the motion mirrored — try --flip")
    span = float(t_model[-1] - t_model[0])
    coverage = cmp.overlap_s / span if span > 0 else 0.0
    short = coverage < MIN_COVERAGE
    if short:
        rep.warn(f"the track covers {cmp.overlap_s:.2f} s of the {span:.2f} s prediction ({coverage * 100:.0f} %)")
    if plot is not None:
        from ..plots.compare import plot_compare

        theta_meas = -tr.theta if flip else tr.theta
        plot_compare(cmp, t_model, theta_model, plot, f"{prediction.name} vs {track.name}", tr.t, theta_meas)
        rep.print(f"plot: {plot}")
    rep.emit(
        {
            "prediction": str(prediction),
            "track": str(track),
            "lag_s": cmp.lag_s,
            "lag_estimated": cmp.lag_estimated,
            "lag_window_s": cmp.lag_window_s,
            "rival_lag_s": cmp.rival_lag_s,
            "rival_score": cmp.rival_correlation,
            "rms_deg": cmp.rms_deg,
            "max_deg": cmp.max_deg,
            "overlap_s": cmp.overlap_s,
            "samples": cmp.samples,
            "score": cmp.correlation,
            "mirrored": cmp.mirrored,
            "flipped": flip,
            "track_frames": int(len(tr.t)),
            "track_theta_frames": int(np.isfinite(tr.theta).sum()),
            "coverage": coverage,
            "ok": not short or partial,
        }
    )
    if short and not partial:
        raise CheckFailed(f"the track covers only {coverage * 100:.0f} % of the prediction ({cmp.overlap_s:.2f} of "
                          f"{span:.2f} s): the experiment stopped early or the files do not belong together; "
                          "--partial compares the overlap anyway")  # fmt: skip


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("compare")(compare)
