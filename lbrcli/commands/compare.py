"""`lbr compare`: the tracked string angle against the model's prediction — lag, RMS and max error, overlay plot."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

from ..options import JsonOpt


def compare(
    prediction: Annotated[Path, typer.Argument(help="Prediction t,theta \\[s, rad] (`lbr plan ... --prediction`), or a simulated execution log with --column.")],
    track: Annotated[Path, typer.Argument(help="Track CSV from `lbr track video` with a theta column.")],
    plot: Annotated[Optional[Path], typer.Option("--plot", help="PNG overlaying model and experiment θ \\[deg] over time, and their difference.")] = None,
    lag: Annotated[Optional[float], typer.Option("--lag", help="Track time − prediction time \\[s]; estimated by cross-correlation when omitted.")] = None,
    max_lag: Annotated[Optional[float], typer.Option("--max-lag", help="Search the lag only within ± this \\[s] (default: half the longer of the two series, at least 2 s).")] = None,
    flip: Annotated[bool, typer.Option("--flip", help="Negate the track's θ (camera looking at the plane of motion from the other side).")] = False,
    column: Annotated[str, typer.Option("--column", help="Angle column \\[rad] of the prediction file (e.g. ball_theta in an execution log).")] = "theta",
    json_out: JsonOpt = False,
) -> None:
    """Compare the model's θ with the tracked θ: align in time, report RMS and max error over the overlap.

    Lag convention: track time = prediction time + lag. The lag is searched within a window (reported) and the
    best other peak of the match score is reported too: when it scores nearly as well (a steady swing matches
    itself one period off) a warning says to give --lag or a tighter --max-lag. Frames where the ball (or
    pivot) was not found are skipped. A cup-and-ball prediction (`lbr plan cup-and-ball --prediction`, with phase,
    ball and anchor columns) against a track with a pivot marker is also compared by position where its string is
    slack (the free flight; the track has no θ there): the image scale is the tracked string length over the
    model's. Exit 1 when prediction and track do not overlap.
    """
    import math

    import numpy as np

    from trajectories.csvio import PREDICTION_COLUMNS, read_table
    from trajectories.errors import CsvFormatError, OptionError
    from tracking.compare import compare_angles
    from tracking.trackfile import read_track_csv

    from ..console import Reporter

    rep = Reporter(json_out)
    if max_lag is not None and not (max_lag > 0 and math.isfinite(max_lag)):
        raise OptionError(f"--max-lag must be a positive number of seconds, got {max_lag:g}")
    if lag is not None and not math.isfinite(lag):
        raise OptionError(f"--lag must be a finite number of seconds, got {lag:g}")
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
    positions = _slack_positions(pred, tr, cmp.lag_s, flip) if column == "theta" else None
    if positions is not None:
        if positions.frames:
            rep.print(f"slack string (free flight) over {positions.frames} frames: ball position RMS error "
                      f"{1e3 * positions.rms_m:.1f} mm, max {1e3 * positions.max_m:.1f} mm (scale "
                      f"{positions.px_per_m:.0f} px/m from the string's length)")
        else:
            rep.print("the prediction's slack phase and the track do not overlap: no positions compared")
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
            "slack_position": None if positions is None else {
                "frames": positions.frames, "rms_m": positions.rms_m, "max_m": positions.max_m,
                "px_per_m": positions.px_per_m},
        }
    )


def _slack_positions(pred, tr, lag: float, flip: bool):
    """Ball positions where the prediction's string is slack (a cup-and-ball prediction with ball and anchor columns)
    against the track's ball relative to its pivot marker; None when either lacks them."""
    import numpy as np

    from tracking.compare_positions import compare_positions
    from tracking.slack import string_length_px

    needed = ("phase", "ball_y", "ball_z", "anchor_y", "anchor_z")
    if not all(pred.has(c) for c in needed) or tr.pivot_uv is None:
        return None
    phase = pred.column("phase")
    rel = np.column_stack([pred.column("ball_y") - pred.column("anchor_y"), pred.column("ball_z") - pred.column("anchor_z")])
    taut = phase == 0
    if not taut.any() or not (phase == 1).any():
        return None
    length = float(np.median(np.hypot(*rel[taut].T)))
    rel_px = tr.uv - tr.pivot_uv
    return compare_positions(pred.column("t"), rel, phase == 1, length, tr.t, rel_px,
                             string_length_px(np.hypot(*rel_px.T)), lag, flip)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("compare")(compare)
