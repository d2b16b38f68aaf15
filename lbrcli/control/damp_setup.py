"""`lbr control damp` set up for one joint file: the correction plan, the damping client, the sensor and what the
simulator must simulate for it (the ball and the plant that measures it). Built by the command from its settings;
no option names here."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any, NamedTuple

import numpy as np

SENSORS = ("io", "module", "camera")  # where the sway comes from: the controller's analog inputs, the module, a camera


class CameraSetup(NamedTuple):
    """The camera the damper reads (started), the simulator's camera plant spec (None for a real camera) and the
    sensor delay [ms] the observer assumes for it."""

    sensor: Any
    sim_camera: Any
    assumed_ms: float


@dataclass(frozen=True)
class DampSetup:
    """The damper for the joint path ``traj`` on ``robot`` (trajectories.robot.Robot: its TCP is the pivot)."""

    robot: Any
    traj: Any  # trajectories.trajectory.JointTrajectory: the rows [rad] at the command period
    limits: Any  # trajectories.limits.JointLimits
    period_s: float  # [s] the command period (the file's step)
    model_length: float  # [m] the string length the damper assumes
    true_length: float  # [m] the simulated ball's string
    damp_s: float | None  # [s] damping after the last row (None: 3 swing periods)
    sensor: str  # one of SENSORS
    io_names: tuple[str, str] = ("ball_theta_x", "ball_theta_y")  # analog inputs with θx, θy [rad] (sensor io)
    module_axis: str = "y"  # the base axis the module swings along (sensor module)
    sensor_rate_hz: float = 200.0  # [Hz] the module's readings (sensor module)
    target_rad: float = math.radians(0.3)  # [rad] the residual sway to reach
    open_loop: bool = False  # estimate and log, do not correct

    def __post_init__(self) -> None:
        if self.damp_s is None:
            object.__setattr__(self, "damp_s", 3.0 * self.swing_period_s)

    @cached_property
    def plan(self):
        """The correction's tables along the file (planners.feedback.correction.CorrectionPlan)."""
        from planners.feedback.correction import correction_plan

        return correction_plan(self.robot, self.traj.q, self.limits, self.period_s)

    @property
    def swing_period_s(self) -> float:
        """[s] of the string the damper assumes."""
        from planners.pendulum import natural_period

        return natural_period(self.model_length)

    def module_axis_error(self) -> tuple[int, float]:
        """(row, angle [rad]) where the module's bearing is farthest from the base axis across its sway: its rod can
        swing with the ball's sway only where the bearing lies along that axis."""
        from planners.feedback.geometry import module_axis_error

        return module_axis_error(self.robot, self.traj.q, 1 - "xy".index(self.module_axis))

    def client(self, camera: CameraSetup | None, assumed_ms: float, *, start_tolerance: float, move_to_start: bool,
               start_sway_rad: float, sway_wait_s: float):  # fmt: skip
        """The DampingClient: the sensor delay ``assumed_ms`` [ms] (the camera's own where there is one); with the io
        sensor the first row waits until the sway stayed below ``start_sway_rad`` (at most ``sway_wait_s``)."""
        from lbrcli.control.camera_setup import observer_bandwidth
        from lbrcli.control.damping import DampingClient
        from lbrcli.fri.sway import IoSway, SwayWatch, window_for_length
        from planners.feedback.damping import DampingOptions
        from planners.shapers import make_shaper

        options = (
            DampingOptions()
            if camera is None
            else DampingOptions(bandwidth=observer_bandwidth(1.0 / camera.sensor.interval_s))
        )
        sway = (SwayWatch(IoSway("ball_theta"), start_sway_rad, window_for_length(self.model_length), sway_wait_s)
                if self.sensor == "io" else None)  # fmt: skip
        return DampingClient(
            self.traj.q, self.limits, self.period_s, self.model_length, self.plan, damp_s=self.damp_s,
            sensor_delay_s=(camera.assumed_ms if camera is not None else assumed_ms) * 1e-3,
            io_names=self.io_names if self.sensor == "io" else None, module_axis="xy".index(self.module_axis),
            sensor_rate_hz=self.sensor_rate_hz, active=not self.open_loop, target=self.target_rad,
            sensor=camera.sensor if camera is not None else None, options=options, start_tolerance=start_tolerance,
            move_to_start=move_to_start, move_shaper=make_shaper("zvd", self.swing_period_s), move_robot=self.robot, sway=sway,
        )  # fmt: skip

    def ball(self, delay_ms: float):
        """The simulated ball (BallSpec); with the io sensor its inputs show it ``delay_ms`` [ms] late."""
        from lbrcli.plants import BallSpec

        return BallSpec(self.true_length, io_delay_ms=delay_ms if self.sensor == "io" else 0.0)

    def plants(self, camera: CameraSetup | None, delay_ms: float) -> tuple:
        """What measures the simulated ball besides its inputs: the simulator's camera (unless another source is
        filmed), or the module reading its θy over the emulated serial link ``delay_ms`` [ms] late."""
        from lbrcli.plants import PendulumModuleSpec

        if self.sensor == "camera":
            return (camera.sim_camera,) if camera is not None and camera.sim_camera is not None else ()
        if self.sensor == "module":
            return (PendulumModuleSpec(self.sensor_rate_hz, delay_ms=delay_ms),)
        return ()

    def offset_room(self) -> tuple[float, float, float]:
        """The correction's room along the file: (largest offset [m], least and largest acceleration [m/s²])."""
        bounds = np.asarray(self.plan.bounds)
        return float(self.plan.travel), float(bounds[:, 2].min()), float(bounds[:, 2].max())
