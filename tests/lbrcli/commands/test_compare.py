"""`lbr compare` end to end: a video rendered from a model with a known delay, tracked, compared."""

import json
import math

import numpy as np
import pytest

from trajectories.csvio import write_table
from tests.helpers.cli import one_line_error
from tracking.synthetic import render_pendulum_video

LAG = 0.45  # [s] the video starts this long before the modelled motion
FRAME_S = 1.0 / 60.0
OMEGA = math.sqrt(9.81 / 0.25)


def model(t):
    """Still until 0.3 s, then a sway that builds up (as after an unshaped crane move) [rad]."""
    s = np.clip(t - 0.3, 0.0, None)
    return 0.4 * (1 - np.exp(-s / 0.5)) * np.sin(OMEGA * s)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    from tests.helpers.cli import run_lbr

    d = tmp_path_factory.mktemp("cmp")
    t_model = np.arange(0.0, 3.0 + 1e-9, 0.002)
    pred = d / "pred.csv"
    write_table(pred, ("t", "theta"), np.column_stack([t_model, model(t_model)]), ["%.6f", "%.9f"])
    t_video = np.arange(0.0, 3.6, 0.001)
    render_pendulum_video(d / "exp.mp4", t_video, model(t_video - LAG), (320, 40), 220.0, 6.0, (640, 360), seed=2)
    res = run_lbr("track", "video", d / "exp.mp4", "-o", d / "track.csv", "--pivot", "320,40")
    assert res.returncode == 0, res.stderr
    return pred, d / "track.csv"


@pytest.mark.heavy
def test_compare_recovers_lag_json_plot(lbr, files, tmp_path):
    pred, track = files
    plot = tmp_path / "cmp.png"
    res = lbr("compare", pred, track, "--plot", plot, "--json")
    assert res.returncode == 0, res.stderr
    fig = json.loads(res.stdout)
    assert abs(fig["lag_s"] - LAG) <= FRAME_S
    assert fig["rms_deg"] < 0.2 and fig["max_deg"] < 0.6
    assert fig["overlap_s"] == pytest.approx(3.0, abs=0.02) and fig["samples"] >= 175
    assert fig["mirrored"] is False and fig["lag_estimated"] is True
    assert plot.stat().st_size > 10_000


def test_a_constant_prediction_names_the_lag_option(lbr, files, tmp_path):
    """The library names the setting (compare_angles.lag_s); the user's error line names the option."""
    _, track = files
    flat = tmp_path / "flat.csv"
    t = np.arange(0.0, 3.0, 0.01)
    write_table(flat, ("t", "theta"), np.column_stack([t, np.zeros_like(t)]), ["%.6f", "%.9f"])
    assert "a θ series is constant (give --lag)" in one_line_error(lbr("compare", flat, track), code=1)


def test_given_lag_and_wrong_lag(lbr, files):
    pred, track = files
    good = json.loads(lbr("compare", pred, track, "--lag", str(LAG), "--json").stdout)
    bad = json.loads(lbr("compare", pred, track, "--lag", str(LAG + 0.1), "--json").stdout)
    assert good["lag_estimated"] is False and good["rms_deg"] < 0.2
    assert bad["rms_deg"] > 5 * good["rms_deg"]
    res = lbr("compare", pred, track, "--lag", "100")
    assert res.returncode == 1 and "no overlap" in res.stderr


def test_mirrored_camera_warns_and_flip(lbr, files, tmp_path):
    pred, track = files
    lines = track.read_text().splitlines()
    col = lines[0].split(",").index("theta")
    out = [lines[0]]
    for line in lines[1:]:
        cells = line.split(",")
        cells[col] = str(-float(cells[col]))
        out.append(",".join(cells))
    mirrored = tmp_path / "mirrored.csv"
    mirrored.write_text("\n".join(out) + "\n")
    res = lbr("compare", pred, mirrored)
    assert res.returncode == 0 and "--flip" in res.stderr
    fig = json.loads(lbr("compare", pred, mirrored, "--flip", "--json").stdout)
    assert abs(fig["lag_s"] - LAG) <= FRAME_S and fig["rms_deg"] < 0.2 and fig["flipped"] is True


def test_log_column(lbr, files, tmp_path):
    pred, track = files
    t = np.arange(0.0, 3.0, 0.001)
    log = tmp_path / "log.csv"
    write_table(log, ("t", "state", "ball_theta"), np.column_stack([t, np.full_like(t, 4), model(t)]))
    fig = json.loads(lbr("compare", log, track, "--column", "ball_theta", "--json").stdout)
    assert abs(fig["lag_s"] - LAG) <= FRAME_S
    assert "no column 'theta_x'" in one_line_error(lbr("compare", log, track, "--column", "theta_x"))


def test_bad_files_exit_2(lbr, files, tmp_path):
    pred, track = files
    no_theta = tmp_path / "no_theta.csv"
    no_theta.write_text("t,frame,u,v,found\n0,0,1,2,1\n0.1,1,,,0\n")
    assert "no 'theta' column" in one_line_error(lbr("compare", pred, no_theta))
    bad_found = tmp_path / "bad_found.csv"
    bad_found.write_text("t,frame,u,v,found,theta\n0,0,1,2,1,0.1\n0.1,1,1,2,2,0.1\n")
    line = one_line_error(lbr("compare", pred, bad_found))
    assert "row 3" in line and "found" in line
    wrong = tmp_path / "wrong.csv"
    wrong.write_text("t,angle\n0,0\n0.1,0.2\n")
    assert "expected 'theta'" in one_line_error(lbr("compare", wrong, track))
    assert "file not found" in one_line_error(lbr("compare", tmp_path / "none.csv", track))


def test_lag_window_and_rival_reported(lbr, files):
    pred, track = files
    fig = json.loads(lbr("compare", pred, track, "--json").stdout)
    assert fig["lag_window_s"] == pytest.approx(2.0)  # half of the 3.6 s track, at least 2 s
    assert fig["rival_lag_s"] is not None and abs(fig["rival_lag_s"] - fig["lag_s"]) >= 0.15
    assert fig["rival_score"] < fig["score"] - 0.02  # a growing sway: one period off matches clearly worse
    res = lbr("compare", pred, track)
    assert "estimated within ±2.00 s" in res.stdout and "next best peak" in res.stdout
    fig = json.loads(lbr("compare", pred, track, "--max-lag", "0.3", "--json").stdout)
    assert fig["lag_window_s"] == 0.3 and abs(fig["lag_s"]) <= 0.3 + 1e-9


def test_non_finite_lag_options_exit_2(lbr, files):
    pred, track = files
    assert "--lag" in one_line_error(lbr("compare", pred, track, "--lag", "nan"))
    assert "--max-lag" in one_line_error(lbr("compare", pred, track, "--max-lag", "nan"))
