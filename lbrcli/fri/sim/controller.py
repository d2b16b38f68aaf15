"""The simulated KUKA controller: a robot application holding the robot (PositionHold) with an FRI overlay.

Once per cycle ``cycle(t)`` evaluates the client's timing (quality), advances the session state, moves the robot
and returns the monitoring message to send; ``on_datagram`` takes the client's command messages in between.

PositionHold semantics (as the real controller reports them):
- ``ipoData.jointPosition`` is the application's own motion: constant under PositionHold — where the robot stood
  when the overlay started (position mode) or the held set-point (impedance modes); it never follows the client.
- In COMMANDING_ACTIVE the client's ``jointPosition`` is the absolute set-point. It passes through the
  interpolator (velocity/acceleration limits, tracking performance < 1 when clipped; with receiveMultiplier k the
  commands are fine-interpolated, a late or missing one is extrapolated at the commands' velocity). Position mode:
  the measured position is the interpolator's; torque mode: joint impedance around it plus the commanded torque;
  wrench mode: Cartesian impedance around its TCP pose plus the commanded wrench (``arm``).
- A command outside the position limits (or NaN) is a safety stop: the robot brakes within its limits, never past
  a position limit, then the drives switch off; the application ends the overlay.
- A command in COMMANDING_WAIT must mirror the ipo position (and, in torque/wrench mode, carry a torque/wrench:
  KUKA's consistency check); in COMMANDING_ACTIVE a missing torque/wrench counts as zero (``incomplete_commands``).
- In COMMANDING_ACTIVE every reply must carry the 7 joint positions (in every command mode: KUKA's ``LBRClient``
  always sets them): a reply to a COMMANDING_ACTIVE message without them is an error — the overlay ends
  (``end_reason`` "command_missing", ``commands_without_position``) and the robot stops, as after a safety stop
  but with the drives on.
- FRI 2.7 CARTESIAN_POSE (``command_mode`` "cartesian", position control): the client commands the TCP pose (tx, ty,
  tz [mm], quaternion) and E1 (the A3 angle) instead of joints; the controller turns each pose into joints with the
  IK of :mod:`~lbrcli.fri.cartesian` (A3 at E1, warm-started from the last solution, within the position limits) and
  they pass the same interpolator. In COMMANDING_WAIT the pose must mirror the ipo pose (its joints within
  ``mirror_tolerance``); in COMMANDING_ACTIVE a pose the IK cannot reach, or one that jumps (a joint further than
  10 periods at its velocity limit), ends the overlay (``end_reason`` "cartesian_refused") and the robot brakes
  within its limits; a reply without a pose is "command_missing" as above.
- FRI 2.7 transformation requests (``transformations``): every monitoring message names the frames the application
  wants; the client's values arrive in ``commandedTransformations`` and are kept (:mod:`.transforms`).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from trajectories.errors import FriDecodeError, FriForeignMessage, SettingError

from ..cartesian import PoseSolver, wire_to_pose
from ..codec import FriCodec
from ..constants import (
    N_JOINTS,
    ClientCommandMode,
    ConnectionQuality,
    ControlMode,
    DriveState,
    OverlayType,
    SafetyState,
    SessionState,
)
from .arm import Arm
from .config import IoChannel, SimConfig
from .interpolator import Interpolator
from .link import RING
from .monitor import MonitoringWriter
from .plant import PlantContext
from .session import QualityMonitor, QualityThresholds, SessionMachine, SessionTiming
from .transforms import TransformationBank

_U32 = 0xFFFFFFFF
CA, CW = SessionState.COMMANDING_ACTIVE, SessionState.COMMANDING_WAIT
MODES = {  # command mode -> (client command mode, overlay type, control mode)
    "position": (ClientCommandMode.POSITION, OverlayType.JOINT, ControlMode.POSITION_CONTROLMODE),
    "torque": (ClientCommandMode.TORQUE, OverlayType.JOINT, ControlMode.JOINT_IMPEDANCE_CONTROLMODE),
    "wrench": (ClientCommandMode.WRENCH, OverlayType.CARTESIAN, ControlMode.CARTESIAN_IMPEDANCE_CONTROLMODE),
    "cartesian": (ClientCommandMode.CARTESIAN_POSE, OverlayType.CARTESIAN, ControlMode.POSITION_CONTROLMODE),
}


class Controller:
    """Session, overlay, robot and plants of one simulated controller (no sockets: see ``Simulator``)."""

    def __init__(self, cfg: SimConfig, sent_at: Callable[[int], float] = lambda seq: float("nan")) -> None:
        from trajectories.limits import load_limits
        from trajectories.robot import Flange, Robot, RobotConfig

        cfg.validate()
        self.cfg = cfg
        self._sent_at = sent_at
        self.period = cfg.period_ms * 1e-3  # [s]
        self.codec = FriCodec(cfg.version)
        self.limits = load_limits(cfg.limits_path)
        q0 = np.array(cfg.q0, dtype=float)
        if np.any(np.abs(q0) > self.limits.position):
            j = int(np.argmax(np.abs(q0) - self.limits.position))
            raise SettingError("SimConfig", "q0", f"q{j + 1} = {q0[j]:.4f} rad is outside the position limit "
                               f"±{self.limits.position[j]:.4f} rad")  # fmt: skip
        self.robot = Robot(RobotConfig(flange=Flange(cfg.flange), tool=tuple(cfg.tool)))
        self.arm = Arm(
            self.robot, self.limits.position, q0, np.array(cfg.external_torque), np.array(cfg.external_force)
        )
        self.interp = Interpolator(q0, self.limits.velocity, self.limits.acceleration, self.period)
        self.quality_monitor = QualityMonitor(
            QualityThresholds(cfg.quality_window, cfg.quality_fair, cfg.quality_good, cfg.quality_excellent)
        )
        self.machine = SessionMachine(SessionTiming.of(cfg))
        self._mode = cfg.command_mode
        self.writer = MonitoringWriter(self.codec, cfg, *MODES[self._mode])
        self.io = self.writer.io
        self.mon = self.writer.mon
        self._cmd = self.codec.new_command()
        self.transforms = TransformationBank(self.mon, cfg.transformations) if cfg.transformations else None
        self._poses = (PoseSolver(self.robot, self.limits, self.period * cfg.receive_multiplier)
                       if self._mode == "cartesian" else None)  # fmt: skip
        self._init_state(q0)
        self.plants = []
        self._plant_io: list[list] = []
        ctx = PlantContext(self.period, self.robot, tuple(cfg.q0), lockstep=cfg.lockstep_timeout_s is not None)
        for spec in cfg.plants:
            plant = spec.build(ctx)
            ctx.plants.append(plant)
            self.plants.append(plant)
            entries = []
            for name in plant.inputs:
                ch = self.io.channel(name)
                if ch is None:
                    entries.append(self.io.add(IoChannel(name, "analog", "in")))
                elif ch.is_output or not ch.is_analog:
                    raise SettingError(
                        "SimConfig", "io", f"{name}: the plant {plant.name} drives it, it must be an analog input"
                    )
                else:
                    entries.append(self.io.entry(name))
            self._plant_io.append(entries)
        self._plant_rotation = [bool(getattr(p, "uses_rotation", False)) for p in self.plants]  # step(t, tcp, rotation)

    # -- setup -----------------------------------------------------------------------------------------------
    def _init_state(self, q0: np.ndarray) -> None:
        n = N_JOINTS
        self.ipo = q0.copy()  # [rad] the application's own (PositionHold) position
        self._hold = q0.copy()  # [rad] interpolator target outside COMMANDING_ACTIVE
        self._cmd_q = np.zeros(n)  # last received command [rad]
        self._cmd_tau = np.zeros(n)  # last received commanded torque [Nm]
        self._cmd_wrench = np.zeros(6)  # last received commanded wrench [N, Nm]
        self._tau_in_force = np.zeros(n)
        self._wrench_in_force = np.zeros(6)
        self._overlay_fresh = False  # the last command carried the torque/wrench the mode needs
        self._cmd_refl = -1  # the monitoring counter the last received command reflects
        self._last_cmd = q0.copy()  # last command used [rad]
        self._last_refl = -1  # ... and the counter it reflected
        self._vel_est = np.zeros(n)  # commanded velocity [rad/cycle], for late or missing commands
        self._vel_cap = self.limits.velocity * self.period  # [rad/cycle] no faster extrapolation than allowed
        self._cmd_fresh = False  # a command with 7 positions arrived in this interval
        self._header_only = False  # a reply without joint positions arrived in this interval
        self._missing_refl = -1  # the monitoring counter the last reply without joint positions reflects
        self._active_from: int | None = None  # the counter of the first COMMANDING_ACTIVE message
        self._target = q0.copy()  # the set-point handed to the interpolator this cycle [rad]
        self._sub = 0  # fine-interpolation sub-step within a receive-multiplier slot
        self._sub_from = q0.copy()
        self._sub_to = q0.copy()
        self.seq = -1  # last monitoring sequence counter used
        self._reflect = 0  # last client sequence counter received
        self._last_client_seq: int | None = None
        self._timely = False
        self._since_timely = 0
        self._any_reply = False
        self.latency = np.empty(RING)  # [s] send → reply reflecting it
        self.n_latency = 0
        self.safety = False
        self._stiff = self._mode in ("position", "cartesian")  # the arm follows the interpolator (position control)
        self._pose_seed = q0.copy()  # [rad] the joints of the last Cartesian pose solved (its IK's warm start)
        self._pose_problem: str | None = None  # why the last Cartesian pose in COMMANDING_ACTIVE cannot be executed
        self.command_problem = ""  # the first such reason (the stats)
        self.state = SessionState.MONITORING_WAIT
        self.quality = ConnectionQuality.POOR
        self.states_seen: list[int] = []
        self._tracking = 0.0
        self.min_tracking = 1.0
        self.counts = dict.fromkeys(("replies", "late", "missed", "malformed_rx", "foreign_rx", "commanded", "gaps",
                                     "active", "incomplete", "no_position", "untimely_active", "poses"), 0)  # fmt: skip

    # -- receiving -------------------------------------------------------------------------------------------
    def on_datagram(self, data: bytes, arrival: float) -> None:
        """One datagram from the client's host; ``arrival`` its receive time (time.time [s])."""
        c = self.counts
        cmd = self._cmd
        try:
            self.codec.decode_command(data, into=cmd)
        except FriForeignMessage:
            c["foreign_rx"] += 1
            return
        except FriDecodeError:
            c["malformed_rx"] += 1
            return
        c["replies"] += 1
        self._any_reply = True
        h = cmd.header
        seq = h.sequenceCounter
        if self._last_client_seq is not None and seq != ((self._last_client_seq + 1) & _U32):
            c["gaps"] += 1
        self._last_client_seq = seq
        self._reflect = seq
        refl = h.reflectedSequenceCounter
        if refl == (self.seq & _U32):
            self._timely = True
        else:
            c["late"] += 1
        sent = self._sent_at(refl)
        if sent == sent and refl <= self.seq:  # not NaN: the message was actually sent
            self.latency[self.n_latency % RING] = arrival - sent
            self.n_latency += 1
        cd = cmd.commandData
        if cd.writeIORequest:
            self.io.apply(cd.writeIORequest)
        if self.transforms is not None and cd.commandedTransformations:
            self.transforms.apply(cd.commandedTransformations)
        if self._poses is not None:
            self._take_pose(cd, refl)
            return
        jp = cd.jointPosition.value
        if len(jp) == N_JOINTS:
            self._cmd_q[:] = jp
            self._cmd_fresh = True
            self._cmd_refl = refl
            if self._mode == "torque":
                tau = cd.jointTorque.value
                self._overlay_fresh = len(tau) == N_JOINTS
                self._cmd_tau[:] = tau if self._overlay_fresh else 0.0
            elif self._mode == "wrench":
                w = cd.cartesianWrenchFeedForward.element
                self._overlay_fresh = len(w) == 6
                self._cmd_wrench[:] = w if self._overlay_fresh else 0.0
            else:
                self._overlay_fresh = True
        else:
            self._header_only = True
            self._missing_refl = refl

    def _take_pose(self, cd, refl: int) -> None:
        """CARTESIAN_POSE: the joints of the commanded pose (or why there are none) as this interval's command."""
        if len(cd.cartesianPose.element) != 7:
            self._header_only = True
            self._missing_refl = refl
            return
        commanding = self.state is CA
        seed = self._pose_seed if commanding else self.ipo  # COMMANDING_WAIT: the robot stands at the ipo position
        e1 = cd.redundancyInformation.value if cd.HasField("redundancyInformation") else float(self.ipo[2])
        try:
            position, rotation = wire_to_pose(cd.cartesianPose.element)
            sol = self._poses.solve(seed, position, rotation, e1)  # type: ignore[union-attr]
            problem = sol.problem
        except ValueError as exc:
            sol, problem = None, f"malformed Cartesian pose: {exc}"
        self._cmd_fresh = True
        self._cmd_refl = refl
        self._overlay_fresh = True
        if problem is not None:
            self._cmd_q[:] = np.nan  # never mirrors; in COMMANDING_ACTIVE the overlay ends (not a safety stop)
            if commanding:
                self._pose_problem = problem
                self.command_problem = self.command_problem or problem
            return
        self._cmd_q[:] = sol.q  # type: ignore[union-attr]
        if commanding:
            self._pose_seed[:] = sol.q  # type: ignore[union-attr]
        self.counts["poses"] += 1

    def awaits_reply(self) -> bool:
        """Lock-step: the client must answer the message just sent within this interval — it has answered before,
        the session is open, and (receiveMultiplier k) no reply came in the k−1 intervals before."""
        return (self._any_reply and not self._timely and self.state is not SessionState.IDLE
                and self._since_timely + 1 >= self.cfg.receive_multiplier)  # fmt: skip

    def answered(self) -> bool:
        """A reply to the message just sent has arrived."""
        return self._timely

    # -- one cycle -------------------------------------------------------------------------------------------
    def cycle(self, t: float) -> bytes:
        """Run the cycle starting at time t [s] (since the first): state, motion, plants; the message to send."""
        was = self.state
        if self.seq >= 0 and was is not SessionState.IDLE:
            self._evaluate_interval()
        mirror_ok, safety = self._check_command(was)
        missing = (was is CA and self._header_only and self._active_from is not None
                   and self._missing_refl >= self._active_from)  # fmt: skip
        if missing:
            self.counts["no_position"] += 1
        refused = was is CA and self._pose_problem is not None
        self._pose_problem = None
        state = self.machine.advance(t, self.quality, mirror_ok, safety, missing, refused)
        if state is CA and was is not CA:
            self._active_from = (self.seq + 1) & _U32
        self._motion(state, was)
        self._set_robot_info()
        if state is not was or not self.states_seen:
            self.states_seen.append(int(state))
        self.state = state
        pose = self.arm.tcp_pose()
        if self.plants:
            tcp = pose.translation.tolist()
            for plant, entries, rotation in zip(self.plants, self._plant_io, self._plant_rotation):
                values = plant.step(t, tcp, pose.rotation) if rotation else plant.step(t, tcp)
                for io, v in zip(entries, values):
                    io.analogValue = v
        self.seq += 1
        target = self._target if state is CA else self.interp.q
        return self.writer.fill(self.seq, self._reflect, state, self.quality, self.arm, self.ipo, target,
                                self._tracking, pose)  # fmt: skip

    def _evaluate_interval(self) -> None:
        """Timeliness of the interval that just ended → quality."""
        k = self.cfg.receive_multiplier
        if self._timely:
            self._since_timely = 0
        else:
            self._since_timely += 1
            if self.state is CA:
                self.counts["untimely_active"] += 1
            if self._any_reply and self._since_timely % k == 0:
                self.counts["missed"] += 1
        self.quality = self.quality_monitor.push(self._since_timely < k)
        self._timely = False

    def _check_command(self, state: SessionState) -> tuple[bool | None, bool]:
        """(mirror_ok for COMMANDING_WAIT, safety stop) from this interval's command."""
        if state is CW:
            if self._cmd_fresh:
                ok = bool(np.all(np.abs(self._cmd_q - self.ipo) <= self.cfg.mirror_tolerance))
                if not self._overlay_fresh:
                    self.counts["incomplete"] += 1
                    ok = False
                if ok:
                    for a in (self._sub_from, self._sub_to, self._target, self._last_cmd, self._pose_seed):
                        a[:] = self._cmd_q
                    self._last_refl = self._cmd_refl
                return ok, False
            return (False if self._header_only else None), False
        if state is CA and self._cmd_fresh and not self.safety and self._pose_problem is None:
            q = self._cmd_q
            if not (np.all(np.isfinite(q)) and np.all(np.abs(q) <= self.limits.position)):
                self.safety = True
                self._cmd_fresh = False
                return None, True
            if not self._overlay_fresh:
                self.counts["incomplete"] += 1
        return None, False

    def _active_target(self, entering: bool) -> None:
        """The set-point of this COMMANDING_ACTIVE cycle from the commands (fine interpolation with k > 1)."""
        k = self.cfg.receive_multiplier
        if entering:  # hold the mirrored position until the first command
            self._sub, self._sub_from[:], self._vel_est[:] = k, self._sub_to, 0.0
        elif self._cmd_fresh and self._cmd_refl > self._last_refl:
            # a new command, meant for the cycle after the message it reflects; a late one (reflecting an older
            # message) is carried forward by its lateness at the commands' velocity [rad/cycle]
            gap = self._cmd_refl - self._last_refl
            np.subtract(self._cmd_q, self._last_cmd, out=self._vel_est)
            self._vel_est /= gap if gap < 64 else np.inf
            np.clip(self._vel_est, -self._vel_cap, self._vel_cap, out=self._vel_est)
            self._last_cmd[:] = self._cmd_q
            self._last_refl = self._cmd_refl
            late = (self.seq & _U32) - self._cmd_refl
            self._sub_from[:] = self._target
            np.multiply(self._vel_est, late if 0 < late < 64 else 0, out=self._sub_to)
            self._sub_to += self._cmd_q
            self._sub = 0
            self._tau_in_force[:] = self._cmd_tau
            self._wrench_in_force[:] = self._cmd_wrench
            self.counts["commanded"] += 1
        elif self._sub >= k:  # no command in time: bridge by extrapolating at the commands' velocity
            self._sub_from[:] = self._sub_to
            self._sub_to += k * self._vel_est
            self._sub = 0
        self._sub = min(self._sub + 1, k)
        w = self._sub / k
        np.multiply(self._sub_from, 1.0 - w, out=self._target)
        self._target += w * self._sub_to

    def _motion(self, state: SessionState, was: SessionState) -> None:
        ip, arm = self.interp, self.arm
        if state is CA:
            self._active_target(was is not CA)
            self._tracking = ip.step(self._target)
            self.min_tracking = min(self.min_tracking, self._tracking)
            self.counts["active"] += 1
        else:
            if was is CA:  # the overlay ended
                self._tau_in_force[:] = 0.0
                self._wrench_in_force[:] = 0.0
                if self.safety and not self._stiff:  # brake under position control from the arm's motion
                    ip.q[:], ip.v[:], ip.a[:] = arm.q, arm.v, arm.a
                    self._stiff = True
                if self._stiff:  # brake to a stop within the limits, never beyond a position limit
                    stop = ip.q + ip.v * np.abs(ip.v) / (2.0 * ip.amax)
                    np.clip(stop, -self.limits.position, self.limits.position, out=self._hold)
                else:  # impedance: back to the held position
                    self._hold[:] = self.ipo
            ip.step(self._hold)
            self._tracking = 0.0
        if self._stiff:
            over = np.abs(ip.q) > self.limits.position
            if over.any():  # a joint that could not stop before its limit stops at it
                np.clip(ip.q, -self.limits.position, self.limits.position, out=ip.q)
                ip.v[over] = 0.0
                ip.a[over] = 0.0
            arm.follow(ip.q, ip.v, ip.a)
        elif self._mode == "torque":
            arm.joint_impedance(ip.q, self._tau_in_force, self.cfg.joint_stiffness, self.cfg.damping_ratio, self.period)
        else:
            c = self.cfg
            arm.cartesian_impedance(ip.q, self._wrench_in_force, c.cartesian_stiffness, c.nullspace_stiffness,
                                    c.damping_ratio, self.period)  # fmt: skip
        if state is not CA and state is not CW and self._stiff:
            self.ipo[:] = arm.q  # PositionHold starts (again) where the robot stands
        self._cmd_fresh = False
        self._header_only = False

    def _set_robot_info(self) -> None:
        ri = self.mon.robotInfo
        if self.safety and ri.safetyState != SafetyState.SAFETY_STOP_LEVEL_1:
            ri.safetyState = SafetyState.SAFETY_STOP_LEVEL_1
        if self.safety and not np.any(self.interp.v) and ri.driveState[0] != DriveState.OFF:
            ri.driveState[:] = [DriveState.OFF] * N_JOINTS  # stop category 1: stopped, then drives off

    def close(self) -> None:
        for plant in self.plants:
            plant.close()
