"""The pieces between the camera and the damper, without processes: the time-stamped rings (the robot's poses, the
simulated ball), the camera sensor's readings with their ages, and the tilt from a tracker result with the robot's
pivot at the frame's moment."""

from __future__ import annotations

import math
import threading
import time
from types import SimpleNamespace

import numpy as np
import pytest

from lbrcli.control.camera import CameraTilt, TiltReading
from lbrcli.control.sensors import CameraSensor
from lbrcli.lab.timed_ring import TimedRing
from lbrcli.plants.camera import SceneRing
from tracking.camera_geometry import CameraGeometry, string_direction


def test_a_timed_ring_interpolates_and_keeps_the_newest_rows():
    ring = TimedRing(16, 2)
    assert ring.at(0.0) is None
    for k in range(40):  # wraps around twice
        ring.push(0.1 * k, (k, -2.0 * k))
    np.testing.assert_allclose(ring.at(3.25), [32.5, -65.0])
    np.testing.assert_allclose(ring.at(99.0), [39.0, -78.0])  # after the newest: the newest
    np.testing.assert_allclose(ring.at(0.0), [25.0, -50.0])  # before the oldest kept: the oldest kept
    assert len(ring) == 40 and ring.newest_t == pytest.approx(3.9)


def test_the_scene_waits_for_the_simulator_to_reach_a_frames_moment():
    scene = SceneRing.create(64)
    try:
        now = time.monotonic()
        scene.push(now, (0.0, 0.0, 0.0), (0.0, 0.0, 1.0))
        assert scene.live_since is None

        def later() -> None:
            time.sleep(0.01)
            scene.push(now + 0.02, (0.2, 0.0, 0.0), (0.0, 0.0, 1.0))

        th = threading.Thread(target=later)
        th.start()
        ball, pivot = scene.at(now + 0.01)  # not reached yet: waits for the next sample, then interpolates
        th.join()
        np.testing.assert_allclose(ball, [0.1, 0.0, 0.0], atol=1e-12)
        assert scene.live_since == pytest.approx(now + 0.02)
        # a scene nobody writes any more is shown as it was (no wait)
        ball, _ = scene.at(now + 5.0)
        np.testing.assert_allclose(ball, [0.2, 0.0, 0.0])
    finally:
        scene.remove()


class _Tracker:
    def __init__(self) -> None:
        self.result = None
        self.frozen = 0
        self.poses = []

    def latest(self):
        return self.result

    def freeze(self) -> None:
        self.frozen += 1

    def observe(self, t, q) -> None:
        self.poses.append((t, q))


def test_the_camera_sensor_hands_on_each_reading_once_with_its_age():
    tr = _Tracker()
    sensor = CameraSensor(tr, (0, 1), 120.0, max_age_s=0.2)
    state = SimpleNamespace(measured_joint_position=(0.0,) * 7)
    sensor.observe(state)
    assert len(tr.poses) == 1
    assert list(sensor.poll(state)) == [] and tr.frozen == 1
    tr.result = TiltReading(1, time.monotonic() - 0.03, time.monotonic(), 0.01, math.nan)
    out = list(sensor.poll(state))
    assert len(out) == 1 and out[0][:2] == (0, 0.01) and 0.03 <= out[0][2] < 0.2  # y: not seen from here
    assert list(sensor.poll(state)) == []  # the same result is not read twice
    tr.result = TiltReading(2, time.monotonic() - 0.5, time.monotonic(), 0.02, 0.03)  # too old to be of use
    assert list(sensor.poll(state)) == [] and sensor.late == 1 and tr.frozen == 1


def test_a_tracker_result_becomes_the_tilt_about_the_pivot_where_the_robot_was():
    """The pivot moves along y at 0.5 m/s; a frame's tilt is judged with the pivot at the frame's moment (its
    capture less the camera's delay), the string measured from the hanging ball before the move."""
    from lbrcli.options import make_robot

    robot = make_robot("touch-electric", None)
    q0 = np.array([0.0, 0.6, 0.0, -1.4, 0.0, 1.14, 0.0])
    g = CameraGeometry.from_pose((1.3, 0.8, 0.9), robot.fk(q0).translation - [0, 0, 0.3], 50.0, (640, 480))
    tilt = CameraTilt("none", g, robot, None, string_m=0.25, camera_delay_s=0.02, q_rest=q0)
    t0 = 1000.0
    # hanging still before the first row: 10 frames, the robot standing at q0
    for k in range(10):
        tilt.observe(t0 + 0.01 * k, q0)
    pivot0 = robot.fk(q0).translation
    uv = g.project(pivot0 + 0.3 * string_direction(0, 0))[0]
    for k in range(10):
        tilt._take({"seq": k, "t_capture": t0 + 0.2 + 0.01 * k, "latency_s": 0.001, "found": True,
                    "u": uv[0], "v": uv[1], "t_source": math.nan})  # fmt: skip
    assert tilt.freeze() == pytest.approx(0.3, abs=1e-6) and tilt.string_source == "camera"
    # now the robot turns A1 (the TCP sweeps sideways) and the ball hangs tilted by (0.1, −0.05) rad
    for k in range(100):
        tilt.observe(t0 + 0.3 + 0.005 * k, q0 + [0.004 * k, 0, 0, 0, 0, 0, 0])
    moment = t0 + 0.3 + 0.005 * 60
    pivot = robot.fk(q0 + [0.24, 0, 0, 0, 0, 0, 0]).translation
    uv = g.project(pivot + 0.3 * string_direction(0.1, -0.05))[0]
    tilt._take({"seq": 99, "t_capture": moment + 0.02, "latency_s": 0.002, "found": True, "u": uv[0], "v": uv[1],
                "t_source": math.nan})  # fmt: skip
    r = tilt.latest()
    assert r.moment == pytest.approx(moment) and r.theta_x == pytest.approx(0.1, abs=1e-4)
    assert r.theta_y == pytest.approx(-0.05, abs=1e-4)
    # a frame judged 10 ms off (a wrong --camera-delay) is off by the pivot's 5 mm: about 1°
    tilt._take({"seq": 100, "t_capture": moment + 0.03, "latency_s": 0.002, "found": True, "u": uv[0], "v": uv[1],
                "t_source": math.nan})  # fmt: skip
    off = tilt.latest()
    assert math.degrees(math.hypot(off.theta_x - 0.1, off.theta_y + 0.05)) > 0.5


def test_the_camera_s_bias_seen_on_the_hanging_ball_is_taken_off_every_tilt():
    """A detector (or a calibration) that places the ball 0.4 px off to one side: the hanging ball shows it before
    the first row (the camera's zero) and the tilts read afterwards do not carry it (without the zero, 0.4 px at
    this view is a tilt of about 0.15°)."""
    from lbrcli.options import make_robot

    robot = make_robot("touch-electric", None)
    q0 = np.array([0.0, 0.6, 0.0, -1.4, 0.0, 1.14, 0.0])
    pivot = robot.fk(q0).translation
    g = CameraGeometry.from_pose((1.3, 0.8, 0.9), pivot - [0, 0, 0.3], 50.0, (640, 480))
    bias = np.array([0.4, 0.0])  # [px]
    tilt = CameraTilt("none", g, robot, None, string_m=0.25, camera_delay_s=0.02, q_rest=q0)
    t0 = 1000.0
    for k in range(10):
        tilt.observe(t0 + 0.01 * k, q0)

    def take(seq: int, t: float, theta: tuple[float, float]) -> None:
        u, v = g.project(pivot + 0.3 * string_direction(*theta))[0] + bias
        tilt._take({"seq": seq, "t_capture": t, "latency_s": 0.001, "found": True, "u": u, "v": v,
                    "t_source": math.nan})  # fmt: skip

    for k in range(10):
        take(k, t0 + 0.2 + 0.01 * k, (0.0, 0.0))
    assert tilt.freeze() == pytest.approx(0.3, abs=2e-3)
    assert math.hypot(*tilt.zero_px) > 0.3
    take(20, t0 + 0.4, (0.01, -0.005))
    r = tilt.latest()
    assert math.degrees(abs(r.theta_x - 0.01)) < 0.01 and math.degrees(abs(r.theta_y + 0.005)) < 0.01
    raw = CameraTilt("none", g, robot, None, string_m=0.3, camera_delay_s=0.02, q_rest=q0)
    raw.freeze()  # no hanging view: the assumed length and no zero
    u, v = g.project(pivot + 0.3 * string_direction(0.01, -0.005))[0] + bias
    raw._take(
        {"seq": 1, "t_capture": t0 + 0.4, "latency_s": 0.001, "found": True, "u": u, "v": v, "t_source": math.nan}
    )
    off = raw.latest()
    assert math.degrees(math.hypot(off.theta_x - 0.01, off.theta_y + 0.005)) > 0.05
