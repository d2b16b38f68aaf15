import numpy as np
import pytest

from trajectories.check import check_trajectory
from trajectories.limits import load_limits
from trajectories.errors import InputError
from trajectories.trajectory import JointTrajectory


def sine_traj(amplitude, freq, h=0.005, duration=2.0, q0=None):
    t = np.arange(0, duration + h / 2, h)
    q = np.zeros((len(t), 7)) if q0 is None else np.tile(q0, (len(t), 1))
    q = q + amplitude * np.sin(2 * np.pi * freq * t)[:, None] * np.ones(7)
    return JointTrajectory(t=t, q=q)


def test_slow_motion_passes(limits):
    rep = check_trajectory(sine_traj(0.1, 0.5), limits)
    assert rep.ok and not rep.violations
    # velocity peak ≈ A·ω
    assert rep.peaks["velocity"][0] == pytest.approx(0.1 * 2 * np.pi * 0.5, rel=1e-3)


def test_velocity_violation_names_joint_time_value_limit(limits):
    # A·ω = 0.5·2π·0.6 = 1.88 rad/s > A1's 1.71 rad/s, below A4's 2.27 rad/s
    rep = check_trajectory(sine_traj(0.5, 0.6), limits)
    assert not rep.ok
    vel = [v for v in rep.violations if v.quantity == "velocity"]
    assert {v.joint for v in vel} == {1, 2, 3}
    v1 = next(v for v in vel if v.joint == 1)
    assert v1.limit == pytest.approx(np.radians(98))
    assert abs(v1.value) > v1.limit
    assert v1.t == pytest.approx(0.0, abs=0.1)  # the sine starts at full speed
    text = v1.describe()
    assert "A1 velocity" in text and "rad/s" in text and "t = " in text


def test_margin_scales_limits(limits):
    traj = sine_traj(0.45, 0.6)  # peak 1.70 rad/s, just under A1's 1.71
    assert not any(v.quantity == "velocity" for v in check_trajectory(traj, limits).violations)
    rep = check_trajectory(traj, limits, margin=0.1)
    assert any(v.quantity == "velocity" and v.joint == 1 for v in rep.failing)


def test_jerk_reported_but_fails_only_when_enforced(limits):
    # a step in acceleration: jerk spikes
    h = 0.001
    t = np.arange(0, 1, h)
    acc = np.where(t < 0.5, 1.0, -1.0)
    q = np.cumsum(np.cumsum(acc) * h) * h
    traj = JointTrajectory(t=t, q=np.tile(q[:, None], (1, 7)))
    rep = check_trajectory(traj, limits)
    assert any(v.quantity == "jerk" for v in rep.violations)
    assert rep.ok
    assert not check_trajectory(traj, limits, jerk=True).ok


def test_position_violation(limits):
    traj = sine_traj(0.1, 0.2, q0=np.array([0, 0, 0, 2.1, 0, 0, 0]))  # A4 limit 2.094 rad
    rep = check_trajectory(traj, limits)
    assert [v.joint for v in rep.failing if v.quantity == "position"] == [4]


def test_cartesian_speed(limits):
    traj = sine_traj(0.01, 0.5)
    pos = np.column_stack([0.3 * traj.t, np.zeros(len(traj)), np.zeros(len(traj))])  # 0.3 m/s
    rep = check_trajectory(traj, limits, cartesian_positions=pos)
    assert rep.cartesian_speed_peak == pytest.approx(0.3)
    assert [v.quantity for v in rep.failing] == ["cartesian speed"]


def test_limits_override_file(tmp_path):
    p = tmp_path / "lim.toml"
    p.write_text("velocity_rad_s = [1, 1, 1, 1, 1, 1, 1]\n")
    lim = load_limits(p)
    assert np.all(lim.velocity == 1.0)
    assert lim.position[0] == pytest.approx(np.radians(170))  # the rest stays default
    p.write_text("velocity_rad_s = [1, 1]\n")
    with pytest.raises(InputError, match="7 positive numbers"):
        load_limits(p)
    p.write_text("speed = [1, 1, 1, 1, 1, 1, 1]\n")
    with pytest.raises(InputError, match="unknown limit table"):
        load_limits(p)
