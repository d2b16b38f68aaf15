"""`lbr track video` (ball centre and string angle per frame), `lbr track calibrate` (checkerboard camera calibration)
and `lbr track live` (the same tracker on a camera's stream)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

from ..fri_options import parse_host_port
from ..options import JsonOpt, choice, floats, grid, number


PivotOpt = Annotated[
    Optional[tuple],
    floats(
        "--pivot",
        count=2,
        low=0,
        high=100_000,
        unit="px",
        metavar="U,V",
        help="Fixed pivot (string attachment) U,V \\[px] in the image.",
    ),
]
PivotColorOpt = Annotated[
    Optional[str],
    typer.Option("--pivot-color", help="Colour of a marker on the pivot, tracked in every frame (e.g. green)."),
]
ColorOpt = Annotated[
    str,
    typer.Option(
        "--color",
        help="Ball colour: red, orange, yellow, green, cyan, blue, magenta, or an OpenCV hue range H1-H2 (0–179).",
    ),
]
RadiusOpt = Annotated[
    Optional[float],
    number(
        "--radius",
        low=0,
        high=10_000,
        low_open=True,
        unit="px",
        help="Approximate ball radius \\[px]: accept blobs of 0.3–3× its area (default: learned, from a 3 px ball to a radius of 1/6 of the frame height).",
    ),
]
CalibrationOpt = Annotated[
    Optional[Path],
    typer.Option(
        "--calibration",
        help="Camera JSON from `lbr track calibrate`: undistort points; with a plane, θ in the plane of motion and x_m,y_m \\[m].",
    ),
]
"""The ball and pivot options `lbr track video` and `lbr track live` share (one definition each)."""


def _check_out(path: Path | None, option: str) -> None:
    from trajectories.errors import OptionError

    if path is not None and not path.resolve().parent.is_dir():
        raise OptionError(f"{option}: folder does not exist: {path.parent}")


_COLOR_FLAGS = {"track_video.ball": "--color", "track_video.pivot_color": "--pivot-color"}


def _colors(color: str, pivot_color: str | None):  # noqa: ANN202
    """The ball's and the pivot marker's colour specs; an unknown colour is an OptionError naming its option."""
    from tracking.color import color_spec

    from ..option_groups import settings_named

    with settings_named(_COLOR_FLAGS):
        ball = color_spec(color, "track_video.ball")
        return ball, color_spec(pivot_color, "track_video.pivot_color") if pivot_color is not None else None


def video(
    video_path: Annotated[
        Path, typer.Argument(metavar="VIDEO", help="Experiment video (any format OpenCV/FFmpeg reads).")
    ],
    out: Annotated[
        Path,
        typer.Option(
            "-o", "--out", help="Track CSV to write: t,frame,u,v,found\\[,theta,...] \\[s, -, px, px, 0/1, rad]."
        ),
    ],
    pivot: PivotOpt = None,
    pivot_color: PivotColorOpt = None,
    color: ColorOpt = "red",
    radius: RadiusOpt = None,
    min_circularity: Annotated[
        float,
        number(
            "--min-circularity",
            low=0,
            high=1,
            help="Minimum 4π·area/perimeter² of the ball blob (disc ≈ 0.9, cable ≈ 0.1).",
        ),
    ] = 0.6,
    min_fit: Annotated[
        float,
        number(
            "--min-fit",
            low=0,
            high=1,
            help="Minimum overlap (IoU) of the blob with its moment ellipse (disc ≥ 0.9, any box ≈ 0.83).",
        ),
    ] = 0.88,
    calibration: CalibrationOpt = None,
    start: Annotated[
        Optional[tuple],
        floats(
            "--start",
            count=2,
            low=0,
            high=100_000,
            unit="px",
            metavar="U,V",
            help="Where the ball is when first seen, U,V \\[px]: the ball is the candidate nearest to it (names it among round objects of its colour).",
        ),
    ] = None,
    fps: Annotated[
        Optional[float],
        number(
            "--fps",
            low=0,
            high=100_000,
            low_open=True,
            unit="1/s",
            help="Capture frame rate \\[1/s] when the container's is wrong (slow-motion videos state their playback rate): times = frame / fps.",
        ),
    ] = None,
    min_saturation: Annotated[
        Optional[int],
        number(
            "--min-saturation",
            low=1,
            high=255,
            integer=True,
            help="Minimum HSV saturation of ball pixels (default 100, or 80 for green, cyan, blue); lowered automatically inside the search window for motion-blurred balls.",
        ),
    ] = None,
    min_found: Annotated[
        float,
        number(
            "--min-found",
            low=0,
            high=100,
            unit="%",
            help="Exit 1 with a warning when the ball is found in fewer than this share of frames \\[%].",
        ),
    ] = 90.0,
    plot: Annotated[
        Optional[Path],
        typer.Option("--plot", help="PNG of θ \\[deg] and u, v \\[px] over time with lost frames marked."),
    ] = None,
    preview: Annotated[
        Optional[Path],
        typer.Option("--preview", help="Video (mp4) with the detection drawn over it: ball circle, pivot, string, θ."),
    ] = None,
    candidates: Annotated[
        Optional[Path],
        typer.Option(
            "--candidates",
            help="PNG of the first frame with every ball-like blob circled and labelled U,V \\[px] (pick one for --start).",
        ),
    ] = None,
    slack: Annotated[
        bool,
        typer.Option(
            "--slack/--no-slack",
            help="With a pivot: frames where the ball is nearer to the pivot than the string's length (estimated from the track) are slack — position kept, θ left empty.",
        ),
    ] = True,
    json_out: JsonOpt = False,
) -> None:
    """Track a coloured ball in every frame of a video; θ from the pivot when one is known.

    Detection in HSV (red uses two hue bands), morphology, blobs gated by area, circularity and ellipse fit; the search
    runs in a window around a constant-velocity prediction with a full-frame fallback. Frames where the ball
    is not found are written with found = 0 and empty (nan) positions — never invented. Times are the
    decoder timestamps \\[s] (variable frame rates kept). θ = atan2(u_ball − u_pivot, v_ball − v_pivot) \\[rad]:
    0 hanging straight down, positive toward the right of the image; with a plane calibration θ is measured in
    the plane of motion (metric coordinates; the board's edges level and plumb), so an oblique camera does not
    bias it. When several round blobs of the ball's colour are seen at once, each is followed for a moment
    and the one moving like a pendulum about the pivot is kept (said in a warning); --start names the ball
    instead. Every fix has a confidence: a new lock until confirmed by steady motion, candidates being judged, a
    fix where the ball's colour has been static are unsure — written found = 0, unsure = 1 (columns confidence,
    unsure) — and a fix beyond the learned string length is rejected. Where the string is slack (the ball nearer to
    the pivot than the string's length) θ is left empty and the position kept (--no-slack: θ everywhere; not judged
    with a plane calibration). Exit 1 if the ball is found in fewer than --min-found percent of the frames, or the
    pivot marker in none.
    """
    import contextlib
    import math
    import time

    import numpy as np

    from trajectories.errors import OptionError
    from tracking.calibration import load_calibration
    from tracking.color import with_min_saturation
    from tracking.detect import BlobGates
    from tracking.pipeline import track_video
    from tracking.tracker import TrackerOptions
    from tracking.trackfile import write_track_csv
    from tracking.video import check_video_name, check_written, open_writer, probe_video

    from ..console import Reporter
    from ..outputs import atomic_path

    rep = Reporter(json_out)
    if pivot is not None and pivot_color is not None:
        raise OptionError("give either --pivot or --pivot-color, not both")
    ball_spec, piv_spec = _colors(color, pivot_color)
    if piv_spec is not None and piv_spec.bands == ball_spec.bands:
        raise OptionError("--pivot-color must differ from the ball's --color")
    piv_uv, start_uv = pivot, start
    if min_saturation is not None:
        ball_spec = with_min_saturation(ball_spec, min_saturation)
    for p, name in ((out, "--out"), (plot, "--plot"), (preview, "--preview"), (candidates, "--candidates")):
        _check_out(p, name)
    if preview is not None:
        check_video_name(preview, "--preview")
    options = _tracker_options(radius, min_circularity, min_fit, start_uv)
    gates = options.gates
    pivot_options = TrackerOptions(gates=BlobGates(min_circularity=min_circularity, min_ellipse_fit=min_fit))
    cal = load_calibration(calibration) if calibration is not None else None
    info = probe_video(video_path)
    for point, name in ((piv_uv, "--pivot"), (start_uv, "--start")):
        if point is not None and not (0 <= point[0] <= info.width and 0 <= point[1] <= info.height):
            raise OptionError(
                f"{name} {point[0]:g},{point[1]:g} is outside the {info.width}x{info.height} px image of {video_path}"
            )

    if candidates is not None:
        n_cand = _write_candidates(video_path, ball_spec, gates, candidates)
        rep.print(f"candidates: {n_cand} ball-like blobs in the first frame, drawn in {candidates}")

    t0 = time.perf_counter()
    with contextlib.ExitStack() as stack:  # the preview appears under its name only when complete and readable
        on_frame, writer, written = None, None, [0]
        if preview is not None:
            from tracking.overlay import draw_overlay

            preview_tmp = stack.enter_context(atomic_path(preview))
            writer = open_writer(preview_tmp, fps or info.fps, info.size, target=preview)
            stack.callback(writer.release)

            def on_frame(frame, res):  # noqa: ANN001
                b = res.ball
                draw_overlay(
                    frame, res.t, (b.u, b.v) if b else None, b.radius_px if b else None, res.pivot_uv, res.theta
                )
                writer.write(frame)
                written[0] += 1

        with rep.progress(f"tracking {video_path.name}", info.frame_count or None) as update:
            track = track_video(
                video_path,
                ball_spec,
                options=options,
                pivot_uv=piv_uv,
                pivot_color=piv_spec,
                pivot_options=pivot_options,
                calibration=cal,
                fps=fps,
                progress=update,
                on_frame=on_frame,
            )
        if writer is not None:
            writer.release()
            check_written(preview_tmp, written[0], preview)
    elapsed = time.perf_counter() - t0
    slack_info = None
    if slack and track.theta is not None and not track.theta_in_plane:  # (distances of an oblique image: not judged)
        from dataclasses import replace

        from tracking.slack import slack_frames

        mask, _, string_px = slack_frames(track.uv, track.pivot_uv if track.pivot_uv is not None else np.array(piv_uv))
        track = replace(track, theta=np.where(mask, np.nan, track.theta))
        slack_info = {"slack_frames": int(mask.sum()), "string_px": string_px}
    write_track_csv(out, track)

    n = len(track.t)
    found = int(track.found.sum())
    duration = float(track.t[-1]) if n else 0.0
    figures: dict = {
        "video": str(video_path),
        "out": str(out),
        "frames": n,
        "found": found,
        "found_percent": 100.0 * found / n if n else 0.0,
        "duration_s": duration,
        "fps_nominal": info.fps,
        "fps_measured": (n - 1) / duration if duration > 0 else math.nan,
        "width": info.width,
        "height": info.height,
        "ball_radius_px": float(np.nanmedian(track.radius_px)) if found else math.nan,
        "full_frame_searches": track.full_frame_searches,
        "processing_fps": n / elapsed if elapsed > 0 else math.nan,
        "fps_given": fps,
        "theta_in_plane": track.theta_in_plane,
        "ambiguities": list(track.notes),
    }
    rep.print(
        f"{video_path}: {n} frames over {duration:.3f} s ({info.width}x{info.height}, {figures['fps_measured']:.2f} fps); "
        f"ball found in {found} ({figures['found_percent']:.1f} %), radius ≈ {figures['ball_radius_px']:.1f} px; "
        f"tracked at {figures['processing_fps']:.0f} frames/s"
    )
    for note in track.notes:
        rep.warn(f"several ball-like blobs: {note}")
    _report_looks(rep, track, figures)
    if track.theta is not None:
        th = track.theta[np.isfinite(track.theta)]
        figures["theta_frames"] = int(len(th))
        figures["theta_min_deg"] = float(np.degrees(th.min())) if len(th) else math.nan
        figures["theta_max_deg"] = float(np.degrees(th.max())) if len(th) else math.nan
        where = "in the calibrated plane of motion" if track.theta_in_plane else "in the image"
        if len(th):
            rep.print(
                f"θ ({where}) in {len(th)} frames, from {figures['theta_min_deg']:.2f}° to {figures['theta_max_deg']:.2f}°"
            )
        else:
            rep.print("θ in no frame")
    if slack_info is not None:
        figures.update(slack_info)
        if slack_info["slack_frames"]:
            rep.print(
                f"string slack in {slack_info['slack_frames']} frames (ball nearer than the string's "
                f"{slack_info['string_px']:.1f} px): position only, no θ there"
            )
    if track.pivot_uv is not None:
        figures["pivot_found"] = int(np.all(np.isfinite(track.pivot_uv), axis=1).sum())
        rep.print(f"pivot marker found in {figures['pivot_found']} frames")
    if cal is not None and cal.plane is not None:
        figures["metres_per_px"] = cal.plane.metres_per_px
    rep.print(f"wrote {out}")
    if plot is not None:
        from ..plots.track import plot_track

        plot_track(track, plot, title=video_path.name)
        rep.print(f"plot: {plot}")
    if preview is not None:
        figures["preview"] = str(preview)
        rep.print(f"preview: {preview}")
    rep.emit(figures)
    if found == 0:
        rep.warn(
            f"the {color} ball was not found in any frame (try --color, --radius, --min-circularity, --min-fit or --min-saturation)"
        )
        raise typer.Exit(1)
    if figures["found_percent"] < min_found:
        rep.warn(
            f"the ball was found in only {figures['found_percent']:.1f} % of the frames (--min-found {min_found:g} %): "
            "check --color, --radius, --start and the lost frames in --plot or --preview"
        )
        raise typer.Exit(1)
    if track.pivot_uv is not None and figures["pivot_found"] == 0:
        rep.warn(
            f"the {pivot_color} pivot marker was not found in any frame: no θ (try another --pivot-color or --pivot U,V)"
        )
        raise typer.Exit(1)


def _report_looks(rep, track, figures: dict) -> None:  # noqa: ANN001
    """What the looks and checks after the first pass did (tracking.second_look, tracking.model_look,
    tracking.smoothing, tracking.pendulum_check): in the figures always, printed when they did something."""
    looks = {
        "second_look_frames": (
            track.second_look_frames,
            "second look: the ball found in {} more frames before confirmed stretches",
        ),
        "model_look_frames": (
            track.model_look_frames,
            "model look: {} frames placed by a pendulum fitted to the fixes around them, where the frame shows the ball",
        ),
        "outlier_frames": (
            track.outlier_frames,
            "outlier check: {} fixes off their neighbours' motion reported unsure (not found)",
        ),
        "smoothed_frames": (track.smoothed_frames, "smoothing: {} centres smoothed about the fixed pivot"),
        "off_pendulum_frames": (
            track.off_pendulum_frames,
            "pendulum check: {} fixes off the pendulum fitted over their second reported unsure (not found)",
        ),
        "on_pendulum_frames": (
            track.on_pendulum_frames,
            "pendulum check: {} noisy centres put on the pendulum fitted over their second",
        ),
    }
    unsure = int(track.unsure.sum()) if track.unsure is not None else 0
    figures.update({k: int(n) for k, (n, _) in looks.items()}, unsure_frames=unsure)
    for n, text in looks.values():
        if n:
            rep.print(text.format(n))
    if unsure:
        rep.print(f"{unsure} frames with a candidate not trusted: reported not found")


def _write_candidates(video_path: Path, spec, gates, png: Path) -> int:  # noqa: ANN001
    """Draw the first frame's ball-like blobs (strict gates) with their U,V into a PNG; how many there were."""
    from tracking.detect import coarse_factor, find_blobs_coarse
    from tracking.overlay import draw_candidates
    from tracking.video import iter_frames

    import cv2

    from trajectories.errors import OptionError

    from ..outputs import atomic_open

    for _, _, frame in iter_frames(video_path):
        blobs = find_blobs_coarse(frame, spec, gates, coarse_factor(frame.shape[1]))
        try:  # encoded in memory, written by Python: a full disk is an OSError, not a libpng message
            ok, data = cv2.imencode(png.suffix or ".png", draw_candidates(frame, blobs))
        except cv2.error:
            ok = False
        if not ok:
            raise OptionError(f"--candidates {png}: not an image format OpenCV writes (use .png or .jpg)")
        with atomic_open(png, "wb") as fh:
            fh.write(data.tobytes())
        return len(blobs)
    return 0


def calibrate(
    inputs: Annotated[
        list[Path],
        typer.Argument(metavar="IMAGES_OR_VIDEO...", help="Checkerboard images, folders of images, or videos."),
    ],
    out: Annotated[Path, typer.Option("-o", "--out", help="Camera calibration JSON to write.")],
    board: Annotated[
        tuple,
        grid(
            "--board",
            low=2,
            high=1000,
            metavar="COLSxROWS",
            help="Inner corners COLSxROWS of the checkerboard (a 10x7-square board is 9x6).",
        ),
    ] = "9x6",
    square: Annotated[
        float, number("--square", low=0, high=10, low_open=True, unit="m", help="Side of one square \\[m].")
    ] = 0.025,
    plane: Annotated[
        Optional[Path],
        typer.Option(
            "--plane",
            help="Image (or video: first frame with the board) of the board lying in the plane of motion: metres per pixel.",
        ),
    ] = None,
    stride: Annotated[
        int, number("--stride", low=1, high=100_000, integer=True, help="Use every N-th frame of videos.")
    ] = 15,
    max_views: Annotated[
        int,
        number(
            "--max-views",
            low=3,
            high=10_000,
            integer=True,
            help="At most this many views (evenly chosen) go into the calibration.",
        ),
    ] = 40,
    json_out: JsonOpt = False,
) -> None:
    """Camera calibration from checkerboard views (OpenCV findChessboardCorners, cornerSubPix, calibrateCamera).

    Reports the RMS reprojection error \\[px]. `lbr track video --calibration` then undistorts the tracked
    points; with --plane it also reports positions in metres in that plane.
    """
    import numpy as np

    from trajectories.errors import InputError
    from tracking.calibration import calibrate_camera, find_board, iter_images, plane_from_corners, save_calibration

    from ..console import Reporter

    rep = Reporter(json_out)
    cols_rows = board
    board = "x".join(map(str, board))
    _check_out(out, "--out")
    views: list[np.ndarray] = []
    names: list[str] = []
    rejected = 0
    size: tuple[int, int] | None = None
    with rep.progress("finding the board", None) as update:
        for name, img in iter_images(inputs, stride):
            h, w = img.shape[:2]
            if size is None:
                size = (w, h)
            elif size != (w, h):
                raise InputError(f"image is {w}x{h}, the first one was {size[0]}x{size[1]}", file=name)
            corners = find_board(img, cols_rows)
            if corners is None:
                rejected += 1
            else:
                views.append(corners)
                names.append(name)
            update(len(views) + rejected)
    if len(views) < 3:
        raise InputError(
            f"the {board} board was found in {len(views)} of {len(views) + rejected} views; need at least 3"
        )
    if len(views) > max_views:
        keep = np.round(np.linspace(0, len(views) - 1, max_views)).astype(int)
        views = [views[k] for k in keep]
    cal = calibrate_camera(views, size, cols_rows, square)
    if plane is not None:
        pl = None
        for name, img in iter_images([plane], 1):
            if img.shape[1::-1] != tuple(cal.image_size):
                raise InputError(
                    f"image is {img.shape[1]}x{img.shape[0]}, the calibration is for {size[0]}x{size[1]}", file=name
                )
            c = find_board(img, cols_rows)
            if c is not None:
                pl = plane_from_corners(cal, c)
                break
        if pl is None:
            raise InputError(f"the {board} board was not found", file=str(plane))
        cal = cal.with_plane(pl)
    save_calibration(out, cal)
    K = cal.camera_matrix
    rep.print(
        f"board {board} found in {len(names)} of {len(names) + rejected} views; {cal.views} used; "
        f"RMS reprojection error {cal.rms_px:.3f} px"
    )
    rep.print(
        f"fx {K[0, 0]:.1f} px, fy {K[1, 1]:.1f} px, cx {K[0, 2]:.1f} px, cy {K[1, 2]:.1f} px; "
        f"distortion {np.array2string(cal.dist_coeffs, precision=4)}"
    )
    if cal.rms_px > 1.0:
        rep.warn(f"reprojection error {cal.rms_px:.2f} px is high: check --board and the images")
    figures = {
        "out": str(out),
        "views_found": len(names),
        "views_rejected": rejected,
        "views_used": cal.views,
        "image_size": list(cal.image_size),
        "rms_px": cal.rms_px,
        "fx_px": K[0, 0],
        "fy_px": K[1, 1],
        "cx_px": K[0, 2],
        "cy_px": K[1, 2],
        "dist_coeffs": cal.dist_coeffs,
    }
    if cal.plane is not None:
        figures["metres_per_px"] = cal.plane.metres_per_px
        rep.print(f"plane of motion: {cal.plane.metres_per_px * 1e3:.4f} mm/px at the board centre")
    rep.print(f"wrote {out}")
    rep.emit(figures)


def live(
    source: Annotated[
        str,
        typer.Argument(
            metavar="SOURCE",
            help="Camera: a V4L2 device index (0) or path (/dev/video0), a stream URL (http://…/stream.mjpg, rtsp://…), or a video file played at its frame rate.",
        ),
    ],
    out: Annotated[
        Optional[Path],
        typer.Option(
            "-o",
            "--out",
            help="Track CSV as `track video` writes, plus theta_x,theta_y \\[rad], latency_s, t_source \\[s]; t from the first frame's capture.",
        ),
    ] = None,
    duration: Annotated[
        Optional[float],
        number(
            "--duration",
            low=0,
            high=86400,
            low_open=True,
            unit="s",
            help="Stop after this long \\[s] (default: when the source ends, or Ctrl-C).",
        ),
    ] = None,
    pivot: PivotOpt = None,
    pivot_color: PivotColorOpt = None,
    color: ColorOpt = "red",
    radius: RadiusOpt = None,
    calibration: CalibrationOpt = None,
    geometry: Annotated[
        Optional[Path],
        typer.Option(
            "--geometry",
            help="Camera pose JSON (tracking.camera_geometry: camera_matrix, rotation, centre_m — or position_m, look_at_m, fov_deg — and pivot_m, string_m): adds the tilt components θx, θy in the base frame.",
        ),
    ] = None,
    udp: Annotated[
        Optional[tuple],
        typer.Option(
            "--udp",
            parser=parse_host_port,
            metavar="HOST:PORT",
            help="Send every result to HOST:PORT as one UDP datagram (see --udp-format).",
        ),
    ] = None,
    udp_format: Annotated[
        str,
        choice(
            "--udp-format",
            choices=("binary", "json"),
            help="binary (64 bytes little-endian, layout in docs/guides/camera.md) or json.",
        ),
    ] = "binary",
    mqtt: Annotated[
        Optional[str],
        typer.Option(
            "--mqtt", help="Publish results as JSON to mqtt://HOST:PORT/TOPIC (at most --mqtt-rate per second)."
        ),
    ] = None,
    mqtt_rate: Annotated[
        float,
        number("--mqtt-rate", low=0, high=1000, low_open=True, unit="Hz", help="MQTT messages per second \\[Hz]."),
    ] = 50.0,
    fps: Annotated[
        Optional[float],
        number(
            "--fps",
            low=0,
            high=100_000,
            low_open=True,
            unit="1/s",
            help="Playback rate \\[1/s] of a video file SOURCE (default: its own).",
        ),
    ] = None,
    min_found: Annotated[
        float,
        number(
            "--min-found",
            low=0,
            high=100,
            unit="%",
            help="Exit 1 when the ball is found in fewer than this share of the tracked frames \\[%].",
        ),
    ] = 50.0,
    plot: Annotated[
        Optional[Path], typer.Option("--plot", help="PNG of θ and u, v over time, lost frames marked.")
    ] = None,
    json_out: JsonOpt = False,
) -> None:
    """Track the ball live in a camera's stream at the camera's rate; print latency and figures, publish results.

    The same tracker as `lbr track video` runs on the newest frame: when it falls behind, frames are dropped (counted),
    never queued. Each result has the frame's capture time and its latency (capture → result). With --udp every
    result leaves as one datagram; with --mqtt as JSON. θ comes from --pivot/--pivot-color (or the pivot of
    --geometry projected into the image); --geometry also gives θx, θy toward base +x, +y. Exit 1 when no frame
    arrives or the ball is found in fewer than --min-found percent of the tracked frames; 2 when SOURCE cannot be
    opened.
    """
    import math
    import signal
    import time

    import numpy as np

    from trajectories.errors import OptionError
    from tracking.calibration import load_calibration
    from tracking.camera_geometry import load_geometry
    from tracking.live import LiveTracker, TiltSetup, track_from_results
    from tracking.trackfile import write_track_csv

    from ..console import Reporter

    rep = Reporter(json_out)
    if pivot is not None and pivot_color is not None:
        raise OptionError("give either --pivot or --pivot-color, not both")
    for p, name in ((out, "--out"), (plot, "--plot")):
        _check_out(p, name)
    ball_spec, piv_spec = _colors(color, pivot_color)
    piv_uv = pivot
    options = _tracker_options(radius, 0.6, 0.88, None)
    cal = load_calibration(calibration) if calibration is not None else None
    tilt = None
    if geometry is not None:
        geo, d = load_geometry(geometry)
        if "pivot_m" not in d or "string_m" not in d:
            raise OptionError(f"--geometry {geometry}: needs pivot_m [x,y,z] and string_m for the tilt")
        tilt = TiltSetup(geo, tuple(float(x) for x in d["pivot_m"]), float(d["string_m"]))
    udp_pub = mqtt_pub = None
    if udp is not None:
        from ..lab.camera_publish import UdpPublisher

        host, port = udp
        udp_pub = UdpPublisher(host.strip("[]"), port, udp_format)
    if mqtt is not None:
        from ..lab.telemetry import TelemetryPublisher, parse_mqtt_url

        mqtt_pub = TelemetryPublisher(parse_mqtt_url(mqtt, "--mqtt"), mqtt_rate)
    results = []

    def on_result(r) -> None:  # noqa: ANN001
        results.append(r)
        if udp_pub is not None:
            udp_pub.publish(r)
        if mqtt_pub is not None and mqtt_pub.due(r.t_capture):
            from ..lab.camera_publish import result_dict

            mqtt_pub.offer(r.t_capture, lambda r=r: result_dict(r))

    tracker = LiveTracker(
        source,
        ball_spec,
        options=options,
        pivot_uv=piv_uv,
        pivot_color=piv_spec,
        tilt=tilt,
        calibration=cal,
        on_result=on_result,
        file_fps=fps,
    )
    interrupted = False

    def _interrupt(signum, frame) -> None:  # noqa: ANN001
        nonlocal interrupted
        interrupted = True

    old_handler = signal.signal(signal.SIGINT, _interrupt)
    tracker.start()
    if mqtt_pub is not None:
        mqtt_pub.start()
    t0 = time.monotonic()
    try:
        while tracker.running and not interrupted and (duration is None or time.monotonic() - t0 < duration):
            time.sleep(0.02)
    finally:
        tracker.stop()
        signal.signal(signal.SIGINT, old_handler)
        if udp_pub is not None:
            udp_pub.close()
        if mqtt_pub is not None:
            mqtt_pub.stop()
    elapsed = time.monotonic() - t0
    st = tracker.stats
    lat = np.array(st.latency_s) * 1e3
    trk = np.array(st.track_s) * 1e3

    def pct(a, q):  # noqa: ANN001
        return float(np.percentile(a, q)) if len(a) else math.nan

    n = st.tracked
    figures = {
        "source": str(source),
        "frames_read": st.read,
        "frames_tracked": n,
        "frames_dropped": st.dropped,
        "found": st.found,
        "found_percent": 100.0 * st.found / n if n else 0.0,
        "duration_s": elapsed,
        "rate_fps": n / elapsed if elapsed > 0 else math.nan,
        "source_fps": st.read / elapsed if elapsed > 0 else math.nan,
        "width": tracker.size[0] if tracker.size else None,
        "height": tracker.size[1] if tracker.size else None,
        "latency_ms_p50": pct(lat, 50),
        "latency_ms_p95": pct(lat, 95),
        "latency_ms_p99": pct(lat, 99),
        "latency_ms_max": float(lat.max()) if len(lat) else math.nan,
        "track_ms_p50": pct(trk, 50),
        "track_ms_p99": pct(trk, 99),
        "udp_sent": udp_pub.sent if udp_pub else 0,
        "mqtt_published": mqtt_pub.published if mqtt_pub else 0,
        "interrupted": interrupted,
        "errors": st.errors,
    }
    rep.print(
        f"{source}: {st.read} frames read in {elapsed:.2f} s ({figures['source_fps']:.1f} fps), {n} tracked, "
        f"{st.dropped} dropped while busy; ball found in {st.found} ({figures['found_percent']:.1f} %)"
    )
    if n:
        rep.print(
            f"latency capture → result: p50 {figures['latency_ms_p50']:.2f} ms, p95 {figures['latency_ms_p95']:.2f} ms, "
            f"max {figures['latency_ms_max']:.2f} ms; tracking p50 {figures['track_ms_p50']:.2f} ms per frame"
        )
    th = np.array([r.theta for r in results])
    if np.isfinite(th).any():
        figures["theta_min_deg"] = float(np.degrees(np.nanmin(th)))
        figures["theta_max_deg"] = float(np.degrees(np.nanmax(th)))
        rep.print(f"θ from {figures['theta_min_deg']:.2f}° to {figures['theta_max_deg']:.2f}°")
    for e in st.errors:
        rep.warn(e)
    if results and (out is not None or plot is not None):
        track = track_from_results(
            results,
            source,
            tracker.size,
            tracker.fps_nominal,
            piv_uv is not None or piv_spec is not None or tilt is not None,
        )
        if out is not None:
            write_track_csv(out, track)
            figures["out"] = str(out)
            rep.print(f"wrote {out}")
        if plot is not None:
            from ..plots.track import plot_track

            plot_track(track, plot, title=str(source))
            figures["plot"] = str(plot)
            rep.print(f"plot: {plot}")
    rep.emit(figures)
    if n == 0:
        rep.warn(f"no frame was tracked from {source}")
        raise typer.Exit(1)
    if figures["found_percent"] < min_found:
        rep.warn(
            f"the ball was found in only {figures['found_percent']:.1f} % of the frames (--min-found {min_found:g} %)"
        )
        raise typer.Exit(1)


def _tracker_options(radius: float | None, min_circularity: float, min_fit: float, start_uv):  # noqa: ANN001
    """TrackerOptions from the shared command-line options, checked at parse time (gates for a given radius, or
    learned)."""
    from tracking.detect import BlobGates
    from tracking.tracker import TrackerOptions

    shape = {"min_circularity": min_circularity, "min_ellipse_fit": min_fit}
    if radius:
        return TrackerOptions(
            gates=BlobGates.for_radius(radius, **shape),
            start_uv=start_uv,
            max_radius_share=None,
            tiny_search=radius < 3.0,
        )
    return TrackerOptions(gates=BlobGates(**shape), start_uv=start_uv)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    groups["track"].command("video")(video)
    groups["track"].command("calibrate")(calibrate)
    groups["track"].command("live")(live)
