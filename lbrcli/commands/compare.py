"""`lbr compare`: the tracked string angle against the model's prediction — lag, RMS and max error, overlay plot."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

from ..options import JsonOpt, number

MIN_COVERAGE = 0.5  # share of the prediction's time span the track must overlap (without --partial)


def compare(
    prediction: Annotated[
        Path,
        typer.Argument(
            help="Prediction t,theta \\[s, rad] (`lbr plan ... --prediction`), or a simulated execution log with --column."
        ),
    ],
    track: Annotated[Path, typer.Argument(help="Track CSV from `lbr track video` with a theta column.")],
    plot: Annotated[
        Optional[Path],
        typer.Option("--plot", help="PNG overlaying model and experiment θ \\[deg] over time, and their difference."),
    ] = None,
    lag: Annotated[
        Optional[float],
        number(
            "--lag",
            low=-86400,
            high=86400,
            unit="s",
            help="Track time − prediction time \\[s]; estimated from the model when omitted.",
        ),
    ] = None,
    max_lag: Annotated[
        Optional[float],
        number(
            "--max-lag",
            low=0,
            high=86400,
            low_open=True,
            unit="s",
            help="Search the lag only within ± this \\[s] (default: half the longer of the two series, at least 2 s; a better lag beyond it makes the lag ambiguous).",
        ),
    ] = None,
    flip: Annotated[
        bool,
        typer.Option(
            "--flip", help="Negate the track's θ (camera looking at the plane of motion from the other side)."
        ),
    ] = False,
    column: Annotated[
        str,
        typer.Option(
            "--column", help="Angle column \\[rad] of the prediction file (e.g. ball_theta in an execution log)."
        ),
    ] = "theta",
    partial: Annotated[
        bool,
        typer.Option(
            "--partial",
            help="Compare even when the track covers less than half of the prediction, or the execution log's session stopped early (refused otherwise).",
        ),
    ] = False,
    json_out: JsonOpt = False,
) -> None:
    """Compare the model's θ with the tracked θ: align in time, report RMS and max error over the overlap.

    Lag convention: track time = prediction time + lag. The lag is the one at which the model explains the
    whole track best: inside the overlap by the squared difference, and the tracked frames the model does not
    cover count half their own square as misfit (a shift that overlaps only part of the clip pays for the
    rest). The best other lag (a steady swing matches itself one period off) is reported; when its RMS misfit is
    within 1.5× of the best's, or the best lies on the edge of the window, or a better one lies beyond the
    default window, the lag is ambiguous: the figures are printed and the exit code is 1 — give --lag, or a
    --max-lag that leaves one candidate. Uneven frame times (dropped frames, jitter) and frames without θ are
    counted and warned about. Frames where the ball (or pivot) was not found are skipped. A cup-and-ball
    prediction (`lbr plan cup-and-ball --prediction`, with phase, ball and anchor columns) against a track with a
    pivot marker is also compared by position where its string is slack (the free flight; the track has no θ
    there): the image scale is the tracked string length over the model's. Exit 1 when prediction and track do
    not overlap, the lag is ambiguous, or (without --partial) the overlap covers less than half of the prediction —
    the experiment stopped early, or the files do not belong together; exit 2 for an execution log (--column)
    whose session did not complete, without --partial.
    """
    import math

    import numpy as np

    from trajectories.csvio import PREDICTION_COLUMNS, read_table
    from trajectories.errors import CheckFailed, CsvFormatError, OptionError
    from tracking.compare import AMBIGUOUS_RMS_RATIO, LAG_SETTING, compare_angles
    from tracking.samples import sample_report
    from tracking.trackfile import read_track_csv

    from ..console import Reporter
    from ..option_groups import settings_named
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
        require_complete(pred, partial, rep, option="--partial")
    t_model, theta_model = pred.column("t"), pred.column(column)
    known = np.isfinite(theta_model)  # an execution log's pendulum columns are nan before the first reading
    t_model, theta_model = t_model[known], theta_model[known]
    if len(t_model) < 2:
        raise CsvFormatError("need at least 2 samples", file=pred.path)
    tr = read_track_csv(track)
    if tr.theta is None:
        raise CsvFormatError("no 'theta' column: track the video with --pivot or --pivot-color", file=tr.path, row=1)

    with settings_named({LAG_SETTING: "--lag"}):  # the library names the setting, the user sees the option
        cmp = compare_angles(t_model, theta_model, tr.t, tr.theta, lag_s=lag, flip=flip, max_lag_s=max_lag)
    how = f"estimated within ±{cmp.lag_window_s:.2f} s" if cmp.lag_estimated else "given"
    rep.print(f"lag {cmp.lag_s:+.4f} s ({how}; track time = prediction time + lag)")
    ambiguous_why = None
    if cmp.lag_estimated:
        rep.print(f"model fit over the whole track: RMS {cmp.rms_fit_deg:.3f}° (score {cmp.correlation:.3f})")
        if math.isfinite(cmp.rival_lag_s):
            rep.print(
                f"next best peak at {cmp.rival_lag_s:+.3f} s: RMS {cmp.rival_rms_fit_deg:.3f}° (score {cmp.rival_correlation:.3f})"
            )
        if cmp.ambiguous:
            if abs(cmp.rival_lag_s) > cmp.lag_window_s:
                ambiguous_why = (
                    f"a lag of {cmp.rival_lag_s:+.3f} s beyond the default window ±{cmp.lag_window_s:.2f} s fits "
                    f"{'better' if cmp.rival_rms_fit_deg < cmp.rms_fit_deg else 'nearly as well'}"
                )
            elif math.isfinite(cmp.rival_lag_s) and cmp.rival_rms_fit_deg <= AMBIGUOUS_RMS_RATIO * cmp.rms_fit_deg:
                ambiguous_why = f"{cmp.rival_lag_s:+.3f} s fits nearly as well as {cmp.lag_s:+.3f} s"
            else:
                ambiguous_why = (
                    f"the best lag {cmp.lag_s:+.3f} s lies on the edge of the window ±{cmp.lag_window_s:.2f} s"
                )
    samples = sample_report(tr.t, tr.theta)
    if samples.uneven:
        rep.warn(
            f"uneven frame times in {track}: {samples.dropped_frames} frames dropped (longest interval "
            f"{samples.longest_gap_s * 1e3:.1f} ms, median {samples.median_interval_s * 1e3:.1f} ms), timing jitter "
            f"{100 * samples.jitter:.0f} %"
        )
    if samples.incomplete:
        rep.warn(
            f"{samples.missing} of {samples.frames} frames have no θ (ball or pivot not found, or unsure); longest run "
            f"{samples.longest_missing_s:.3f} s"
        )
    rep.print(
        f"over {cmp.overlap_s:.3f} s ({cmp.samples} frames): RMS error {cmp.rms_deg:.3f}°, max {cmp.max_deg:.3f}°"
    )
    if cmp.mirrored:
        rep.warn(
            "the track's θ matches the prediction much better negated: the camera sees the motion mirrored — try --flip"
        )
    span = float(t_model[-1] - t_model[0])
    coverage = cmp.overlap_s / span if span > 0 else 0.0
    short = coverage < MIN_COVERAGE
    if short:
        rep.warn(f"the track covers {cmp.overlap_s:.2f} s of the {span:.2f} s prediction ({coverage * 100:.0f} %)")
    positions = _slack_positions(pred, tr, cmp.lag_s, flip) if column == "theta" else None
    if positions is not None:
        if positions.frames:
            rep.print(
                f"slack string (free flight) over {positions.frames} frames: ball position RMS error "
                f"{1e3 * positions.rms_m:.1f} mm, max {1e3 * positions.max_m:.1f} mm (scale "
                f"{positions.px_per_m:.0f} px/m from the string's length)"
            )
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
            "lag_ambiguous": cmp.ambiguous,
            "rival_lag_s": cmp.rival_lag_s,
            "rival_score": cmp.rival_correlation,
            "fit_rms_deg": cmp.rms_fit_deg,
            "rival_fit_rms_deg": cmp.rival_rms_fit_deg,
            "rms_deg": cmp.rms_deg,
            "max_deg": cmp.max_deg,
            "overlap_s": cmp.overlap_s,
            "samples": cmp.samples,
            "score": cmp.correlation,
            "mirrored": cmp.mirrored,
            "flipped": flip,
            "track_frames": int(len(tr.t)),
            "track_theta_frames": int(np.isfinite(tr.theta).sum()),
            "frame_interval_s": samples.median_interval_s,
            "frames_dropped": samples.dropped_frames,
            "longest_interval_s": samples.longest_gap_s,
            "timing_jitter": samples.jitter,
            "frames_without_theta": samples.missing,
            "longest_without_theta_s": samples.longest_missing_s,
            "slack_position": None
            if positions is None
            else {
                "frames": positions.frames,
                "rms_m": positions.rms_m,
                "max_m": positions.max_m,
                "px_per_m": positions.px_per_m,
            },
            "coverage": coverage,
            "ok": (not short or partial) and ambiguous_why is None,
        }
    )
    if ambiguous_why is not None:  # first: the overlap (and so the coverage) depends on the lag
        raise CheckFailed(f"the lag is ambiguous: {ambiguous_why} — give --lag, or --max-lag around the expected delay")
    if short and not partial:
        raise CheckFailed(f"the track covers only {coverage * 100:.0f} % of the prediction ({cmp.overlap_s:.2f} of "
                          f"{span:.2f} s): the experiment stopped early or the files do not belong together; "
                          "--partial compares the overlap anyway")  # fmt: skip


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
    rel = np.column_stack(
        [pred.column("ball_y") - pred.column("anchor_y"), pred.column("ball_z") - pred.column("anchor_z")]
    )
    taut = phase == 0
    if not taut.any() or not (phase == 1).any():
        return None
    length = float(np.median(np.hypot(*rel[taut].T)))
    rel_px = tr.uv - tr.pivot_uv
    return compare_positions(
        pred.column("t"), rel, phase == 1, length, tr.t, rel_px, string_length_px(np.hypot(*rel_px.T)), lag, flip
    )


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    app.command("compare")(compare)
