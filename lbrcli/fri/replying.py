"""How a cycle's reply is made, a collaborator of :class:`~lbrcli.fri.application.ClientApplication`: the guarded
command written into the message, replies prepared one cycle ahead, the client sequence counter and the latencies.

A client that knows its next command before the next message (``LBRClient.prepare_command``: a stream of
precomputed positions) has it guarded and encoded right after the current cycle, with the next sequence counter.
When that message arrives it is decoded and checked as every message (self-consistent, the robot side has not ended
the session), and the prepared reply goes out at once; the client's ``command`` call, which must set the same
position (and, in TORQUE or WRENCH mode, the torque or wrench its ``prepare_overlay`` gave), and the rest of the cycle
follow. Any other message (lost ones before it, a state change, a stop) takes
the full cycle. Supervision judges each message after its reply: a problem it finds brakes from the next command.

FRI 2.7: in CARTESIAN_POSE mode the client's pose is turned into joints (:class:`~lbrcli.fri.cartesian.PoseSolver`,
the TCP of the application's ``tcp_robot``: a ``trajectories.robot.Robot``, default the Touch Electric flange without
a tool) which pass the same core and guard as joint commands — a pose that cannot be reached or jumps is refused like
a joint command — and the pose of the admitted joints goes out (a braking stop's too). The application's
``transformation_client`` provides the frames the robot application requests (:mod:`~lbrcli.fri.transformation`):
called for every message but IDLE after the robot client, as KUKA's ``ClientApplication::step``.
"""

from __future__ import annotations

import time
from typing import Any

from .command import LBRCommand
from .constants import ClientCommandMode
from .motion import ExecutedMotion, Refused
from .outcome import EndReason, Outcome
from .reply import ReplyMessage
from .supervision import End

from .constants import STATE_COMMANDING_ACTIVE as CMD_ACTIVE

CLIENT_CLAMP = 1e-4  # [rad] a clamp the client is told about (``LBRClient.clamped``)
STANDING_TOL = 5e-4  # [rad] the measured position this close to the ipo one before commanding: noise and the servo's
# standing error, not a push (judged from the ipo position)
_POSITION = int(ClientCommandMode.POSITION)
_TORQUE = int(ClientCommandMode.TORQUE)
_WRENCH = int(ClientCommandMode.WRENCH)
_CARTESIAN = int(ClientCommandMode.CARTESIAN_POSE)

_PREPARED_MODES = (_POSITION, _TORQUE, _WRENCH)
Prepared = tuple[int, bytes, tuple[float, ...]]  # (sequence counter it answers, datagram, joint position [rad])


class Replier:
    """The reply side of a session: one command message (``message``, opened with the session's codec) written
    each cycle from the guarded command, the reply prepared for the next message, the client sequence counter and
    the replies' counts and latencies [ns]. ``transformation_client`` and ``tcp_robot``: the application's."""

    def __init__(self, limits: Any, transformation_client: Any = None, tcp_robot: Any = None) -> None:
        self.limits = limits
        self.transformation_client, self.tcp_robot = transformation_client, tcp_robot
        self.message: ReplyMessage | None = None
        self.prepared: Prepared | None = None  # the reply to the next message, if the client prepared it
        self._overlay: tuple[int, tuple[float, ...] | None, Any] = (_POSITION, None, None)  # (mode, torque [Nm] or
        # wrench [N, Nm] of the prepared reply, the motion): what its confirmation compares and records
        self.poses: Any = None  # the PoseSolver, built at the first Cartesian command
        self.client_seq = 0  # the sequence counter of the next reply
        self.client_sequence = -1  # ... of the last reply sent (−1 before the first)
        self.answered = self.position_commands = 0
        self.prepared_replies = 0  # cycles answered with the reply prepared after the previous one
        self.unanswered_at_start = 0  # messages that went by before the first reply
        self.latencies: list[int] = []  # [ns] receive → reply

    def open(self, codec: Any) -> None:
        """The session's codec is known: its command message."""
        self.message = ReplyMessage(codec)

    # -- sending ---------------------------------------------------------------------------------------------
    def send(self, transport: Any, datagram: bytes, t_rx: int) -> str | None:
        """Send ``datagram`` (received at ``t_rx``, perf_counter_ns); why it could not be, or None."""
        try:
            transport.send(datagram)
        except OSError as exc:
            return f"cannot send to the controller: {exc.strerror}"
        self.latencies.append(time.perf_counter_ns() - t_rx)
        return None

    def sent(self, cycle: Any, missed: int) -> None:
        """The reply of ``cycle`` went out (``missed``: the controller's messages lost so far)."""
        if not self.answered:
            self.unanswered_at_start = missed
        self.client_sequence = self.client_seq
        self.client_seq = (self.client_seq + 1) & 0xFFFFFFFF
        self.answered += 1
        cycle.answered = True
        if cycle.sent_position:
            self.position_commands += 1

    # -- the reply prepared a cycle ahead ----------------------------------------------------------------------
    def prepare(self, seq: int, mon: Any, motion: ExecutedMotion, client: Any) -> None:
        """Prepare the reply to the next message (``seq`` + 1) from the client's ``prepare_command`` (and in TORQUE or
        WRENCH mode its ``prepare_overlay``), guarded now: only in POSITION, TORQUE or WRENCH mode, receive multiplier
        1, without a transformation client and while nothing brakes (the application calls it in COMMANDING_ACTIVE
        while nothing stops)."""
        mode = mon.ipoData.clientCommandMode
        if (motion.braking or not motion.steady  # (coasting or on the way back onto the path after a bridge: the full cycle)
                or self.transformation_client is not None  # (its provide() runs in the full cycle)
                or mode not in _PREPARED_MODES or (mon.connectionInfo.receiveMultiplier or 1) != 1):  # fmt: skip
            return
        try:
            q = client.prepare_command()
            overlay = None if q is None or mode == _POSITION else client.prepare_overlay()
        except Exception:  # noqa: BLE001 - no preparation; command() runs when the message is there and reports
            return
        if q is None or (mode != _POSITION and overlay is None):
            return
        q = tuple(q)
        adm = motion.envelope.admit(
            q, motion.prev, motion.prev2, motion.prev3, client.jerk_limited or motion._jerk_left > 0
        )
        guard = motion.guard
        if adm.reason is not None or adm.clamped > 0.0 or guard.refuse_position(q, motion.prev, motion.prev2,
                                                                                False) is not None:  # fmt: skip
            return  # the full cycle decides (clamps it, or refuses it with its reason and brakes)
        if overlay is not None:
            overlay = tuple(overlay)
            if (guard.refuse_torque if mode == _TORQUE else guard.refuse_wrench)(overlay) is not None:
                return  # (the full cycle refuses it with its reason and brakes)
        reply = self.message
        reply.set_motion(mode, q, overlay if mode == _TORQUE else None, overlay if mode == _WRENCH else None)  # type: ignore[union-attr]
        reply.set_io(())  # type: ignore[union-attr]
        nxt = (seq + 1) & 0xFFFFFFFF
        self.prepared = (nxt, reply.datagram(self.client_seq, nxt), q)  # type: ignore[union-attr]
        self._overlay = (mode, overlay, motion)

    def confirm(self, q: tuple[float, ...], client: Any, cmd: LBRCommand, ending: Any, cyc: Any) -> None:
        """A cycle answered with the prepared reply carrying ``q`` [rad] (and the prepared torque or wrench): the client's
        ``command`` call (through ``ending``: a SessionEnding), which must set that same position (torque, wrench) —
        else the session stops braking."""
        client.reply_due = True
        client.skipped = 0
        client.braking = False
        cmd.reset()
        got = ending.call("command", client.robot_state)
        if got is None:
            got = cmd.joint_position
        mode, overlay, motion = self._overlay
        tau = None if cmd.torque is None else tuple(cmd.torque)
        wrench = None if cmd.wrench is None else tuple(cmd.wrench)
        if ending.stop is None and (got is None or tuple(got) != q or cmd.io_writes
                                    or tau != (overlay if mode == _TORQUE else None)
                                    or wrench != (overlay if mode == _WRENCH else None)):  # fmt: skip
            what = "a joint position" + (", a torque" if mode == _TORQUE else ", a wrench" if mode == _WRENCH else "")
            ending.stop_braking(Outcome.FAILED, EndReason.CLIENT_ERROR, "the client's prepare_command() did not "
                                f"predict its command(): prepared {what}, command() set "
                                + ("another joint position" if got is None or tuple(got) != q
                                   else "IO writes" if cmd.io_writes else "another torque or wrench")
                                + " (the prepared one was sent)")  # fmt: skip
        if mode == _TORQUE:  # (where a braking stop's torque ramp starts)
            motion.last_torque = overlay
        elif mode == _WRENCH:
            motion.last_wrench = overlay
        cyc.torque = overlay if mode == _TORQUE else None
        cyc.wrench = overlay if mode == _WRENCH else None
        cyc.command = q
        cyc.sent_position = True
        cyc.phase = client.phase
        cyc.row = client.row
        self.prepared_replies += 1

    # -- the reply written in the cycle --------------------------------------------------------------------------
    def set_extras(self, cmd: LBRCommand) -> None:
        """The client's IO writes and the transformation client's values into this cycle's reply."""
        self.message.set_io(cmd.io_writes)  # type: ignore[union-attr]
        if self.transformation_client is not None:
            self.message.set_transformations(self.transformation_client.values)  # type: ignore[union-attr]

    def _pose_solver(self, motion: ExecutedMotion) -> Any:
        """The session's PoseSolver (built at the first Cartesian command: pinocchio only for clients that use it)."""
        if self.poses is None:
            from trajectories.robot import Robot

            from .cartesian import PoseSolver

            self.poses = PoseSolver(self.tcp_robot or Robot(), self.limits, motion.period_s)
        return self.poses

    def _pose_joints(self, mon: Any, state: int, cmd: LBRCommand, motion: ExecutedMotion) -> str | None:
        """CARTESIAN_POSE: the joints of the client's pose as its joint command (``cmd.joint_position``), or why
        there are none. IK warm-started from the joints last sent (COMMANDING_WAIT: the measured ones), A3 at the
        client's E1 or else the ipo E1."""
        if cmd.cartesian_pose is None:
            return "no Cartesian pose was set (CARTESIAN_POSE mode needs one in every commanding cycle)"
        seed = motion.prev if state == CMD_ACTIVE else mon.monitorData.measuredJointPosition.value
        e1 = cmd.redundancy
        if e1 is None:
            red = mon.ipoData.redundancyInformation if mon.ipoData.HasField("redundancyInformation") else None
            e1 = red.value if red is not None else seed[2]
        m = cmd.cartesian_pose
        sol = self._pose_solver(motion).solve(seed, m[:3, 3], m[:3, :3], e1)
        if sol.problem is not None:
            return sol.problem
        cmd.joint_position = tuple(sol.q.tolist())
        return None

    def build_motion(self, mon: Any, state: int, cmd: LBRCommand, motion: ExecutedMotion, client: Any,
                     cyc: Any) -> tuple[End, bool] | None:  # fmt: skip
        """Guard the client's joint position (or take the braking stop's) and write it into the message and ``cyc``.
        None, or a stop with whether the reply was written: (stop, True) — the motion brakes from here — or
        (end, False): refused, nothing to send, the session ends."""
        mode = mon.ipoData.clientCommandMode
        clamps = motion.clamped_cycles
        found: End | None = None
        if mode == _CARTESIAN and not motion.braking:
            problem = self._pose_joints(mon, state, cmd, motion)
            if problem is not None:
                found = (Outcome.REFUSED, EndReason.GUARD, f"guard refused the Cartesian command: {problem}")
                if state != CMD_ACTIVE or not motion.moving:
                    return found, False
                motion.begin_braking()  # from the joints last sent, within the joint limits, as any stop
        try:
            # (where the robot stands matters only before COMMANDING_ACTIVE: the command must start there)
            measured = _standing(mon) if state != CMD_ACTIVE else ()
            q, tau, wrench, refused = motion.next_command(measured, state, mode,
                                                          cmd.joint_position, cmd.torque, cmd.wrench,
                                                          client.exact_command, client.jerk_limited)  # fmt: skip
        except Refused as exc:
            return (Outcome.REFUSED, EndReason.GUARD, str(exc)), False
        # (a clamp of a few µrad — after a reply the controller may have bridged — is no reason to re-plan)
        client.clamped = motion.clamped_cycles != clamps and motion.last_clamp > CLIENT_CLAMP
        if refused is not None and found is None:
            if motion.loss_refused:  # not the client's command: the link lost it
                found = (Outcome.STOPPED, EndReason.SUPERVISION, f"supervision: {refused}")
            else:
                found = (Outcome.REFUSED, EndReason.GUARD, refused)
        cyc.braking = motion.braking
        pose = None
        if mode == _CARTESIAN:  # what goes out is the pose of the joints the guard admitted (a stop's too)
            from .cartesian import pose_to_wire

            pose = pose_to_wire(*self._pose_solver(motion).tcp(q))
        self.message.set_motion(mode, q, tau, wrench, pose)  # type: ignore[union-attr]
        cyc.torque = tau if mode == _TORQUE else None
        cyc.wrench = wrench if mode == _WRENCH else None
        q = tuple(q)
        motion.sent(q, state)
        cyc.command = q
        cyc.sent_position = True
        return None if found is None else (found, True)


def _standing(mon: Any) -> Any:
    """Where the robot stands before commanding [rad]: the controller's ipo position (what it holds, and what a
    COMMANDING_WAIT reply mirrors) if the measured one is within ``STANDING_TOL`` of it, else the measured one (a
    robot pushed away from where it is held: the mirror then breaks the limits and the session is refused). (Judged
    from the measured position alone, sensor noise or the servo's standing error of 10 µrad in one 1 ms period — 10
    rad/s², over the acceleration limit — refused sessions before they began.)"""
    ipo, measured = mon.ipoData.jointPosition.value, mon.monitorData.measuredJointPosition.value
    if len(ipo) == 7 and len(measured) == 7 and max(abs(a - b) for a, b in zip(ipo, measured)) <= STANDING_TOL:
        return ipo
    return measured
