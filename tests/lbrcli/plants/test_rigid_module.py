"""The simulated pendulum module (lbrcli.plants.rigid_module) and `lbr control upright` on the simulator."""

from __future__ import annotations

import csv
import json
import math
import os

import numpy as np
import pytest

from tests.helpers.cli import Q_START, run_lbr
from lbrcli.fri.sim import PlantContext
from lbrcli.lab.pendulum_serial import parse_line
from lbrcli.plants.rigid_module import RigidModuleSpec
from planners.rigid_pendulum import RigidPendulum
from trajectories.errors import OptionError


def _read_lines(fd: int) -> list[bytes]:
    data = b""
    while True:
        try:
            chunk = os.read(fd, 4096)
        except BlockingIOError:
            break
        if not chunk:
            break
        data += chunk
    return [x for x in data.split(b"\n") if x]


def test_the_module_swings_in_the_y_z_plane_and_its_encoder_lines_arrive_late_and_quantised(robot):
    """Stand-alone: the TCP accelerates along +y at the thesis pose (flange along +x): the rod swings to −y; the
    serial lines carry 12-bit counts of the angle one delay earlier."""
    h = 1e-3
    spec = RigidModuleSpec(RigidPendulum(rod_length=0.5), rate_hz=250.0, delay_ms=8.0, jitter_ms=0.0)
    plant = spec.build(PlantContext(h, robot, tuple(Q_START.tolist())))
    fd = os.open(plant.info()["pendulum_path"], os.O_RDONLY | os.O_NONBLOCK)
    try:
        pose = robot.fk(Q_START)
        p0, rot = pose.translation.copy(), pose.rotation.copy()
        truth, lines = [], []
        for k in range(1, 400):
            t = k * h
            tcp = p0 + np.array([0.0, 0.5 * 3.0 * min(t, 0.2) ** 2 + 3.0 * 0.2 * max(t - 0.2, 0.0), 0.0])
            phi, _ = plant.step(t, tcp.tolist(), rot)
            truth.append(phi)
            for line in _read_lines(fd):
                lines.append((k, parse_line(line)[0]))
    finally:
        os.close(fd)
        plant.close()
    truth = np.array(truth)
    assert truth[190] < -0.05  # accelerating toward +y swings the rod toward −y
    assert len(lines) >= 90
    for k, theta in lines[5:]:
        # the reading is the angle 8 ms (8 cycles) before it arrived, within half a count of 12 bits
        assert abs(theta - truth[k - 1 - 8]) <= math.pi / 4096 + 1e-4
    assert len({round(th * 4096 / (2 * math.pi)) for _, th in lines}) > 10


def test_a_vertical_axis_and_bad_options_are_refused(robot):
    down = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)  # the flange points up: its axis is vertical
    with pytest.raises(OptionError, match="vertical"):
        RigidModuleSpec().build(PlantContext(1e-3, robot, down))
    for bad in (
        RigidModuleSpec(rate_hz=0.0),
        RigidModuleSpec(delay_ms=-1.0),
        RigidModuleSpec(pushes=((-1.0, 0.1),)),
        RigidModuleSpec(pendulum=RigidPendulum(rod_length=0.0)),
    ):
        with pytest.raises(OptionError):
            bad.validate()


def _log(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    head = rows[0]
    data = np.array([[float(x) if x else math.nan for x in r] for r in rows[1:]])
    return {n: data[:, i] for i, n in enumerate(head)}


@pytest.mark.slow  # an end-to-end run of ≈ 40 s; beside other work it sometimes falls once even in lock-step (open)
def test_lbr_control_upright_swings_up_balances_and_survives_a_push(tmp_path):
    log = tmp_path / "up.csv"
    plot = tmp_path / "up.png"
    # a rod 15 % shorter than the model says, some dry friction, encoder noise: the identification finds it
    p = run_lbr("control", "upright", "--sim-lockstep", "--port", "0", "--rod-length", "0.4", "--sim-rod-length", "0.34", "--sim-friction", "0.02",
                "--sim-noise", "1", "--hold", "12", "--push", "-10deg@13.5", "--sim-delay", "8", "--log", log,
                "--plot", plot, "--json", timeout=180)  # fmt: skip
    assert p.returncode == 0, p.stderr
    fig = json.loads(p.stdout)
    assert fig["outcome"] == "completed" and fig["succeeded"] and fig["falls"] == 0
    assert abs(fig["identified_length_m"] - 2 / 3 * 0.34) < 0.005  # the simulated rod's, not the model's
    assert 0 < fig["swing_up_s"] < 8 and fig["longest_balance_s"] >= 8
    d = _log(log)
    up = np.degrees(np.abs(np.angle(np.exp(1j * (d["pendulum_phi"] - np.pi)))))
    t, mode = d["t"], d["mode"]
    bal = np.flatnonzero(mode == 1)
    push_t = t[0] + 13.5
    assert t[bal[0]] < push_t - 2.0  # caught well before the push
    assert up[(t > t[bal[0]] + 1.5) & (t < push_t - 0.05)].max() < 3.0  # balanced (simulated truth)
    assert up[(t > push_t - 0.05) & (t < push_t + 0.5)].max() > 8.0  # the push …
    assert up[(t > push_t + 2.0) & (t <= t[bal[-1]])].max() < 3.0  # … was caught
    # the commands stayed within the joint limits
    from trajectories.limits import default_limits

    lim = default_limits()
    q = np.column_stack([d[f"cmd_q{j}"] for j in range(1, 8)])[d["state"] == 4]
    assert np.all(np.abs(np.diff(q, axis=0)) / 1e-3 <= lim.velocity)
    assert np.all(np.abs(np.diff(q, 2, axis=0)) / 1e-6 <= lim.acceleration)
    # lowered, not dropped: after the hold the rod comes down in swings that shrink, and ends near hanging
    low = np.flatnonzero(mode == 3)
    assert len(low) and abs(np.degrees(np.angle(np.exp(1j * d["pendulum_phi"][-1])))) < 20.0
    assert plot.stat().st_size > 10_000


# lock-step as fast as computed (--sim-fast): which failure, not when — the same encoder lines as --sim-lockstep. One
# session per case (they were one test of ≈ 40 s at load 3, the longest of the suite, which bounded `-n 2`'s wall time)
UPRIGHT_FAILURES = {
    # the give-up, not the identification (the next two cases need it): --no-identify skips its push, ≈ 8 s simulated
    "no catch": (("--swing-timeout", "1", "--no-identify"), "no catch upright within 1 s"),
    "encoder sign": (("--sim-encoder-sign", "-1"), "--encoder-sign -1"),  # detected from the push, not guessed
    # a rod whose period is not the model's (--rod-length 0.9, the simulated rod 0.4 m): the line names the flag
    "rod length": (("--rod-length", "0.9", "--sim-rod-length", "0.4"), "check --rod-length"),
}


@pytest.mark.heavy
@pytest.mark.parametrize("case", UPRIGHT_FAILURES)
def test_lbr_control_upright_fails_when_it_cannot_catch(case):
    args, text = UPRIGHT_FAILURES[case]
    p = run_lbr("control", "upright", "--sim-fast", "--port", "0", *args, "--hold", "5", timeout=120)
    assert p.returncode == 1 and text in p.stderr, p.stderr


def test_lbr_control_upright_refuses_bad_input():
    for args, text in ((("--rod-length", "0"), "--rod-length"), (("--push", "10deg"), "--push"),
                       (("--robot", "192.0.2.1"), "--pendulum PORT"), (("--push", "10deg@3", "--robot", "192.0.2.1",
                        "--pendulum", "/dev/null"), "--push")):  # fmt: skip
        p = run_lbr("control", "upright", *args, timeout=60)
        assert p.returncode == 2 and text in p.stderr and "Traceback" not in p.stderr, (args, p.stderr)


@pytest.mark.slow  # ≈ 1 min, not a CI gate: run to run the rod fell and was re-caught 0–3 times under these faults (the
# fit's result was taken when the worker finished, in wall-clock time; now at FIT_WAIT_S of simulated time, as the CLI
# does in lock-step); since the safety core rebases after every bridged reply, the session ends by its 0.05 rad
# rejoin limit (28 Nov: 2 of 2 runs) — the upright client's own gap offset and the core's are not yet reconciled
def test_upright_rides_through_lost_and_malformed_messages(robot):
    """2 % of the controller's messages lost, 1 % malformed: the controller extrapolates the commands along the
    rail's tangent; the cart coasts as the joints did, the commands fade back onto the rail, a cart past the end
    brakes on the rail's run-on — swing-up and balance complete, every command passed the guard."""
    from lbrcli.console import Reporter
    from lbrcli.control import UprightClient
    from lbrcli.control.upright import LOG_COLUMNS
    from lbrcli.fri_runner import run_client
    from lbrcli.lab.attach import LabOptions
    from lbrcli.session_settings import LogColumns, SessionSettings, SimulatorSettings
    from planners.rail import build_rail
    from trajectories.limits import default_limits

    lim = default_limits()
    model = RigidPendulum(rod_length=0.5)
    rail = build_rail(robot, Q_START, lim, 0.3)
    from planners.feedback.session import SessionOptions

    from lbrcli.commands.control import FIT_WAIT_S
    from lbrcli.control.fitter import ProcessFitter

    fitter = ProcessFitter(0)  # the fit outside the cycle, as the CLI does in lock-step
    opts = SessionOptions(hold_s=3.0, fit_wait_s=FIT_WAIT_S)
    client = UprightClient(rail, model.equivalent_length, lim, session=opts, fitter=fitter)
    sim = SimulatorSettings(
        start=tuple(Q_START.tolist()),
        plants=(RigidModuleSpec(model),),
        max_runtime_s=90,
        lockstep=True,
        loss=0.02,
        malformed=0.01,
        seed=3,
    )  # fmt: skip (the same loop on a busy machine)
    result, _, lab = run_client(Reporter(True), client, SessionSettings(port=0, limits=lim), sim, lab=LabOptions("sim"),
                                extra=LogColumns(LOG_COLUMNS, client.log_values))  # fmt: skip
    fitter.close()
    assert result.outcome.value == "completed", result.detail
    assert result.missed > 50  # the faults happened
    f = client.figures()
    assert f["succeeded"] and f["swing_up_s"] is not None and f["falls"] == 0 and f["longest_balance_s"] >= 3.0, f
