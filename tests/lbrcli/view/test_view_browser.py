"""`lbr view` in a real headless browser: the offline file and the live server load without console errors, and
the arm and the ball stand where the files say (pinocchio's forward kinematics of the logged joints, the logged
ball angles) at two times chosen with the slider."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from lbrcli.fri.log import LOG_COLUMNS
from trajectories.csvio import read_table
from trajectories.robot import Robot

from lbrcli.view.testing import NODE_POSITION_JS, errors, node_position, page, status, status_time, wait_for_scene
from tests.helpers.browser import require_browser
from tests.helpers.run_files import LENGTH, run_files

FPS = 10.0  # a coarse replay: fewer messages for the software-rendered page


def _expected(log_path: Path, offset: float, tau: float) -> dict[str, np.ndarray]:
    """Where the measured arm's bodies and the simulated ball are at view time ``tau`` [s], from the log alone
    (linear interpolation between its rows, pinocchio's forward kinematics, the ball at TCP + L·s(θ, φ), or where the
    log's ball_x, ball_y, ball_z put it)."""
    log = read_table(log_path, LOG_COLUMNS, time="increasing")
    t = log.column("t") + offset
    q = np.array([np.interp(tau, t, log.column(f"msr_q{j}")) for j in range(1, 8)])
    robot = Robot()
    pin.framesForwardKinematics(robot.model, robot.data, q)
    theta, phi = (np.interp(tau, t, log.column(c)) for c in ("ball_theta", "ball_phi"))
    s = np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), -np.cos(theta)])
    tcp = robot.data.oMf[robot.tcp_id].translation
    out = {f"body{b}": robot.data.oMi[b].translation.copy() for b in (2, 4, 6)}
    out["body8"] = robot.data.oMf[robot.flange_id].translation.copy()
    if log.has("ball_x"):  # the simulator's string model logs where the ball is (slack strings too)
        out["ball"] = np.array([np.interp(tau, t, log.column(c)) for c in ("ball_x", "ball_y", "ball_z")])
    else:
        out["ball"] = tcp + LENGTH * s
    return out


def _settled_status(pg, ui_time, timeout: float = 120.0) -> str:
    """The status label once it shows the time the page's controls show (``ui_time()`` [s]) and stopped changing:
    the page has drawn what the slider asked for (software rendering applies messages a few frames later; the field shows 0.1 s)."""
    last, since = None, time.monotonic()
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        now = status(pg)
        if now != last:
            last, since = now, time.monotonic()
        elif time.monotonic() - since > 0.5 and now and abs(status_time(now) - ui_time()) <= 0.5 / FPS + 0.05:
            return now
        time.sleep(0.1)
    raise AssertionError(f"the scene did not settle at the slider's time: {last}, controls at {ui_time()}")


def _check_scene(pg, key: str, log: Path, offset: float, ui_time) -> float:
    """Assert the measured arm and the simulated ball against the log at the time the page reports; that time [s].
    Before and after the log the arm stands at its first/last row and the ball is not drawn."""
    tau = status_time(_settled_status(pg, ui_time))
    want = _expected(log, offset, tau)
    span = read_table(log, LOG_COLUMNS, time="increasing").column("t")[[0, -1]] + offset
    for name, where in want.items():
        node = f"/balls/{key}/ball_simulated" if name == "ball" else f"/arms/{key}/measured/{name}"
        got = pg.evaluate(NODE_POSITION_JS, node)
        assert got is not None, node
        if name == "ball" and not span[0] <= tau <= span[1]:
            assert got[3] is False, f"{node} drawn at t = {tau} s, outside the log"
            continue
        assert got[3] is True, f"{node} hidden at t = {tau} s"
        np.testing.assert_allclose(got[:3], where, atol=1e-4, err_msg=f"{node} at t = {tau} s")
    return tau


@pytest.mark.slow
def test_offline_file_draws_the_run_where_the_files_say_and_the_slider_moves_it(tmp_path, tmp_path_factory, capsys):
    require_browser()
    run = run_files(tmp_path_factory)
    out = tmp_path / "view.html"
    from lbrcli.app import main

    try:  # in this process: the command as a user runs it, without another interpreter's start-up
        main(
            [
                "view",
                *map(str, (run.plan, run.log, run.track, run.obstacles)),
                "-o",
                str(out),
                "--fps",
                str(FPS),
                "--json",
            ]
        )
    except SystemExit as ended:
        assert not ended.code, capsys.readouterr().err
    fig = json.loads(capsys.readouterr().out)
    offset = next(f["offset_s"] for f in fig["files"] if f["file"] == str(run.log))
    with page() as (pg, console):
        pg.goto(out.as_uri())
        wait_for_scene(pg, "/arms/log/measured/body4")
        field = pg.locator("input").first  # the player's time [s], next to its slider

        def ui_time() -> float:
            return float(field.input_value() or "nan")

        pg.keyboard.press("Space")  # pause the player first: a click while it plays is overtaken by its clock
        bar = pg.locator(".mantine-Slider-root").last
        box = bar.bounding_box()
        times, elbows = [], []
        for share in (0.25, 0.6):
            pg.mouse.click(box["x"] + share * box["width"], box["y"] + box["height"] / 2)
            times.append(_check_scene(pg, "log", run.log, offset, ui_time))
            elbows.append(node_position(pg, "/arms/log/measured/body4"))
        for share, tau in zip((0.25, 0.6), times):  # the slider's positions (its bar spans the recording)
            assert tau == pytest.approx(share * fig["duration_s"], abs=0.15)
        assert np.linalg.norm(elbows[1] - elbows[0]) > 0.01  # the slider moved the arm
        assert node_position(pg, "/obstacles/post") is not None
        assert errors(console) == []


@pytest.mark.slow
def test_live_view_serves_on_loopback_and_follows_its_slider(tmp_path_factory):
    require_browser()
    run = run_files(tmp_path_factory)
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "lbrcli",
            "view",
            str(run.plan),
            str(run.log),
            str(run.track),
            "--port",
            "0",
            "--fps",
            str(FPS),
            "--duration",
            "60",
            "--json",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        url, offset = None, None
        for line in proc.stderr:  # "…/log.csv: execution log, at +0.370 s: reference clock", then "view: URL"
            if line.startswith(f"{run.log}: execution log, at "):
                offset = float(line.split(" at ")[1].split(" s")[0])
            if line.startswith("view: "):
                url = line.split()[1]
                break
        assert url is not None and url.startswith("http://127.0.0.1:") and offset is not None, proc.stderr.read()
        with page() as (pg, console):
            pg.goto(url)
            wait_for_scene(pg, "/arms/log/measured/body4")
            pg.get_by_role("button", name="Pause").click()
            thumb = pg.get_by_role("slider").first
            thumb.focus()
            pg.keyboard.press("Home")

            def ui_time() -> float:
                return float(thumb.get_attribute("aria-valuenow") or "nan")

            first = _check_scene(pg, "log", run.log, offset, ui_time)
            for _ in range(12):
                pg.keyboard.press("ArrowRight")
            second = _check_scene(pg, "log", run.log, offset, ui_time)
            assert second - first == pytest.approx(12 / FPS, abs=1e-6)
            assert errors(console) == []
    finally:
        proc.send_signal(signal.SIGINT)
        stdout, _ = proc.communicate(timeout=20)
    assert proc.returncode == 130
    fig = json.loads(stdout)
    assert fig["url"] == url and fig["frames_shown"] >= 2
