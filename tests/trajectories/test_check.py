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
    t = np.arange(0, 2.0 + 0.0025, 0.005)
    q = 0.05 * (1 - np.cos(np.pi * t))[:, None] * np.ones(7)  # one period: starts and ends at rest
    rep = check_trajectory(JointTrajectory(t=t, q=q), limits)
    assert rep.ok and not rep.violations
    # velocity peak ≈ A·ω
    assert rep.peaks["velocity"][0] == pytest.approx(0.05 * np.pi, rel=1e-3)


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
    with pytest.raises(InputError, match="list of 7 numbers"):
        load_limits(p)
    p.write_text("speed = [1, 1, 1, 1, 1, 1, 1]\n")
    with pytest.raises(InputError, match="unknown limit table"):
        load_limits(p)
    p.write_bytes(b"\xef\xbb\xbfvelocity_rad_s = [1, 1, 1, 1, 1, 1, 2]\n")  # a byte-order mark is read
    assert load_limits(p).velocity[6] == 2.0


@pytest.mark.parametrize(
    "content, words",
    [
        (bytes(range(256)) * 4, "NUL byte"),
        (b"\xff\xfe velocity", "not UTF-8"),
        (b"a = " + b"[" * 5000 + b"]" * 5000, "nested deeper"),
        (b"velocity_deg_s = [" + b",".join([b"9" * 400] * 7) + b"]", "list of 7 numbers"),
        (b"velocity_deg_s = [1e-300, 98, 100, 130, 140, 180, 180]", "'velocity_deg_s' (A1) = 1e-300 is outside"),
        (b"velocity_deg_s = [98, 98, 100, 130, 140, 180, inf]", "(A7) = inf is outside"),
        (b"velocity_deg_s = [98, 98, 100, 130, 140, 180, nan]", "(A7) = nan is outside"),
        (b"position_rad = [1, 1, 1, 1, 1, 1, 1e9]", "(A7) = 1e+09 is outside"),
        (b"velocity_deg_s = [true, 98, 100, 130, 140, 180, 180]", "list of 7 numbers"),
        (b"t1_cartesian_speed_m_s = 1e300", "outside the plausible range"),
        (b"t1_cartesian_speed_m_s = 'fast'", "must be a number"),
        (b"velocity_deg_s = ", "not a valid TOML"),
    ],
)
def test_hostile_limits_files_are_refused_naming_the_file(tmp_path, content, words):
    p = tmp_path / "lim.toml"
    p.write_bytes(content)
    with pytest.raises(InputError, match=words.replace("(", r"\(").replace(")", r"\)").replace("+", r"\+")) as exc:
        load_limits(p)
    assert exc.value.file == str(p)


def test_limits_file_size_is_bounded(tmp_path):
    p = tmp_path / "lim.toml"
    p.write_bytes(b"# " + b"x" * (5 << 20) + b"\n")
    with pytest.raises(InputError, match="more than lbr reads"):
        load_limits(p)
    with pytest.raises(InputError, match="NUL byte"):
        load_limits("/dev/zero")


def _rest_to_rest(q_peak, n=400, h=0.005):
    """Rows moving all joints by ``q_peak`` [rad] on a 1 − cos velocity profile: at rest at both ends."""
    t = np.arange(n) * h
    s = (t / t[-1]) - np.sin(2 * np.pi * t / t[-1]) / (2 * np.pi)
    return JointTrajectory(t=t, q=np.outer(s, q_peak))


def test_cycle_to_cycle_oscillation_fails_by_step_acceleration(limits):
    """±0.95 of the velocity step every cycle: central differences cancel it, the controller would not."""
    h = 0.005
    traj = _rest_to_rest(np.full(7, 0.2))
    q = traj.q.copy()
    q[100:300:2, 3] += 0.95 * limits.velocity[3] * h
    rep = check_trajectory(JointTrajectory(t=traj.t, q=q), limits)
    step = [v for v in rep.failing if v.quantity == "step acceleration" and v.joint == 4]
    assert step and step[0].peak > 50 * limits.acceleration[3]
    assert rep.ratios()["step velocity"][3] > 0.9


def test_exactly_at_the_limit_passes_a_hair_above_fails(limits):
    """A step of exactly the velocity limit passes (relative tolerance, not rounding); 1 % more fails."""
    h = 0.005
    n_ramp = 400
    # accelerate at 0.5 of the limit, cruise at the velocity limit, brake: steps built exactly
    v_max, a = limits.velocity[0], 0.5 * limits.acceleration[0]
    v = np.concatenate([np.arange(1, n_ramp) * a * h, np.full(50, v_max), np.arange(n_ramp - 1, 0, -1) * a * h])
    v = np.minimum(v, v_max)
    for factor, ok in ((1.0, True), (1.01, False)):
        steps = np.where(v == v_max, v_max * factor, v)
        q = np.zeros((len(steps) + 1, 7))
        q[1:, 0] = np.cumsum(steps) * h
        rep = check_trajectory(JointTrajectory(t=np.arange(len(q)) * h, q=q), limits)
        assert rep.ratios()["step velocity"][0] == pytest.approx(factor, rel=1e-9)
        over = [v for v in rep.failing if v.quantity in ("velocity", "step velocity")]
        assert (len(over) == 0) is ok


def test_a_file_that_ends_moving_fails_saying_it_is_not_at_rest(limits):
    traj = _rest_to_rest(np.full(7, 0.2))
    cut = JointTrajectory(t=traj.t[:250], q=traj.q[:250])  # stops mid-motion
    rep = check_trajectory(cut, limits)
    rest = [v for v in rep.failing if v.quantity == "rest"]
    assert {v.note for v in rest} == {"end"} and {v.joint for v in rest} == set(range(1, 8))
    assert "not at rest at the end" in rest[0].describe() and "lbr retime" in rest[0].describe()
    assert check_trajectory(traj, limits).ok
    late = JointTrajectory(t=traj.t[150:] - traj.t[150], q=traj.q[150:])  # starts mid-motion
    assert {v.note for v in check_trajectory(late, limits).failing if v.quantity == "rest"} == {"start"}
