"""`lbr plan cup-and-ball` end to end: a catch planned over a narrow band, judged again from the written files alone —
by `lbr check`, by the independent penalty-force judge and by the simulator's ball plant — and the exits."""

import json

import numpy as np
import pytest

from lbrcli.fri.sim import PlantContext
from lbrcli.plants import BallSpec
from planners.string_model import IN_CUP, SLACK, TAUT, StringModel
from planners.string_penalty import judge
from trajectories.csvio import read_joint_csv, read_table

from tests.helpers.cli import Q_START, run_in_process, run_lbr
from tests.helpers.shared import once

LENGTH = 0.2


@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    """The catch planned once per run (tests of this module on both workers share it; tests only read its files)."""

    def make(d):
        out, pred, plot = d / "catch.csv", d / "pred.csv", d / "catch.png"
        res = run_lbr(
            "plan",
            "cup-and-ball",
            "--length",
            LENGTH,
            "--length-tol",
            "0.01",
            "--mass-tol",
            "0",
            "--no-timing",
            "-o",
            out,
            "--prediction",
            pred,
            "--plot",
            plot,
            "--json",
            timeout=600,
        )
        return res, out, pred, plot

    return once(tmp_path_factory, "lbr plan cup-and-ball (test_plan_catch)", make)


@pytest.mark.heavy
def test_the_plan_catches_the_ball_within_the_limits(planned):
    res, out, pred, plot = planned
    assert res.returncode == 0, res.stderr
    f = json.loads(res.stdout)
    assert f["caught"] and f["ok"] and f["limits_ok"] and f["failure"] is None
    assert 0 < f["release_time_s"] < f["catch_time_s"] < f["rest_in_cup_s"] < f["duration_s"]
    assert 0 < f["entry_margin_m"] <= 0.03 - 0.01 and 0 < f["relative_entry_speed_m_s"] < 4
    rob = f["robustness"]
    assert rob["success_fraction"] >= 0.95 and rob["members"] == 9 and rob["length_tolerance"] == 0.01
    assert f["cup_spec"] in f["rehearse"] and plot.stat().st_size > 20_000
    # without --max-time: the cruising release searched as for a 3 s plan, from rest as soon as the band allows
    swing, move = f["swing_up"], f["catch_move"]
    assert swing["release_deadline_s"] == (pytest.approx(2.95) if swing["release"] == "cruising" else None)
    assert 0.0 <= move["coast_s"] <= 0.25 and move["t_catch_s"] < f["duration_s"]
    assert run_lbr("check", out, "--jerk").returncode == 0  # every limit, rest at both ends


@pytest.mark.heavy  # the module's planned catch (`lbr plan catch`): many seconds
def test_the_prediction_file_has_the_phases_and_the_paths(planned):
    _, _, pred, _ = planned
    tab = read_table(pred, ("t", "theta", "phase", "ball_x", "ball_y", "ball_z", "anchor_x", "anchor_y", "anchor_z"))
    phase = tab.column("phase")
    assert phase[0] == TAUT and phase[-1] == IN_CUP and (phase == SLACK).any()
    ball = np.column_stack([tab.column(f"ball_{c}") for c in "xyz"])
    anchor = np.column_stack([tab.column(f"anchor_{c}") for c in "xyz"])
    d = np.linalg.norm(ball - anchor, axis=1)
    assert np.abs(d[phase == TAUT] - LENGTH).max() < 1e-6  # taut: the string's length
    assert d[phase == IN_CUP].max() < 0.06  # in the cup: near the anchor at its bottom


def _fk(out, robot):
    traj = read_joint_csv(out)
    pos, rot = robot.fk_path(traj.q)
    return traj, pos, rot @ np.asarray(StringModel(LENGTH).axis_flange)


@pytest.mark.slow  # ≈ 20–40 s; bench_catch judges every benchmark plan with the penalty judge (its agreement row)
def test_an_independent_penalty_judge_catches_it_too(planned, robot):
    """The written joints → FK → a penalty-force ball with a spline anchor: caught, entering when the plan says."""
    res, out, _, _ = planned
    f = json.loads(res.stdout)
    traj, pos, axes = _fk(out, robot)
    model = StringModel(LENGTH)
    run = judge([model], traj.t, pos, axes, float(traj.t[-1]))
    assert run.caught[0]
    assert run.t_inside[0] == pytest.approx(f["catch_time_s"], abs=0.02)


@pytest.mark.heavy  # the module's planned catch (`lbr plan catch`): many seconds
def test_the_simulator_ball_plant_catches_it_cycle_by_cycle(planned, robot):
    res, out, _, _ = planned
    f = json.loads(res.stdout)
    traj, pos, _ = _fk(out, robot)
    _, rot = robot.fk_path(traj.q)
    plant = BallSpec(LENGTH, model=StringModel(LENGTH)).build(PlantContext(traj.dt, robot, tuple(Q_START.tolist())))
    phases = [plant.step(t, p, r)[7] for t, p, r in zip(traj.t, pos, rot)]
    got = plant.figures()["cup"]
    assert got["caught"] and got["in_cup_at_end"]
    assert got["entered_s"] == pytest.approx(f["catch_time_s"], abs=0.5 * traj.dt)  # on the TCP samples' clock
    k = int(np.argmax(np.array(phases) == IN_CUP))  # the message of cycle k shows the ball at cycle k − 1
    assert traj.t[k] == pytest.approx(f["catch_time_s"] + traj.dt, abs=1.5 * traj.dt)


@pytest.mark.parametrize(
    "args,fragment",
    [
        (("--cup-radius", "0.008"), "inner radius"),
        (("--length", "0.05"), "exceed the cup's extent"),
        (("--cup-axis", "0,0,1"), "--cup-axis"),
        (("--restitution", "1.5"), "--restitution"),
        (("--max-time", "0"), "--max-time"),
        (("--length-tol", "nan"), "--length-tol"),
    ],
)
def test_bad_options_exit_2_in_one_line(tmp_path, args, fragment):
    opts = dict(zip(args[::2], args[1::2]))
    length = opts.pop("--length", str(LENGTH))
    rest = [x for kv in opts.items() for x in kv]
    code, _, err = run_in_process(["plan", "cup-and-ball", "--length", length, *rest, "-o", tmp_path / "c.csv"])
    lines = [l for l in err.strip().splitlines() if l]
    assert code == 2 and len(lines) == 1 and "Traceback" not in err, err
    assert fragment in lines[0] and not (tmp_path / "c.csv").exists()


@pytest.mark.heavy
def test_the_rehearsal_on_the_simulator_catches_it_and_the_log_says_when(planned, tmp_path):
    res, out, _, _ = planned
    f = json.loads(res.stdout)
    log = tmp_path / "log.csv"
    ex = run_lbr(
        "execute",
        out,
        "--port",
        "0",
        "--sim-fast",  # the catch as planned, however loaded this machine is (the timing rules have their own tests)
        "--length",
        LENGTH,
        "--cup",
        f["cup_spec"],
        "--settle",
        "0.5",
        "--log",
        log,
        "--json",
        timeout=300,
    )
    assert ex.returncode == 0, ex.stderr
    g = json.loads(ex.stdout)
    cup = g["cup"]
    assert cup["stayed"] and "entered the cup" in ex.stderr and "stayed" in ex.stderr
    # the same moment as the plan's, counted from the first trajectory row (the log's clock)
    assert cup["entered_after_start_s"] == pytest.approx(f["catch_time_s"], abs=0.02)
    assert g["simulator"]["plants"]["ball"]["cup"]["caught"]
    tab = read_table(log, ("t", "state"), time="increasing")
    assert set(np.unique(tab.column("ball_phase"))) == {float(TAUT), float(SLACK), float(IN_CUP)}


def test_cup_spec_round_trips_and_bad_specs_are_named():
    from lbrcli.cup_options import cup_spec, parse_cup_spec
    from trajectories.errors import OptionError

    model = parse_cup_spec("radius=0.04,depth=0.05,rim=0.06,wall=0.004,axis=0:0:1,ball=0.012,mass=0.02,e=0.4", 0.3)
    assert model.cup.inner_radius == 0.04 and model.cup.axis == (0.0, 0.0, 1.0) and model.ball.radius == 0.012
    assert parse_cup_spec(cup_spec(model), 0.3) == model
    assert parse_cup_spec("default", 0.3) == StringModel(0.3)
    for spec, fragment in (
        ("radius=x", "radius must be a number"),
        ("size=3", "keys"),
        ("radius=0.005", "inner radius"),
    ):
        with pytest.raises(OptionError, match=fragment):
            parse_cup_spec(spec, 0.3)


def test_the_planners_messages_name_the_options_at_the_cli_edge():
    """The planner names its settings (no flag in library code); the command shows the flags users typed."""
    import inspect

    import planners.catch_plan as catch_plan
    from lbrcli.commands.plan_catch import CATCH_FLAGS
    from lbrcli.option_groups import name_text

    source = inspect.getsource(catch_plan)
    assert "--max-time" not in source and "--cup-axis" not in source and "--q-start" not in source
    for setting, flag in (("CatchRequest.max_time", "--max-time"), ("Cup.axis", "--cup-axis")):
        assert setting in source
        text = name_text(f"enters at 3.2 s, after {setting} 3 s", CATCH_FLAGS)
        assert text == f"enters at 3.2 s, after {flag} 3 s"
