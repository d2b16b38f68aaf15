"""The FRI session's settings objects (lbrcli.session_settings, LabOptions, BallSpec's string rule) and the option
groups that build them at the CLI edge (lbrcli.option_groups): validation on construction with the field named,
frozen, the defaults applied once, the one-line error naming the option."""

from __future__ import annotations

import dataclasses
import math
from typing import Annotated, Optional

import pytest
import typer
from typer.testing import CliRunner

from tests.helpers.cli import Q_START, run_in_process
from lbrcli.fri import LBRClient
from lbrcli.lab.attach import LabOptions
from lbrcli.option_groups import OptionGroup, with_options
from lbrcli.options import number
from lbrcli.plants import BallSpec, PendulumModuleSpec
from lbrcli.plants.ball import STRING_LENGTH_M
from lbrcli.session_settings import (LENIENT_REPLY_GAP_S, LOCKSTEP_WAIT_S, LogColumns, SessionSettings,
                                     SimulatorSettings)  # fmt: skip
from trajectories.errors import OptionError, SettingError


@pytest.mark.parametrize(
    "make, setting",
    [
        (lambda: SessionSettings(port=70000), "SessionSettings.port"),
        (lambda: SessionSettings(port=-1), "SessionSettings.port"),
        (lambda: SessionSettings(version="3.0"), "SessionSettings.version"),
        (lambda: SessionSettings(wait_s=0.0), "SessionSettings.wait_s"),
        (lambda: SessionSettings(duration_s=math.nan), "SessionSettings.duration_s"),
        (lambda: SessionSettings(max_tracking_error=-0.1), "SessionSettings.max_tracking_error"),
        (lambda: SessionSettings(busy_wait_s=-1e-3), "SessionSettings.busy_wait_s"),
        (lambda: SimulatorSettings(plants=(PendulumModuleSpec(),)), "SimulatorSettings.ball"),
        (lambda: BallSpec(STRING_LENGTH_M[0] / 2), "BallSpec.length"),
        (lambda: BallSpec(STRING_LENGTH_M[1] * 1.01), "BallSpec.length"),
        (lambda: BallSpec(math.inf), "BallSpec.length"),
        (lambda: BallSpec(0.3, damping=-1.0), "BallSpec.damping"),
        (lambda: LabOptions(baud=0), "LabOptions.baud"),
        (lambda: LabOptions(pendulum_zero=4096), "LabOptions.pendulum_zero"),
        (lambda: LabOptions(mqtt_rate_hz=0.0), "LabOptions.mqtt_rate_hz"),
        (lambda: LabOptions(mqtt="http://host/x"), "LabOptions.mqtt"),
        (lambda: LogColumns(("a",)), "LogColumns.values"),
    ],
)
def test_a_bad_field_is_refused_when_the_settings_are_made_naming_the_field_never_a_flag(make, setting):
    with pytest.raises(SettingError) as err:
        make()
    assert err.value.setting == setting and err.value.exit_code == 2
    text = str(err.value)
    assert text.startswith(f"{setting}: ") and "\n" not in text and "--" not in text, text


def test_the_simulators_values_are_judged_by_the_simulators_own_rule():
    for bad in (dict(period_ms=0), dict(period_ms=101), dict(receive_multiplier=0), dict(start=(0.0,) * 6),
                dict(loss=1.5), dict(max_runtime_s=-1.0)):  # fmt: skip
        with pytest.raises(OptionError):
            SimulatorSettings(**bad)


def test_the_ball_string_rule_is_one_range_with_its_ends_inside():
    low, high = STRING_LENGTH_M
    assert BallSpec(low).length == low and BallSpec(high).length == high


def test_settings_are_frozen_and_picklable():
    import pickle

    sim = SimulatorSettings(ball=BallSpec(0.3), start=Q_START)
    for obj, field in (
        (SessionSettings(), "port"),
        (sim, "period_ms"),
        (LabOptions(), "baud"),
        (BallSpec(0.3), "length"),
    ):
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(obj, field, 1)
    assert pickle.loads(pickle.dumps(sim)) == sim and isinstance(sim.start, tuple)


def test_the_session_defaults_follow_the_target():
    sim_app = SessionSettings(port=0).application(LBRClient(), lenient=True)
    assert (sim_app.robot, sim_app.bind_host, str(sim_app.version.value)) == ("127.0.0.1", "127.0.0.1", "1.15")
    assert sim_app.first_message_timeout_s == 20.0 and sim_app.commanding_timeout_s == 20.0
    assert sim_app.reply_gap_s == LENIENT_REPLY_GAP_S and not sim_app.catch_up  # (it uses late replies)
    robot_app = SessionSettings(robot="192.0.2.1", port=0, wait_s=5.0).application(LBRClient(), lenient=True)
    assert (robot_app.robot, robot_app.bind_host, robot_app.version) == ("192.0.2.1", "", None)
    assert robot_app.first_message_timeout_s == 5.0 and robot_app.commanding_timeout_s is None
    assert robot_app.reply_gap_s is None and robot_app.catch_up  # leniency is the simulator's, never a robot's
    assert SessionSettings(port=0).application(LBRClient(), lenient=False).catch_up  # as strict as a robot


def test_the_simulator_config_carries_the_settings():
    ball = BallSpec(0.4, 0.1)
    plain = SimulatorSettings(
        period_ms=2, receive_multiplier=2, ball=ball, plants=(PendulumModuleSpec(),), lenient=False
    )
    cfg = plain.config(client_port=40000, version="2.7", realtime=True)
    assert (cfg.client_port, cfg.version, cfg.period_ms, cfg.receive_multiplier, cfg.realtime) == (
        40000,
        "2.7",
        2,
        2,
        True,
    )
    assert cfg.plants == (ball, PendulumModuleSpec()) and cfg.quality_window == 50 and cfg.lockstep_timeout_s is None
    lenient = dataclasses.replace(plain, lenient=True, fast=True).config(client_port=40000)
    assert lenient.quality_good == 0.5 and lenient.quality_window == 250  # a 1 s window at 4 ms
    assert lenient.lockstep_timeout_s == LOCKSTEP_WAIT_S and lenient.lockstep_free and lenient.version == "1.15"


def test_log_columns_add_in_order():
    a = LogColumns(("x",), lambda s: (s,))
    b = LogColumns(("y", "z"), lambda s: (2 * s, 3 * s))
    both = a + LogColumns() + b
    assert both.names == ("x", "y", "z") and tuple(both.values(1.0)) == (1.0, 2.0, 3.0)
    assert (LogColumns() + a) is a


def test_lab_options_must_suit_the_session():
    LabOptions("sim").validate(embedded=True)
    with pytest.raises(SettingError, match="LabOptions.pendulum"):
        LabOptions("sim").validate(embedded=False)


# ---------------------------------------------------------------- the option groups at the CLI edge


def _toy_app():
    def build(speed: Annotated[float, number("--speed", low=0, high=10, help="Speed.")] = 1.0,
              name: Annotated[Optional[str], typer.Option("--name", help="A name.")] = None) -> dict:  # fmt: skip
        if name == "bad":
            raise SettingError("Toy", "name", "not a good name")
        return {"speed": speed, "name": name}

    group = OptionGroup(build, flags={"Toy.name": "--name"})
    app = typer.Typer()
    got = []

    @app.command("full")
    @with_options(toy=group)
    def full(toy: dict, count: Annotated[int, number("--count", low=0, high=5, integer=True, help="N.")] = 0) -> None:
        got.append((toy, count))

    @app.command("part")
    @with_options(toy=group.without("speed"))
    def part(toy: dict) -> None:
        got.append((toy, None))

    return app, got


def test_a_group_puts_its_options_into_each_command_and_hands_it_one_value():
    app, got = _toy_app()
    runner = CliRunner()
    assert runner.invoke(app, ["full", "--speed", "2.5", "--count", "3", "--name", "a"]).exit_code == 0
    assert runner.invoke(app, ["part", "--name", "b"]).exit_code == 0
    assert got == [({"speed": 2.5, "name": "a"}, 3), ({"speed": 1.0, "name": "b"}, None)]  # left out: the default
    assert "--speed" in runner.invoke(app, ["full", "--help"]).output
    refused = runner.invoke(app, ["part", "--speed", "2"])
    assert refused.exit_code == 2  # not an option of that command
    bad = runner.invoke(app, ["full", "--speed", "11"])
    assert bad.exit_code == 2 and "--speed" in bad.output  # the group's options are validated at parse time


def test_a_setting_refused_by_a_library_is_reported_with_its_option():
    app, _ = _toy_app()
    res = CliRunner().invoke(app, ["full", "--name", "bad"])
    assert isinstance(res.exception, OptionError) and str(res.exception) == "--name: not a good name"


@pytest.mark.parametrize(
    "argv, words",
    [
        (
            ["monitor", "--duration", "1", "--port", "0", "--length", "0", "--pendulum", "sim"],
            ["lbr: error: --length: the pendulum module emulation needs a simulated ball"],
        ),
        (
            ["monitor", "--duration", "1", "--robot", "192.0.2.1", "--pendulum", "sim"],
            ["lbr: error: --pendulum: 'sim' emulates the module in the built-in simulator; not with a robot"],
        ),
        (
            ["execute", "x.csv", "--robot", "192.0.2.1", "--sim-lockstep", "--damping", "1"],
            ["--sim-lockstep", "--damping", "apply to the simulator only, not with --robot"],
        ),
        (["execute", "x.csv", "--robot", "192.0.2.1", "--length", "0.3"], ["x.csv"]),  # a length shapes the move there
    ],
)
def test_the_cli_names_the_option_in_one_line(argv, words):
    code, out, err = run_in_process(argv)
    assert code == 2 and len(err.strip().splitlines()) == 1 and all(w in err for w in words), err


@pytest.mark.parametrize("command", [["execute", "x.csv"], ["monitor", "--duration", "1"], ["serve"],
                                     ["control", "damp", "x.csv"], ["sim"], ["view", "x.csv"],
                                     ["export", "x.csv", "-o", "x.mcap"]])  # fmt: skip
def test_every_ball_length_option_takes_the_one_rule(command):
    low, high = STRING_LENGTH_M
    flag = "--sim-length" if "damp" in command else "--length"
    for value in (low / 2, high * 1.01):
        code, _, err = run_in_process([*command, flag, f"{value:g}"])
        assert code == 2 and flag in err and f"[{low:g}, {high:g}]" in err, err
