"""`lbr demo` end to end on the built-in simulator: the user's whole loop, asserting its real outcomes."""

import json
import pytest
import sys
import subprocess


@pytest.mark.slow
def test_demo_runs_the_whole_loop(tmp_path):
    out = tmp_path / "demo"
    res = subprocess.run(
        [sys.executable, "-m", "lbrcli", "demo", "--out", str(out), "--json"],
        capture_output=True,
        text=True,
        timeout=1200,
    )
    assert res.returncode == 0, res.stderr[-3000:]
    f = json.loads(res.stdout)
    assert f["ok"] and not f["steps_failed"]
    base, shaped = f["crane_baseline"], f["crane_shaped"]
    # both crane plans pass the check; the shaped move is faster and leaves no sway on the simulated ball
    assert base["limits_ok"] and shaped["limits_ok"]
    assert shaped["duration_s"] < base["duration_s"]
    # the robust default (±10 % string length) trades a little nominal sway for robustness: the plan predicts it and
    # the simulated ball shows it
    assert shaped["executed_residual_sway_deg"] < 0.3
    assert abs(shaped["executed_residual_sway_deg"] - shaped["predicted_residual_sway_deg"]) < 0.05
    assert shaped["executed_peak_sway_deg"] > 1.0  # the ball really swung during the move
    # the swing-up reaches θ_d on the simulator too
    assert f["swingup"]["reached"] and f["swingup"]["executed_max_theta_deg"] > 113
    # the rendered ball is tracked back to within the tracking goals
    assert f["tracking"]["found_fraction"] >= 0.99
    assert f["tracking"]["centre_rms_px"] <= 0.5 and f["tracking"]["theta_rms_deg"] <= 0.2
    # model and "experiment" agree once aligned
    assert f["compare"]["rms_deg"] < 1.0 and f["compare"]["overlap_s"] > 1.0
    # the cup-and-ball game: planned, caught on the simulator when the plan said, the flight filmed and tracked
    catch = f["catch"]
    assert catch["caught"] and catch["executed_stayed"]
    assert abs(catch["executed_entered_s"] - catch["catch_time_s"]) < 0.03
    assert catch["flight_position_rms_m"] < 0.005
    summary = (out / "summary.md").read_text()
    assert "lbr execute crane_shaped.csv" in summary and "FAILED" not in summary
    for name in (
        "crane_baseline_log.csv",
        "crane_shaped_execution.png",
        "swingup.mp4",
        "swingup_compare.png",
        "catch.mp4",
        "catch_plan.png",
        "catch_compare.png",
    ):
        assert (out / name).stat().st_size > 1000


def test_demo_bad_out_folder_is_one_line_exit_2(tmp_path, lbr):
    blocker = tmp_path / "a_file"
    blocker.write_text("x")
    res = lbr("demo", "--out", blocker)
    assert res.returncode == 2 and "Traceback" not in res.stderr
    assert res.stderr.strip().splitlines() == [f"lbr: error: --out: {blocker} exists and is not a folder"]


def test_demo_refuses_a_folder_that_holds_other_work(tmp_path, lbr):
    work = tmp_path / "thesis"
    work.mkdir()
    (work / "notes.txt").write_text("mine")
    res = lbr("demo", "--out", work)
    assert res.returncode == 2 and "holds no previous demo" in res.stderr
    assert [p.name for p in work.iterdir()] == ["notes.txt"]
